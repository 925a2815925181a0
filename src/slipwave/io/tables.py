"""The CSV tables slipwave writes (events, waves, comparisons...), and read back with checks.

A table of one test's starts with its identity as the acquisition card's CSVs start
with their metadata, one ``# key: value`` line each (``test_id``,
``recording_sha256``: :mod:`slipwave.identity`); pandas reads the rows alone with
``pd.read_csv(path, comment="#")``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from os import PathLike
from typing import Any

import pandas as pd

from slipwave.errors import SlipwaveError
from slipwave.identity import identity_of
from slipwave.io.atomic import atomic_output

WAVE_COLUMNS = ("t_start", "t_end", "frames", "x_start", "x_end", "x_min", "x_max",
                "direction", "speed", "extent", "kind")
"""The columns of a waves table: the video's (:func:`slipwave.video.track_waves`) and a
quasi-dynamic simulation's (:func:`slipwave.solver.fronts.front_waves`)."""


def write_table(table: pd.DataFrame, path: str | PathLike[str],
                identity: Mapping[Any, Any] | None = None) -> None:
    """Write a table as CSV, whole or not at all, under its test's identity lines.

    Parameters
    ----------
    table
        The rows.
    path
        The CSV file.
    identity
        The attributes (or content) of the product it is made from, whose test it
        names; ``None``: a campaign's table (its rows name their tests).

    """
    with atomic_output(path) as temporary, open(temporary, "w", encoding="utf-8") as stream:
        if identity is not None:
            for key, value in identity_of(identity).items():
                stream.write(f"# {key}: {value}\n")
        table.to_csv(stream, index=False, float_format="%.6g", lineterminator="\n")


def read_table(path: str | PathLike[str], columns: Sequence[str] = ()) -> pd.DataFrame:
    r"""A CSV table of slipwave's, with an error naming the file when it is not one.

    Parameters
    ----------
    path
        The file.
    columns
        Columns it must have.

    Returns
    -------
    pandas.DataFrame
        Its rows (an empty table keeps its columns); ``attrs`` holds the identity
        lines (:func:`write_table`).

    Raises
    ------
    SlipwaveError
        ``<path>: <what is wrong>``: missing, not text, not CSV, or a column missing.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "waves.csv"
    >>> write_table(pd.DataFrame({"start_s": [1.5], "speed_m_s": [20]}), path,
    ...             {"test_id": "hl050", "recording_sha256": "9f2c"})
    >>> print(path.read_text())
    # test_id: hl050
    # recording_sha256: 9f2c
    start_s,speed_m_s
    1.5,20
    <BLANKLINE>
    >>> table = read_table(path, ["start_s"])
    >>> table.shape, table.attrs["test_id"]
    ((1, 2), 'hl050')
    >>> read_table(path, ["end_s"])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipwave.errors.SlipwaveError: .../waves.csv: no column 'end_s' (its columns: start_s, ...)
    """
    try:
        with open(path, encoding="utf-8") as stream:
            metadata = {}
            for line in stream:
                if not line.startswith("# "):
                    break
                key, _, value = line[2:].partition(":")
                metadata[key.strip()] = value.strip()
        table = pd.read_csv(path, skiprows=len(metadata))
        table.attrs.update(metadata)
    except FileNotFoundError as err:
        raise SlipwaveError(f"{path}: no such file") from err
    except IsADirectoryError as err:
        raise SlipwaveError(f"{path}: is a directory, not a CSV table") from err
    except pd.errors.EmptyDataError as err:
        raise SlipwaveError(f"{path}: the file is empty, not a CSV table") from err
    except UnicodeDecodeError as err:
        raise SlipwaveError(f"{path}: not UTF-8 text, not a CSV table") from err
    except (pd.errors.ParserError, ValueError) as err:
        raise SlipwaveError(f"{path}: not a CSV table ({str(err).strip()})") from err
    except OSError as err:
        raise SlipwaveError(f"{path}: cannot be read: {err.strerror}") from err
    for column in columns:
        if column not in table.columns:
            raise SlipwaveError(f"{path}: no column {column!r} (its columns: "
                                f"{', '.join(map(str, table.columns))})")
    return table
