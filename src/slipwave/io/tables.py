"""The CSV tables slipwave writes (events, waves, comparisons...), read back with checks."""

from __future__ import annotations

from collections.abc import Sequence
from os import PathLike

import pandas as pd

from slipwave.errors import SlipwaveError


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
        Its rows (an empty table keeps its columns).

    Raises
    ------
    SlipwaveError
        ``<path>: <what is wrong>``: missing, not text, not CSV, or a column missing.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "waves.csv"
    >>> _ = path.write_text("start_s,speed_m_s\n1.5,20\n")
    >>> read_table(path, ["start_s"]).shape
    (1, 2)
    >>> read_table(path, ["end_s"])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipwave.errors.SlipwaveError: .../waves.csv: no column 'end_s' (its columns: start_s, ...)
    """
    try:
        table = pd.read_csv(path)
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
