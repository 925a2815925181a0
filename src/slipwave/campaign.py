"""The campaign table and config of the workflow, read for Snakemake and the CLI."""

from __future__ import annotations

from collections.abc import Mapping
from os import PathLike
from pathlib import Path
from typing import Any

import pandas as pd

from slipwave.errors import ConfigError

TABLE_COLUMNS = ("test_id", "csv", "frames", "columns", "gross_edge_ratio")


def read_campaign(path: str | PathLike[str]) -> pd.DataFrame:
    """Read a campaign table (tab separated, one row per test), indexed by ``test_id``.

    Empty optional cells (``frames``, ``columns``, ``gross_edge_ratio``)
    become empty strings.

    Parameters
    ----------
    path
        The table.

    Returns
    -------
    pandas.DataFrame
        One row per test, all cells text, indexed by ``test_id``.

    Raises
    ------
    ConfigError
        If the file is missing, lacks a required column or repeats a test id
        (naming the line).

    """
    path = Path(path)
    try:
        table = pd.read_csv(path, sep="\t", dtype=str, comment="#", keep_default_na=False)
    except FileNotFoundError as err:
        raise ConfigError(f"{path}: campaign table not found") from err
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as err:
        raise ConfigError(f"{path}: not a tab-separated campaign table: {err}") from err
    table.columns = [c.strip() for c in table.columns]
    for required in ("test_id", "csv"):
        if required not in table.columns:
            raise ConfigError(
                f"{path}, line 1: no {required!r} column; the header names "
                f"{', '.join(map(repr, table.columns))}"
            )
    for optional in ("frames", "columns", "gross_edge_ratio"):
        if optional not in table.columns:
            table[optional] = ""
    table = table.apply(lambda column: column.str.strip())
    repeated = table["test_id"].duplicated()
    if repeated.any():
        row = int(repeated.to_numpy().argmax())
        raise ConfigError(
            f"{path}, line {row + 2}: test_id {table['test_id'].iloc[row]!r} appears twice"
        )
    return table.set_index("test_id", drop=False)


def column_map(config: Mapping[str, Any], name: str) -> dict[str, str]:
    """The column mapping called ``name`` in the config.

    Parameters
    ----------
    config
        The workflow's config (its ``column_maps``).
    name
        The map's name; empty for none.

    Returns
    -------
    dict
        Header name (without its unit) -> channel; empty for no name.

    Raises
    ------
    ConfigError
        If the config has no map of that name.

    """
    if not name:
        return {}
    maps = config.get("column_maps") or {}
    if name not in maps:
        known = ", ".join(map(repr, maps)) or "none"
        raise ConfigError(f"column map {name!r} is not in the config's column_maps ({known})")
    return {str(k): str(v) for k, v in maps[name].items()}


def column_pairs(config: Mapping[str, Any], name: str) -> list[str]:
    """The column map called ``name`` as ``NAME=CHANNEL`` values of ``slipwave ingest --columns``.

    Parameters
    ----------
    config
        The workflow's config.
    name
        A test's ``columns`` cell (empty: no map).

    Returns
    -------
    list of str
        One ``header=channel`` per mapped column.

    Examples
    --------
    >>> column_pairs({"column_maps": {"lab": {"Zeit": "time", "Kraft x": "T"}}}, "lab")
    ['Zeit=time', 'Kraft x=T']
    """
    return [f"{header}={channel}" for header, channel in column_map(config, name).items()]


def gross_edge_ratio(config: Mapping[str, Any], test: Mapping[str, str] | pd.Series) -> float:
    """A test's DG/DD ratio from which a T drop is a gross slip.

    Parameters
    ----------
    config
        The validated workflow config (``detection.gross_edge_ratio`` filled in).
    test
        The test's row of the campaign table; its ``gross_edge_ratio`` cell,
        when not empty, wins over the config's.

    Returns
    -------
    float
        The ratio.

    Examples
    --------
    >>> config = {"detection": {"gross_edge_ratio": 0.9}}
    >>> gross_edge_ratio(config, {"gross_edge_ratio": "1.3"}), gross_edge_ratio(config, {})
    (1.3, 0.9)
    """
    cell = str(test.get("gross_edge_ratio") or "")
    if not cell:
        return float(config["detection"]["gross_edge_ratio"])
    try:
        ratio = float(cell)
    except ValueError as err:
        raise ConfigError(f"test {test.get('test_id', '?')!r}: gross_edge_ratio {cell!r} is "
                          "not a number") from err
    if not ratio > 0:
        raise ConfigError(f"test {test.get('test_id', '?')!r}: gross_edge_ratio {cell!r} must "
                          "be positive")
    return ratio


def check_campaign(config: Mapping[str, Any], campaign: pd.DataFrame) -> None:
    """Check what the schemas cannot: the tests' column maps and per-test settings.

    Parameters
    ----------
    config
        The validated workflow config.
    campaign
        From :func:`read_campaign`.

    Raises
    ------
    ConfigError
        Naming the test and what is wrong, before any job starts.

    """
    for _, test in campaign.iterrows():
        try:
            column_map(config, test["columns"])
        except ConfigError as err:
            raise ConfigError(f"test {test['test_id']!r}: {err}") from err
        gross_edge_ratio(config, test)
