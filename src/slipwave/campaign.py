"""The campaign table and config of the workflow, read for Snakemake and the CLI."""

from __future__ import annotations

import shlex
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
    """The column mapping called ``name`` in the config (empty for no name)."""
    if not name:
        return {}
    maps = config.get("column_maps") or {}
    if name not in maps:
        known = ", ".join(map(repr, maps)) or "none"
        raise ConfigError(f"column map {name!r} is not in the config's column_maps ({known})")
    return {str(k): str(v) for k, v in maps[name].items()}


def column_arguments(config: Mapping[str, Any], name: str) -> str:
    """``--column NAME=CHANNEL`` options of ``slipwave ingest`` for a named map."""
    return " ".join(
        shlex.quote(f"--column={header}={channel}")
        for header, channel in column_map(config, name).items()
    )


DETECTION_OPTIONS = {
    "threshold": "--threshold",
    "max_spike": "--max-spike",
    "max_duration": "--max-duration",
    "min_asymmetry": "--min-asymmetry",
    "gross_edge_ratio": "--gross-edge-ratio",
}
"""Keys of the config's ``detection`` section and the ``slipwave detect`` options they set."""


def detection_arguments(config: Mapping[str, Any], gross_edge_ratio: str = "") -> str:
    """``slipwave detect`` options from the config's ``detection`` section.

    A test's own ``gross_edge_ratio`` cell (campaign table), when not empty,
    overrides the config's.

    Examples
    --------
    >>> detection_arguments({"detection": {"threshold": 10, "gross_edge_ratio": 0.9}}, "1.3")
    '--threshold=10 --gross-edge-ratio=1.3'
    """
    settings = dict(config.get("detection") or {})
    if gross_edge_ratio:
        try:
            settings["gross_edge_ratio"] = float(gross_edge_ratio)
        except ValueError as err:
            raise ConfigError(f"gross_edge_ratio {gross_edge_ratio!r} is not a number") from err
    unknown = set(settings) - set(DETECTION_OPTIONS)
    if unknown:
        raise ConfigError(f"unknown detection settings: {', '.join(sorted(unknown))}")
    return " ".join(shlex.quote(f"{DETECTION_OPTIONS[key]}={value}")
                    for key, value in settings.items() if value is not None)
