r"""The campaign table of spring-slider records: one row per record, checked line by line.

>>> import tempfile, pathlib
>>> table = pathlib.Path(tempfile.mkdtemp()) / "sliders.tsv"
>>> _ = table.write_text("record_id\tmat\trole\tstiffness_n_m\tdrive_speed_um_s\tmass_g\t"
...                      "window_s\nk168v42\tk168Nm_v42.mat\tfit\t168\t42\t30.7\t10\n")
>>> records = read_slider_campaign(table)
>>> float(records.loc["k168v42", "normal_load_n"])  # the slider's weight, N
0.301167
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from os import PathLike
from pathlib import Path
from typing import Any

import pandas as pd

from slipwave.defaults import SLIDER_TUNABLES
from slipwave.errors import ConfigError
from slipwave.validation import check, load_schema

GRAVITY = 9.81
"""The acceleration of gravity, m/s^2 (a slider's weight is its normal load by default)."""

NUMBER_COLUMNS = ("stiffness_n_m", "drive_speed_um_s", "mass_g", "normal_load_n", "window_s")
"""The table's numeric columns."""


def read_slider_campaign(path: str | PathLike[str]) -> pd.DataFrame:
    """Read and check a spring-slider campaign table (tab separated, ``#`` comments).

    Parameters
    ----------
    path
        The table (UTF-8).

    Returns
    -------
    pandas.DataFrame
        Indexed by ``record_id``: ``mat`` (text), ``role``, and the numbers
        (:data:`NUMBER_COLUMNS`; ``normal_load_n`` the slider's weight where empty).

    Raises
    ------
    ConfigError
        Naming the file and the line of a missing table, a row the schema refuses
        (``sliders.schema.json``), a repeated record or a campaign without a record to fit.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError as error:
        raise ConfigError(f"{path}: spring-slider campaign table not found") from error
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"{path}: not a readable table ({error})") from error
    try:
        table = pd.read_csv(io.StringIO(text), sep="\t", comment="#", dtype=str,
                            keep_default_na=False, skip_blank_lines=True)
    except pd.errors.ParserError as error:
        raise ConfigError(f"{path}: not a readable table ({error})") from error
    text_lines = [number for number, line in enumerate(text.splitlines(), start=1)
                  if line.strip() and not line.lstrip().startswith("#")]
    schema = load_schema("sliders")
    if "normal_load_n" not in table.columns:
        table["normal_load_n"] = ""
    for row, (_, record) in enumerate(table.iterrows()):
        where = f"{path}, line {text_lines[row + 1]}"
        check({key: value.strip() for key, value in record.items()}, schema, source=where)
    table = table.apply(lambda column: column.str.strip())
    repeated = table["record_id"][table["record_id"].duplicated()]
    if len(repeated):
        raise ConfigError(f"{path}: record {repeated.iloc[0]!r} appears twice")
    if not (table["role"] == "fit").any():
        raise ConfigError(f"{path}: no record has the role 'fit': there is nothing to fit")
    for column in NUMBER_COLUMNS:
        table[column] = pd.to_numeric(table[column], errors="coerce")  # empty: NaN
    weight = table["mass_g"] * 1e-3 * GRAVITY
    table["normal_load_n"] = table["normal_load_n"].fillna(weight)
    table.attrs["source"] = str(path)
    return table.set_index("record_id")


def slider_ingest_options(record: pd.Series) -> str:
    """``slipwave slider-ingest``'s options for a record of the table.

    Parameters
    ----------
    record
        A row of :func:`read_slider_campaign`'s table.

    Returns
    -------
    str
        ``--role``, ``--stiffness``, ``--drive-speed``, ``--mass``, ``--normal-load``,
        ``--window``.
    """
    numbers = {"stiffness": "stiffness_n_m", "drive-speed": "drive_speed_um_s",
               "mass": "mass_g", "normal-load": "normal_load_n", "window": "window_s"}
    return f"--role {record['role']} " + " ".join(
        f"--{option} {float(record[column])!r}" for option, column in numbers.items())


def slider_fit_options(settings: Mapping[str, Any]) -> str:
    """``slipwave slider-fit``'s options from the config's ``sliders`` section.

    Parameters
    ----------
    settings
        The validated section.

    Returns
    -------
    str
        One option per setting the command takes.
    """
    return " ".join([f"--{key} {settings[key]!r}" for key in SLIDER_TUNABLES if key != "draws"]
                    + [f"--evolution {settings['evolution']}",
                       "--cutoff" if settings["cutoff"] else "--no-cutoff"])
