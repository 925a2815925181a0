"""The campaign table and config of the workflow, read for Snakemake and the CLI."""

from __future__ import annotations

import shlex
from collections.abc import Mapping
from os import PathLike
from pathlib import Path
from typing import Any

import pandas as pd

from slipwave.errors import ConfigError

TABLE_COLUMNS = ("test_id", "csv", "frames", "columns")


def read_campaign(path: str | PathLike[str]) -> pd.DataFrame:
    """Read a campaign table (tab separated, one row per test), indexed by ``test_id``.

    Empty optional cells (``frames``, ``columns``) become empty strings.

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
    for optional in ("frames", "columns"):
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
