"""The ingest stage: acquisition-card CSVs read into a Dataset in N, mm and s.

The canonical acquisition CSV (documented in ``raw_data/README.md``)::

    # test_id: hl050
    # sample_rate_hz: 100
    # length_mm: 80
    time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]
    0.00,0.012,-0.031,0.0004,-0.0002,0.0000
    ...

:func:`read_acquisition` reads it and the variants acquisition cards write
(``;`` or tab separators, decimal comma, CRLF, Latin-1, units in brackets,
parentheses or a second header row, vendor column names) into an
:class:`xarray.Dataset` in mm, N and s.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import io
import re
import unicodedata
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pint
import xarray as xr

from slipwave.defaults import CONVENTIONS
from slipwave.errors import AcquisitionError
from slipwave.io.channels import CHANNEL_ATTRS, CHANNELS, REQUIRED_CHANNELS, RESERVED_ATTRS

# Column names understood without a ``columns`` mapping. Short names are
# case-sensitive (``t`` is time, ``T`` the tangential load); longer ones are
# compared after folding case and accents.
_EXACT_ALIASES: dict[str, str] = {
    "t": "time", "T": "T", "N": "N", "Ft": "T", "FT": "T", "Fn": "N", "FN": "N",
    "DG": "DG", "DD": "DD", "DT": "DT", "i": "index",
}
_FOLDED_ALIASES: dict[str, str] = {
    **{name: "time" for name in ("time", "temps", "zeit", "tiempo", "time s")},
    **{name: "index" for name in ("index", "sample", "sample index", "samples",
                                  "echantillon", "n echantillon", "no")},
    **{name: "T" for name in ("tangential load", "tangential force", "effort tangentiel",
                              "force tangentielle", "charge tangentielle")},
    **{name: "N" for name in ("normal load", "normal force", "effort normal",
                              "force normale", "charge normale")},
    **{name: "DG" for name in ("dg", "left displacement", "left edge displacement",
                               "deplacement gauche", "depl gauche", "dep gauche")},
    **{name: "DD" for name in ("dd", "right displacement", "right edge displacement",
                               "deplacement droit", "depl droit", "dep droit")},
    **{name: "DT" for name in ("dt", "flat displacement", "flat travel", "table displacement",
                               "deplacement plan", "deplacement du plan", "depl plan",
                               "deplacement table", "dep plan")},
}
_CANONICAL_UNITS = {"time": "s", "index": "", "T": "N", "N": "N", "DG": "mm", "DD": "mm",
                    "DT": "mm"}
_DIMENSION_NAMES = {"s": "a time", "N": "a force", "mm": "a length"}

_UNIT_IN_NAME = re.compile(r"^(?P<name>.*?)\s*(?:\[(?P<b>[^\]]*)\]|\((?P<p>[^)]*)\))\s*$")
_DECIMAL_COMMA = re.compile(r"^[-+]?\d*,\d+(?:[eE][-+]?\d+)?$")
_PANDAS_LINE = re.compile(r"line (\d+), saw (\d+)")


@functools.cache
def _units() -> pint.UnitRegistry:
    # Built once: constructing a registry takes a fifth of a second.
    return pint.UnitRegistry()


@dataclass
class _Head:
    """What precedes the numbers: metadata, header, units and the file's dialect."""

    metadata: dict[str, Any]
    names: list[str]
    units: list[str | None]
    raw_names: list[str]
    header_line: int
    unit_line: int | None
    data_line: int
    data_offset: int
    separator: str
    decimal: str
    encoding: str
    warnings: list[str] = field(default_factory=list)


def _fold(name: str) -> str:
    decomposed = unicodedata.normalize("NFKD", name)
    plain = "".join(c for c in decomposed if not unicodedata.combining(c))
    return re.sub(r"[\s_\-.°º#:/]+", " ", plain).strip().lower()


def _decode(line: bytes, encoding: str) -> str:
    return line.decode(encoding, errors="replace")


def _split_name_unit(cell: str) -> tuple[str, str | None]:
    match = _UNIT_IN_NAME.match(cell)
    if match is None:
        return cell.strip(), None
    unit = match["b"] if match["b"] is not None else match["p"]
    return match["name"].strip(), unit.strip()


def _is_number(cell: str, decimal: str) -> bool:
    text = cell.strip()
    if decimal == ",":
        text = text.replace(",", ".")
    try:
        float(text)
    except ValueError:
        return text.lower() in {"", "nan", "na", "n/a", "null", "-nan"}
    return True


def _parse_value(text: str) -> Any:
    text = text.strip()
    for cast in (int, float):
        with contextlib.suppress(ValueError):
            return cast(text)
    with contextlib.suppress(ValueError):
        return float(text.replace(",", "."))
    return text


def _attr_key(key: str) -> str:
    cleaned = re.sub(r"\W+", "_", _fold(key)).strip("_") or "key"
    if cleaned[0].isdigit():
        cleaned = "k_" + cleaned
    return f"meta_{cleaned}" if cleaned in RESERVED_ATTRS else cleaned


def _detect_separator(header: str) -> str:
    counts = {sep: header.count(sep) for sep in (";", "\t", ",")}
    best = max(counts.values())
    # Ties go to the separator that cannot also be a decimal mark.
    return next(sep for sep in (";", "\t", ",") if counts[sep] == best)


def _lines(raw: bytes, start: int) -> Iterator[tuple[int, bytes]]:
    """Yield (offset of the next line, line without its end) from ``start``."""
    pos = start
    while pos < len(raw):
        end = raw.find(b"\n", pos)
        end = len(raw) if end < 0 else end
        yield end + 1, raw[pos:end].rstrip(b"\r")
        pos = end + 1


def _parse_head(path: Path, raw: bytes) -> _Head:
    start = 3 if raw.startswith(b"\xef\xbb\xbf") else 0
    head_bytes = raw[start : start + 65536]
    try:
        head_bytes.decode("utf-8")
        encoding = "utf-8"
    except UnicodeDecodeError as err:
        # A cut inside a multi-byte character at the 64 KiB edge is still UTF-8.
        encoding = "utf-8" if err.start > len(head_bytes) - 4 else "latin-1"

    metadata: dict[str, Any] = {}
    comments: list[str] = []
    lines = _lines(raw, start)
    line_no = 0
    header: str | None = None
    header_end = start
    for next_offset, line in lines:
        line_no += 1
        text = _decode(line, encoding).strip()
        if text.startswith("#"):
            body = text.lstrip("#").strip()
            key, colon, value = body.partition(":")
            if colon and key.strip():
                metadata[_attr_key(key)] = _parse_value(value)
            elif body:
                comments.append(body)
            continue
        if not text:
            continue
        header, header_end = text, next_offset
        break
    if header is None:
        raise AcquisitionError(path, "no header row: the file holds only metadata or comments")
    header_line = line_no
    separator = _detect_separator(header)
    raw_names = [cell.strip().strip('"').strip() for cell in header.split(separator)]

    # Look at the next line: a unit row, or the first data row.
    data_offset, data_line = header_end, header_line + 1
    unit_line = None
    next_line = next(lines, None)
    cells: list[str] = []
    if next_line is not None:
        following, line = next_line
        cells = [c.strip().strip('"') for c in _decode(line, encoding).split(separator)]
    decimal = "."
    if separator != "," and any(_DECIMAL_COMMA.match(c) for c in cells):
        decimal = ","
    names_units = [_split_name_unit(cell) for cell in raw_names]
    names = [name for name, _ in names_units]
    units = [unit for _, unit in names_units]
    nonempty = [c for c in cells if c]
    if nonempty and not any(_is_number(c, decimal) for c in nonempty):
        # Units given as a second header row: "s;N;N;mm" or "[s];[N]..."
        unit_line = header_line + 1
        for k, cell in enumerate(cells[: len(names)]):
            unit = cell.strip("[]()").strip()
            if unit:
                units[k] = unit
        data_offset, data_line = following, header_line + 2
        decimal = "."
        after = next(lines, None)
        if after is not None and separator != ",":
            first = _decode(after[1], encoding).split(separator)
            if any(_DECIMAL_COMMA.match(c.strip()) for c in first):
                decimal = ","
    head = _Head(
        metadata=metadata, names=names, units=units, raw_names=raw_names,
        header_line=header_line, unit_line=unit_line, data_line=data_line,
        data_offset=data_offset, separator=separator, decimal=decimal, encoding=encoding,
    )
    if comments:
        head.metadata.setdefault("comment", "\n".join(comments))
    return head


def _map_columns(
    path: Path, head: _Head, columns: Mapping[str, str] | None
) -> dict[str, int]:
    """Channel name -> column position, checked for duplicates."""
    wanted = dict(columns or {})
    for name, target in wanted.items():
        if target not in (*_CANONICAL_UNITS, "ignore"):
            raise AcquisitionError(
                path,
                f"columns mapping sends {name!r} to {target!r}, which is not one of "
                f"{', '.join(_CANONICAL_UNITS)} or 'ignore'",
            )
    folded_wanted = {_fold(k): v for k, v in wanted.items()}
    found: dict[str, int] = {}
    ignored: list[str] = []
    for k, name in enumerate(head.names):
        if not name:
            continue
        channel = (
            wanted.get(name)
            or folded_wanted.get(_fold(name))
            or _EXACT_ALIASES.get(name)
            or _FOLDED_ALIASES.get(_fold(name))
        )
        if channel is None or channel == "ignore":
            ignored.append(head.raw_names[k])
            continue
        if channel in found:
            raise AcquisitionError(
                path,
                f"columns {head.raw_names[found[channel]]!r} and {head.raw_names[k]!r} "
                f"both map to channel {channel}",
                line=head.header_line,
            )
        found[channel] = k
    if ignored:
        head.warnings.append(f"columns not used: {', '.join(map(repr, ignored))}")
    for channel in REQUIRED_CHANNELS:
        if channel not in found:
            label = CHANNEL_ATTRS[channel]["long_name"]
            raise AcquisitionError(
                path,
                f"no column for the required channel {channel} ({label}); the header names "
                f"{', '.join(map(repr, head.raw_names))}; pass columns={{'<name>': "
                f"'{channel}'}} (or a column map in the campaign config) to name it",
                line=head.header_line,
            )
    return found


def _unit_factor(path: Path, head: _Head, channel: str, k: int) -> float:
    target = _CANONICAL_UNITS[channel]
    unit = head.units[k]
    line = head.unit_line or head.header_line
    column = head.raw_names[k]
    if channel == "index":
        return 1.0
    if not unit:
        head.warnings.append(f"column {column!r} has no unit; read as {target}")
        return 1.0
    registry = _units()
    try:
        quantity = registry.Quantity(1.0, unit)
    except Exception as err:  # pint raises many kinds on arbitrary text
        raise AcquisitionError(path, f"unknown unit {unit!r}", line=line, column=column) from err
    try:
        return float(quantity.to(target).magnitude)
    except pint.DimensionalityError as err:
        raise AcquisitionError(
            path,
            f"unit {unit!r} is not {_DIMENSION_NAMES[target]}, as channel {channel} needs",
            line=line, column=column,
        ) from err


def _read_bytes(path: Path) -> bytes:
    try:
        with open(path, "rb") as handle:  # read-only: raw data are never written
            return handle.read()
    except FileNotFoundError as err:
        raise AcquisitionError(path, "no such file") from err
    except IsADirectoryError as err:
        raise AcquisitionError(path, "is a directory, not an acquisition file") from err
    except OSError as err:
        raise AcquisitionError(path, f"cannot be read: {err.strerror}") from err


def _line_starts(raw: bytes, offset: int) -> np.ndarray:
    """Byte offsets where each line from ``offset`` starts (only on the slow path).

    Line ends are those of pandas' C parser: LF, CRLF and a lone CR.
    """
    buffer = np.frombuffer(raw, dtype=np.uint8, offset=offset)
    lf = buffer == 10
    lone_cr = (buffer == 13) & ~np.concatenate([lf[1:], [False]])
    return np.concatenate([[0], np.flatnonzero(lf | lone_cr) + 1]) + offset


def _tokenize(path: Path, raw: bytes, head: _Head, ncols: int) -> pd.DataFrame:
    try:
        return pd.read_csv(
            io.BytesIO(raw[head.data_offset :]),
            sep=head.separator, decimal=head.decimal, header=None, names=range(ncols),
            skip_blank_lines=False, engine="c", encoding=head.encoding, index_col=False,
            encoding_errors="replace", quotechar='"', comment=None, low_memory=False,
        )
    except pd.errors.ParserError as err:
        match = _PANDAS_LINE.search(str(err))
        if match is None:
            raise AcquisitionError(path, f"cannot be parsed: {err}") from err
        line = head.data_line + int(match[1]) - 1
        raise AcquisitionError(
            path, f"{match[2]} fields where the header has {ncols}", line=line
        ) from err
    except pd.errors.EmptyDataError:
        return pd.DataFrame(columns=range(ncols))


def _check_short_rows(
    path: Path, raw: bytes, head: _Head, frame: pd.DataFrame, ncols: int
) -> pd.DataFrame:
    """Drop blank lines and a truncated last line; refuse other short lines."""
    candidates = np.flatnonzero(frame[ncols - 1].isna().to_numpy())
    if candidates.size == 0:
        return frame
    starts = _line_starts(raw, head.data_offset)
    separator = head.separator.encode()
    drop: list[int] = []
    blanks = 0
    last = len(frame) - 1
    for row in candidates:
        end = starts[row + 1] if row + 1 < len(starts) else len(raw)
        text = raw[starts[row] : end].rstrip(b"\r\n")
        if not text.strip():
            drop.append(int(row))
            blanks += 1
            continue
        fields = text.count(separator) + 1
        if fields >= ncols:
            continue
        line = head.data_line + int(row)
        if row == last:
            drop.append(int(row))
            head.warnings.append(
                f"line {line}: truncated last line ({fields} of {ncols} fields) dropped"
            )
            continue
        raise AcquisitionError(path, f"{fields} fields where the header has {ncols}", line=line)
    if blanks:
        head.warnings.append(f"{blanks} blank line(s) in the data skipped")
    return frame.drop(index=frame.index[drop])


def _drop_cut_last_row(
    raw: bytes, head: _Head, frame: pd.DataFrame, used: list[int]
) -> pd.DataFrame:
    """Drop a last row cut in the middle of a number (acquisition stopped mid-write)."""
    if raw.endswith(b"\n") or len(frame) == 0:
        return frame
    last = frame.iloc[-1]
    if all(_is_number(str(last[k]), ".") for k in used if isinstance(last[k], str)):
        return frame
    line = head.data_line + int(frame.index[-1])
    head.warnings.append(f"line {line}: truncated last line dropped")
    return frame.iloc[:-1]


def _numeric(path: Path, head: _Head, frame: pd.DataFrame, k: int) -> np.ndarray:
    column = frame[k]
    if pd.api.types.is_numeric_dtype(column.dtype) and not pd.api.types.is_bool_dtype(
        column.dtype
    ):
        return column.to_numpy(dtype=np.float64)
    if head.decimal == ",":
        # Only reached when a cell is not a number: the C parser converts the rest.
        column = column.map(lambda v: v.replace(",", ".") if isinstance(v, str) else v)
    values = pd.to_numeric(column, errors="coerce")
    bad = values.isna().to_numpy() & column.notna().to_numpy()
    if not bad.any():
        return values.to_numpy(dtype=np.float64)
    row = int(np.flatnonzero(bad)[0])
    raise AcquisitionError(
        path, f"{str(frame[k].iloc[row])!r} is not a number",
        line=head.data_line + int(frame.index[row]), column=head.raw_names[k],
    )


def _nan_runs(values: np.ndarray) -> tuple[int, int, int]:
    """(NaN samples, NaN runs, index of the first NaN or -1)."""
    missing = np.isnan(values)
    count = int(missing.sum())
    if count == 0:
        return 0, 0, -1
    starts = missing & ~np.concatenate([[False], missing[:-1]])
    return count, int(starts.sum()), int(np.argmax(missing))


def read_acquisition(
    path: str | PathLike[str], *, columns: Mapping[str, str] | None = None
) -> xr.Dataset:
    r"""Read an acquisition-card CSV into a Dataset in N, mm and s.

    Parameters
    ----------
    path
        The CSV file. It is opened read-only.
    columns
        Header name (without its unit part) -> channel (``time``, ``index``,
        ``T``, ``N``, ``DG``, ``DD``, ``DT`` or ``ignore``), for names the
        built-in aliases do not know.

    Returns
    -------
    xarray.Dataset
        Dimension ``time`` (s); variables ``T``, ``N`` and whichever of
        ``DG``, ``DD``, ``DT`` the file has, float64 with ``units`` and
        ``long_name``. Global attributes: every metadata key, ``Conventions``,
        ``source``, ``source_sha256``, ``source_format``, ``missing_channels``
        and ``warnings`` (one per line, empty when none).

    Raises
    ------
    AcquisitionError
        Naming the file, line and column of what cannot be read.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "a.csv").write_text(
    ...     "# test_id: demo\nTemps (ms);Ft (kN);Fn (N)\n0;0,001;-80\n10;0,002;-80\n",
    ...     encoding="latin-1")
    >>> ds = read_acquisition(folder / "a.csv")
    >>> ds["T"].values.tolist(), ds["time"].values.tolist(), ds.attrs["missing_channels"]
    ([1.0, 2.0], [0.0, 0.01], 'DG DD DT')

    """
    path = Path(path)
    raw = _read_bytes(path)
    if not raw.strip():
        raise AcquisitionError(path, "the file is empty")
    head = _parse_head(path, raw)
    found = _map_columns(path, head, columns)

    ncols = len(head.names)
    first_data = next(_lines(raw, head.data_offset), None)
    if first_data is not None:
        cells = _decode(first_data[1], head.encoding).split(head.separator)
        if len(cells) > ncols:
            if any(c.strip() for c in cells[ncols:]):
                raise AcquisitionError(
                    path, f"{len(cells)} fields where the header has {ncols}",
                    line=head.data_line,
                )
            # Every data line ends with a separator the header does not have.
            ncols = len(cells)
    frame = _tokenize(path, raw, head, ncols)
    frame = _check_short_rows(path, raw, head, frame, ncols)
    if len(frame) == 0:
        raise AcquisitionError(path, "no data rows after the header", line=head.header_line)

    frame = _drop_cut_last_row(raw, head, frame, list(found.values()))
    if len(frame) == 0:
        raise AcquisitionError(path, "no data rows after the header", line=head.header_line)
    values = {
        channel: _numeric(path, head, frame, k) * _unit_factor(path, head, channel, k)
        for channel, k in found.items()
    }
    lines = head.data_line + frame.index.to_numpy()

    time = _time_axis(path, head, values, lines)
    data_vars = {}
    for channel in CHANNELS:
        if channel not in values:
            continue
        attrs: dict[str, Any] = dict(CHANNEL_ATTRS[channel])
        k = found[channel]
        attrs["source_column"] = head.raw_names[k]
        attrs["source_units"] = head.units[k] or ""
        count, runs, first = _nan_runs(values[channel])
        attrs["nan_count"] = count
        attrs["nan_runs"] = runs
        if count:
            head.warnings.append(
                f"{channel}: {count} missing value(s) in {runs} run(s), first at line "
                f"{int(lines[first])}"
            )
        data_vars[channel] = xr.Variable("time", values[channel], attrs)
    _note_normal_sign(data_vars["N"])

    missing = [c for c in CHANNELS if c not in values]
    global_attrs: dict[str, Any] = dict(head.metadata)
    global_attrs.update(
        Conventions=CONVENTIONS,
        source=path.name,
        source_sha256=hashlib.sha256(raw).hexdigest(),
        source_format=(
            f"separator {head.separator!r}, decimal {head.decimal!r}, encoding "
            f"{head.encoding}, header line {head.header_line}, data from line {head.data_line}"
        ),
        missing_channels=" ".join(missing),
        warnings="\n".join(head.warnings),
    )
    return xr.Dataset(
        data_vars, coords={"time": xr.Variable("time", time, CHANNEL_ATTRS["time"])},
        attrs=global_attrs,
    )


def _time_axis(
    path: Path, head: _Head, values: dict[str, np.ndarray], lines: np.ndarray
) -> np.ndarray:
    rate = head.metadata.get("sample_rate_hz")
    if rate is not None and (
        not isinstance(rate, int | float) or not np.isfinite(rate) or rate <= 0
    ):
        raise AcquisitionError(path, f"sample_rate_hz is {rate!r}, not a positive number")
    if "time" in values:
        time = values.pop("time")
        label = "time"
    elif rate is None:
        raise AcquisitionError(
            path, "no time column and no '# sample_rate_hz: <Hz>' metadata line to make one"
        )
    elif "index" in values:
        time = values.pop("index") / float(rate)
        label = "sample index"
    else:
        time = np.arange(len(lines), dtype=np.float64) / float(rate)
        label = None
    values.pop("index", None)
    if label is not None:
        missing = np.flatnonzero(~np.isfinite(time))
        if missing.size:
            raise AcquisitionError(
                path, f"{label} is missing", line=int(lines[missing[0]])
            )
    steps = np.diff(time)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        what = "repeats" if steps[bad[0]] == 0 else "goes backwards from"
        raise AcquisitionError(
            path,
            f"{label} {time[k]:.9g} {what} {time[k - 1]:.9g} s on the line before; time must "
            "increase",
            line=int(lines[k]),
        )
    if label == "time" and rate is not None and steps.size:
        median = float(np.median(steps))
        if abs(median * float(rate) - 1.0) > 0.01:
            head.warnings.append(
                f"time column steps by {median:.6g} s but sample_rate_hz is {rate}; "
                "the time column is used"
            )
    return np.asarray(time, dtype=np.float64)


def _note_normal_sign(normal: xr.Variable) -> None:
    values = normal.values
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return
    loaded = finite[np.abs(finite) > 0.1 * np.abs(finite).max()]
    sign = "negative" if loaded.size and np.median(loaded) < 0 else "positive"
    normal.attrs["comment"] = (
        f"stored as recorded; compression is {sign} in this file. Analyses use the "
        "compressive magnitude |N|."
    )
    normal.attrs["compression_sign"] = sign


