"""Reading an acquisition file in blocks, and files cut short, binary or unusual."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from slipwave.errors import SlipwaveError
from slipwave.io import ingest as ingest_module
from slipwave.io import read_acquisition

ROOT = Path(__file__).parents[1]
HL050 = ROOT / "raw_data/bench/hl050.csv"


def test_last_line_cut_inside_a_number_is_dropped(tmp_path):
    raw = HL050.read_bytes()
    cut = tmp_path / "cut.csv"
    cut.write_bytes(raw[:-7])  # "11.58905\n" becomes "11.0" and no line end: it parses
    whole, partial = read_acquisition(HL050), read_acquisition(cut)
    assert partial.sizes["time"] == whole.sizes["time"] - 1
    np.testing.assert_array_equal(partial["DT"].values, whole["DT"].values[:-1])
    assert "the file ends inside this line" in partial.attrs["warnings"]


def test_the_file_is_read_in_blocks_not_whole(tmp_path, monkeypatch):
    """Peak memory stays near the arrays (figures in bench_ingest): no read of the whole file."""
    monkeypatch.setattr(ingest_module, "CHUNK_BYTES", 4096)
    reads: list[int] = []

    def spying_open(path, mode="r"):
        handle = open(path, mode)  # noqa: SIM115 (handed back open, as the reader does)
        read = handle.read

        def counted(size=-1):
            reads.append(size)
            return read(size)

        handle.read = counted  # type: ignore[method-assign]
        return handle

    monkeypatch.setattr(ingest_module, "open", spying_open, raising=False)
    blocks = read_acquisition(HL050)
    assert reads and all(0 < size <= ingest_module.HEAD_BYTES for size in reads)
    monkeypatch.undo()
    whole = read_acquisition(HL050)
    assert blocks.identical(whole)  # 300 blocks of 4 KiB give the same Dataset


def test_line_numbers_hold_across_blocks(write, monkeypatch):
    monkeypatch.setattr(ingest_module, "CHUNK_BYTES", 64)
    rows = "".join(f"{k / 100:.2f},{k},-80,0,0,0\n" for k in range(40))
    text = "time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]\n" + rows.replace(
        "0.30,30,", "0.30,x30,").replace("0.12,12,-80,0,0,0\n", "0.12,12,-80,0,0,0\n\n")
    with pytest.raises(SlipwaveError, match=r"line 33, column 'T \[N\]': 'x30' is not a number"):
        read_acquisition(write(text))


def test_a_long_line_at_the_start_of_any_block_is_refused(write, monkeypatch):
    monkeypatch.setattr(ingest_module, "CHUNK_BYTES", 64)  # pandas only warns on a block's first
    rows = [f"{k / 100:.2f},{k},-80,0,0,0\n" for k in range(30)]
    for k in range(len(rows)):
        longer = [*rows[:k], rows[k].rstrip("\n") + ",7\n", *rows[k + 1 :]]
        path = write("time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]\n" + "".join(longer))
        with pytest.raises(SlipwaveError, match=rf"line {k + 2}: 7 fields where the header has 6"):
            read_acquisition(path)


def test_binary_and_utf16_files(write):
    with pytest.raises(SlipwaveError, match=r"not a text CSV: binary content \(a NUL byte"):
        read_acquisition(write(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256))))
    text = "time [s];T [N];N [N]\r\n0,0;1,5;-80\r\n0,01;2,5;-80\r\n"
    ds = read_acquisition(write(text.encode("utf-16")))
    assert ds["T"].values.tolist() == [1.5, 2.5]


def test_infinite_values_are_missing(write):
    ds = read_acquisition(write("time [s],T [N],N [N]\n0,1,-80\n0.01,inf,-80\n0.02,2,-80\n"))
    assert np.isnan(ds["T"].values[1]) and ds["T"].attrs["nan_count"] == 1
    assert "T: 1 infinite value(s) (inf) read as missing" in ds.attrs["warnings"]
