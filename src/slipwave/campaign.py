"""The campaign table and config of the workflow, read for Snakemake and the CLI."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from os import PathLike
from pathlib import Path
from typing import Any

import pandas as pd

from slipwave.errors import ConfigError
from slipwave.validation import check, read_yaml

OPTIONAL_COLUMNS = ("frames", "columns", "gross_edge_ratio", "fps")
"""Columns a campaign table may leave out (their cells are then empty)."""


def _table_lines(path: Path) -> list[int]:
    """File line of the header and of each row, as pandas reads the table (comments skipped)."""
    lines = []
    with path.open(encoding="utf-8", errors="replace") as handle:
        for number, text in enumerate(handle, start=1):
            if text.strip() and not text.lstrip().startswith("#"):
                lines.append(number)
    return lines


def read_campaign(path: str | PathLike[str]) -> pd.DataFrame:
    """Read a campaign table (tab separated, one row per test), indexed by ``test_id``.

    Empty optional cells (:data:`OPTIONAL_COLUMNS`) become empty strings.

    Parameters
    ----------
    path
        The table.

    Returns
    -------
    pandas.DataFrame
        One row per test, all cells text, indexed by ``test_id``; ``attrs``
        holds ``source`` (the path) and ``lines`` (test id -> its line in the file).

    Raises
    ------
    ConfigError
        If the file is missing, has no test, lacks a required column or repeats
        a test id (naming the line).

    """
    path = Path(path)
    try:
        table = pd.read_csv(path, sep="\t", dtype=str, comment="#", keep_default_na=False)
    except FileNotFoundError as err:
        raise ConfigError(f"{path}: campaign table not found") from err
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as err:
        raise ConfigError(f"{path}: not a tab-separated campaign table: {err}") from err
    lines = _table_lines(path)
    table.columns = [c.strip() for c in table.columns]
    for required in ("test_id", "csv"):
        if required not in table.columns:
            raise ConfigError(
                f"{path}, line {lines[0]}: no {required!r} column; the header names "
                f"{', '.join(map(repr, table.columns))}"
            )
    if len(table) == 0:
        raise ConfigError(f"{path}: no test: the table has a header but no row")
    for optional in OPTIONAL_COLUMNS:
        if optional not in table.columns:
            table[optional] = ""
    table = table.apply(lambda column: column.str.strip())
    rows = lines[1 : 1 + len(table)]
    repeated = table["test_id"].duplicated()
    if repeated.any():
        row = int(repeated.to_numpy().argmax())
        raise ConfigError(
            f"{path}, line {rows[row]}: test_id {table['test_id'].iloc[row]!r} appears twice"
        )
    table = table.set_index("test_id", drop=False)
    table.attrs = {"source": str(path), "lines": dict(zip(table["test_id"], rows, strict=True))}
    return table


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


def check_campaign(config: Mapping[str, Any], campaign: pd.DataFrame,
                   schema: Mapping[str, Any] | None = None) -> None:
    """Check each test of the campaign: its cells, its column map and its settings.

    Parameters
    ----------
    config
        The validated workflow config.
    campaign
        From :func:`read_campaign`.
    schema
        The table's schema (``workflow/schemas/tests.schema.json``): each row
        is checked against it, and an error names the table's file and line.

    Raises
    ------
    ConfigError
        Naming the file, the line, the test and what is wrong, before any job starts.

    """
    source = campaign.attrs.get("source", "the campaign table")
    lines = campaign.attrs.get("lines", {})
    for test_id, test in campaign.iterrows():
        where = f"{source}, line {lines[test_id]}" if test_id in lines else source
        where += f" (test {test_id!r})"
        if schema is not None:
            check(dict(test), dict(schema), source=where)
        try:
            column_map(config, test["columns"])
            gross_edge_ratio(config, test)
        except ConfigError as err:
            raise ConfigError(f"{where}: {err}") from err


def check_config_files(paths: Iterable[str | PathLike[str]],
                       schema: Mapping[str, Any] | None = None, *,
                       command_line: Iterable[str | PathLike[str]] = ()) -> None:
    """Check the workflow's config files one by one, before Snakemake merges them.

    Each file's own settings are checked against the config schema, so that an
    error names the file and the line (Snakemake's check of the merged config
    cannot). And Snakemake merges ``--configfile`` files over the workflow's own
    config: if none of those sets ``tests``, the default campaign would silently run.

    Parameters
    ----------
    paths
        Every config file (the workflow's own and the command line's).
    schema
        ``workflow/schemas/config.schema.json``; ``None``: only the rule on ``tests``.
    command_line
        The ``--configfile`` files (Snakemake's ``workflow.overwrite_configfiles``).

    Raises
    ------
    ConfigError
        Naming the file, the line, the setting and what is wrong.

    """
    if schema is not None:
        settings = {key: value for key, value in schema.items() if key != "required"}
        for path in paths:
            content, line_of = read_yaml(path)
            check(content or {}, settings, source=str(path), line_of=line_of)
    given = [Path(p) for p in command_line]
    if not given:
        return
    for path in given:
        content, _ = read_yaml(path)
        if isinstance(content, Mapping) and content.get("tests"):
            return
    names = ", ".join(map(str, given))
    raise ConfigError(f"{names}: no 'tests' entry naming the campaign table; without it the "
                      "default campaign (config/config.yaml) would run instead")
