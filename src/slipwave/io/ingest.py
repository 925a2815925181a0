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
import os
import re
import unicodedata
import warnings
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any, BinaryIO

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


HEAD_BYTES = 1 << 20
"""Bytes at the start of a file in which its metadata, header and first rows are looked for."""
CHUNK_BYTES = 4 << 20
"""Bytes of whole lines parsed at a time: a file is never read whole into memory."""


def _open(path: Path) -> BinaryIO:
    try:
        return open(path, "rb")  # read-only: raw data are never written
    except FileNotFoundError as err:
        raise AcquisitionError(path, "no such file") from err
    except IsADirectoryError as err:
        raise AcquisitionError(path, "is a directory, not an acquisition file") from err
    except OSError as err:
        raise AcquisitionError(path, f"cannot be read: {err.strerror}") from err


def _text_stream(path: Path, handle: BinaryIO, prefix: bytes) -> tuple[BinaryIO, bytes]:
    """The file as a stream of 8-bit text (UTF-16 with a BOM is converted), and its prefix.

    Raises
    ------
    AcquisitionError
        If the file is empty or binary (a NUL byte in its first MiB).
    """
    if prefix.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            text = (prefix + handle.read()).decode("utf-16")
        except UnicodeDecodeError as err:
            raise AcquisitionError(path, f"starts as UTF-16 but is not: {err.reason} at byte "
                                   f"{err.start}") from err
        stream = io.BytesIO(text.encode("utf-8"))
        return stream, stream.read(HEAD_BYTES)
    nul = prefix.find(b"\x00")
    if nul >= 0:
        raise AcquisitionError(path, f"not a text CSV: binary content (a NUL byte at byte {nul})")
    return handle, prefix


def _line_starts(raw: bytes, offset: int) -> np.ndarray:
    """Byte offsets where each line from ``offset`` starts (only on the slow path).

    Line ends are those of pandas' C parser: LF, CRLF and a lone CR.
    """
    buffer = np.frombuffer(raw, dtype=np.uint8, offset=offset)
    lf = buffer == 10
    lone_cr = (buffer == 13) & ~np.concatenate([lf[1:], [False]])
    return np.concatenate([[0], np.flatnonzero(lf | lone_cr) + 1]) + offset


def _blocks(stream: BinaryIO, start: int, digest: Any = None) -> Iterator[tuple[bytes, bool]]:
    """Blocks of whole lines from ``start`` (the last may lack its line end), and if last.

    With ``digest`` (a hashlib object), every byte of the stream is fed to it on the
    way, the head before ``start`` included: the file is read once.
    """
    stream.seek(0 if digest is not None else start)
    if digest is not None:
        digest.update(stream.read(start))
    carry = b""
    while True:
        block = stream.read(CHUNK_BYTES)
        if digest is not None:
            digest.update(block)
        if not block:
            if carry:
                yield carry, True
            return
        data = carry + block if carry else block
        cut = data.rfind(b"\n") + 1 or data.rfind(b"\r") + 1
        if cut == 0:
            carry = data
            continue
        carry = data[cut:]
        yield data[:cut], False


def _tokenize(path: Path, block: bytes, head: _Head, ncols: int, first_line: int
              ) -> pd.DataFrame:
    try:
        with warnings.catch_warnings():
            # pandas truncates a first line longer than the names, with only a warning
            warnings.simplefilter("error", pd.errors.ParserWarning)
            return pd.read_csv(
                io.BytesIO(block),
                sep=head.separator, decimal=head.decimal, header=None, names=range(ncols),
                skip_blank_lines=False, engine="c", encoding=head.encoding, index_col=False,
                encoding_errors="replace", quotechar='"', comment=None, low_memory=False,
            )
    except pd.errors.ParserWarning as err:
        first = block.split(b"\n", 1)[0].rstrip(b"\r")
        fields = first.count(head.separator.encode()) + 1
        raise AcquisitionError(path, f"{fields} fields where the header has {ncols}",
                               line=first_line) from err
    except pd.errors.ParserError as err:
        match = _PANDAS_LINE.search(str(err))
        if match is None:
            raise AcquisitionError(path, f"cannot be parsed: {err}") from err
        line = first_line + int(match[1]) - 1
        raise AcquisitionError(
            path, f"{match[2]} fields where the header has {ncols}", line=line
        ) from err
    except pd.errors.EmptyDataError:
        return pd.DataFrame(columns=range(ncols))


def _check_short_rows(path: Path, block: bytes, head: _Head, frame: pd.DataFrame, ncols: int,
                      first_line: int, final: bool) -> tuple[pd.DataFrame, int]:
    """Drop blank lines and a truncated last line; refuse other short lines.

    Returns the rows kept and the number of blank lines dropped.
    """
    candidates = np.flatnonzero(frame[ncols - 1].isna().to_numpy())
    if candidates.size == 0:
        return frame, 0
    starts = _line_starts(block, 0)
    separator = head.separator.encode()
    drop: list[int] = []
    blanks = 0
    last = len(frame) - 1
    for row in candidates:
        end = starts[row + 1] if row + 1 < len(starts) else len(block)
        text = block[starts[row] : end].rstrip(b"\r\n")
        if not text.strip():
            drop.append(int(row))
            blanks += 1
            continue
        fields = text.count(separator) + 1
        if fields >= ncols:
            continue
        line = first_line + int(row)
        if final and row == last:
            drop.append(int(row))
            head.warnings.append(
                f"line {line}: truncated last line ({fields} of {ncols} fields) dropped"
            )
            continue
        raise AcquisitionError(path, f"{fields} fields where the header has {ncols}", line=line)
    return frame.drop(index=frame.index[drop]), blanks


class _LineNumbers:
    """The file line of each kept row, stored as the few places where lines were skipped.

    Blank and dropped lines are rare: keeping where they occur, not a line number per
    row, costs nothing next to the data.
    """

    def __init__(self, first_line: int) -> None:
        self.first_line = first_line
        self.size = 0
        self.starts: list[int] = [0]  # row from which ...
        self.offsets: list[int] = [0]  # ... this many lines had been skipped

    def extend(self, lines: np.ndarray) -> None:
        skipped = lines - self.first_line - (self.size + np.arange(lines.size))
        changes = np.flatnonzero(np.diff(skipped, prepend=self.offsets[-1]))
        self.starts.extend((self.size + changes).tolist())
        self.offsets.extend(skipped[changes].tolist())
        self.size += lines.size

    def __len__(self) -> int:
        return self.size

    def __getitem__(self, row: int) -> int:
        at = int(np.searchsorted(self.starts, row, side="right")) - 1
        return self.first_line + int(row) + self.offsets[at]


class _Columns:
    """The channels' values, filled block by block into arrays sized from an estimate.

    Growing by a quarter when the estimate was short, and trimmed in place at the
    end, the arrays are never held twice: the peak stays near their final size.
    """

    def __init__(self, channels: Iterable[str], rows: int, first_line: int) -> None:
        self.arrays = {channel: np.empty(max(rows, 16)) for channel in channels}
        self.lines = _LineNumbers(first_line)

    def append(self, values: Mapping[str, np.ndarray], lines: np.ndarray) -> None:
        start = len(self.lines)
        needed = start + lines.size
        for channel, array in self.arrays.items():
            if needed > array.size:
                array.resize(max(needed, int(array.size * 1.25)), refcheck=False)
            array[start:needed] = values[channel]
        self.lines.extend(lines)

    def finish(self) -> tuple[dict[str, np.ndarray], _LineNumbers]:
        for array in self.arrays.values():
            array.resize(len(self.lines), refcheck=False)
        return self.arrays, self.lines


def _data_columns(path: Path, head: _Head, prefix: bytes) -> int:
    """Fields per data line: the header's, or one more when every line ends with a separator."""
    ncols = len(head.names)
    first_data = next(_lines(prefix, head.data_offset), None)
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
    return ncols


def _read_data(path: Path, stream: BinaryIO, head: _Head, ncols: int, found: Mapping[str, int],
               size: int, digest: Any = None) -> tuple[dict[str, np.ndarray], _LineNumbers]:
    """The channels' values (in N, mm, s) and the line of each row, block by block.

    A last line without its line end was cut while the card wrote it, whatever it
    parses as (``11.0`` may be the start of ``11.58905``): it is dropped, with a warning.
    """
    factors = {channel: _unit_factor(path, head, channel, k) for channel, k in found.items()}
    columns: _Columns | None = None
    row = 0  # data lines read so far
    blanks = 0
    infinities: dict[str, int] = {}
    for block, final in _blocks(stream, head.data_offset, digest):
        first_line = head.data_line + row
        frame = _tokenize(path, block, head, ncols, first_line)
        lines_in_block = len(frame)
        frame, dropped = _check_short_rows(path, block, head, frame, ncols, first_line, final)
        blanks += dropped
        last = lines_in_block - 1
        if final and not block.endswith((b"\n", b"\r")) and last in frame.index:
            frame = frame.drop(index=last)
            head.warnings.append(
                f"line {first_line + last}: the file ends inside this line (no line end: the "
                "acquisition stopped while writing it), so it was dropped"
            )
        if columns is None:
            per_line = len(block) / max(lines_in_block, 1)
            columns = _Columns(found, int((size - head.data_offset) / per_line * 1.02) + 16,
                               head.data_line)
        lines = first_line + frame.index.to_numpy(dtype=np.int64)
        frame.index = lines - head.data_line  # rows numbered from the first data line
        values = {}
        for channel, k in found.items():
            column = _numeric(path, head, frame, k)
            infinite = np.isinf(column)
            if infinite.any():  # an overflowed reading is no value: counted as missing
                column = np.where(infinite, np.nan, column)
                infinities[channel] = infinities.get(channel, 0) + int(infinite.sum())
            values[channel] = column * factors[channel] if factors[channel] != 1.0 else column
        columns.append(values, lines)
        row += lines_in_block
    if blanks:
        head.warnings.append(f"{blanks} blank line(s) in the data skipped")
    for channel, count in infinities.items():
        head.warnings.append(f"{channel}: {count} infinite value(s) (inf) read as missing")
    if columns is None:
        return {channel: np.empty(0) for channel in found}, _LineNumbers(head.data_line)
    return columns.finish()


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


SATURATION_RUN = 50
"""Samples in a row at a channel's extreme value from which it reads as clipped."""


def saturation(values: np.ndarray, *, min_run: int = SATURATION_RUN) -> int:
    """Where a channel sits at its extreme value, as a clipped sensor does: first index.

    A sensor at the end of its range (or a card at full scale) repeats one value
    exactly, its largest or smallest; noise never holds a value that long.

    Parameters
    ----------
    values
        The channel.
    min_run
        Samples in a row at the extreme (and at least 1 % of the channel) that mark it.

    Returns
    -------
    int
        The first sample of the first such run, or -1.

    Examples
    --------
    >>> import numpy as np
    >>> ramp = np.minimum(np.linspace(0.0, 30.0, 1000), 25.0)
    >>> saturation(ramp), saturation(np.sin(np.arange(1000.0)))
    (833, -1)
    """
    finite = values[np.isfinite(values)]
    if finite.size == 0 or finite.min() == finite.max():
        return -1
    run = max(min_run, values.size // 100)
    for extreme in (finite.max(), finite.min()):
        at = np.concatenate([[False], values == extreme, [False]])
        edges = np.flatnonzero(np.diff(at.astype(np.int8)))
        starts, ends = edges[::2], edges[1::2]
        long = np.flatnonzero(ends - starts >= run)
        if long.size:
            return int(starts[long[0]])
    return -1


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
        ``source``, ``source_sha256``, ``source_format``, ``missing_channels``,
        ``warnings`` (one per line, empty when none) and the identity every product
        made from it carries (:mod:`slipwave.identity`): ``product`` ("recording"),
        ``test_id`` (the header's, else the file's name without its suffix) and
        ``recording_sha256`` (``source_sha256``). A channel that sits at its extreme
        value (:func:`saturation`) has ``saturated_from_index``.

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
    with _open(path) as handle:
        digest = hashlib.sha256()
        stream, prefix = _text_stream(path, handle, handle.read(HEAD_BYTES))
        if not prefix.strip():
            raise AcquisitionError(path, "the file is empty")
        size = stream.seek(0, os.SEEK_END)
        head = _parse_head(path, prefix if size <= len(prefix)
                           else prefix[: prefix.rfind(b"\n") + 1])
        found = _map_columns(path, head, columns)
        ncols = _data_columns(path, head, prefix)
        # the hash is of the file's own bytes: fed while reading, or (for UTF-16, which
        # was converted whole) read again
        values, lines = _read_data(path, stream, head, ncols, found, size,
                                   digest if stream is handle else None)
        if stream is not handle:
            handle.seek(0)
            digest.update(handle.read())
    if len(lines) == 0:
        raise AcquisitionError(path, "no data rows after the header", line=head.header_line)
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
                f"{lines[first]}"
            )
        clipped = saturation(values[channel])
        if clipped >= 0:
            attrs["saturated_from_index"] = clipped
            head.warnings.append(
                f"{channel}: stays at {values[channel][clipped]:.6g} {attrs.get('units', '')} "
                f"from line {lines[clipped]} on, as a sensor at the end of its range does: "
                "the values beyond it are lost (the fit leaves them out)")
        data_vars[channel] = xr.Variable("time", values[channel], attrs)
    if "N" in data_vars:
        _note_normal_sign(data_vars["N"])

    missing = [c for c in CHANNELS if c not in values]
    global_attrs: dict[str, Any] = dict(head.metadata)
    global_attrs.update(
        Conventions=CONVENTIONS,
        source=path.name,
        source_sha256=digest.hexdigest(),
        # the recording's identity, which every product made from it carries
        product="recording",
        test_id=str(head.metadata.get("test_id") or path.stem),
        recording_sha256=digest.hexdigest(),
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
    path: Path, head: _Head, values: dict[str, np.ndarray], lines: _LineNumbers
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
                path, f"{label} is missing", line=lines[int(missing[0])]
            )
    bad = np.flatnonzero(time[1:] <= time[:-1])  # no array of steps: time may be GBs
    if bad.size:
        k = int(bad[0]) + 1
        what = "repeats" if time[k] == time[k - 1] else "goes backwards from"
        raise AcquisitionError(
            path,
            f"{label} {time[k]:.9g} {what} {time[k - 1]:.9g} s on the line before; time must "
            "increase",
            line=lines[k],
        )
    if label == "time" and rate is not None and time.size > 1:
        stride = max(1, time.size // 100_000)  # a sample of steps tells the rate as well
        median = float(np.median(np.diff(time[::stride]))) / stride
        if abs(median * float(rate) - 1.0) > 0.01:
            head.warnings.append(
                f"time column steps by {median:.6g} s but sample_rate_hz is {rate}; "
                "the time column is used"
            )
    return np.asarray(time, dtype=np.float64)


def _note_normal_sign(normal: xr.Variable) -> None:
    # A strided sample of at most about a million values tells the sign as well as all.
    values = normal.values[:: max(1, normal.size // 1_000_000)]
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


