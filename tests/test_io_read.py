"""read_acquisition on the canonical format and on every variant cards write."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from slipwave.bench.sawtooth import SawtoothBench, sawtooth_recording
from slipwave.io import read_acquisition, read_dataset, write_acquisition, write_dataset

from conftest import CANONICAL

T = [0.5, 1.5, 2.5, 3.5]
N = [-80.0, -80.5, -81.0, -81.5]
TIME = [0.0, 0.01, 0.02, 0.03]


def check_values(ds: xr.Dataset, *, scale_t: float = 1.0) -> None:
    np.testing.assert_allclose(ds["time"].values, TIME, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(ds["T"].values, np.asarray(T) * scale_t, rtol=1e-12)
    np.testing.assert_allclose(ds["N"].values, N, rtol=1e-12)


def test_canonical(write):
    ds = read_acquisition(write(CANONICAL))
    check_values(ds)
    np.testing.assert_allclose(ds["DT"].values, [0.0, 0.001, 0.002, 0.003])
    assert ds["time"].dtype == np.float64 and ds["T"].dtype == np.float64
    assert ds["T"].attrs["units"] == "N" and ds["DG"].attrs["units"] == "mm"
    assert ds["time"].attrs["units"] == "s"
    assert all("long_name" in ds[v].attrs for v in ["time", "T", "N", "DG", "DD", "DT"])
    assert ds.attrs["test_id"] == "t1"
    assert ds.attrs["sample_rate_hz"] == 100
    assert ds.attrs["length_mm"] == 80 and ds.attrs["normal_load_n"] == 85
    assert ds.attrs["Conventions"] == "CF-1.12"
    assert ds.attrs["source"] == "test.csv"
    assert ds.attrs["source_sha256"] == hashlib.sha256(CANONICAL.encode()).hexdigest()
    assert ds.attrs["missing_channels"] == ""
    assert ds.attrs["warnings"] == ""
    assert ds["N"].attrs["compression_sign"] == "negative"


@pytest.mark.parametrize("separator", [",", ";", "\t"])
def test_separators(write, separator):
    ds = read_acquisition(write(CANONICAL.replace(",", separator)))
    check_values(ds)
    assert f"separator {separator!r}" in ds.attrs["source_format"]


def test_decimal_comma_with_semicolon(write):
    text = CANONICAL.replace(",", ";").replace(".", ",")
    ds = read_acquisition(write(text))
    check_values(ds)
    assert "decimal ','" in ds.attrs["source_format"]


def test_crlf(write):
    ds = read_acquisition(write(CANONICAL.replace("\n", "\r\n")))
    check_values(ds)
    assert ds.attrs["test_id"] == "t1"


def test_latin1_french_headers(write):
    text = (
        "# test_id: fr\n"
        "Temps (s);Effort tangentiel (N);Effort normal (N);Déplacement gauche (mm);"
        "Déplacement droit (mm);Déplacement plan (mm)\n"
        "0;0,5;-80;0,1;0,2;0\n0,01;1,5;-80,5;0,11;0,21;0,001\n"
        "0,02;2,5;-81;0,12;0,22;0,002\n0,03;3,5;-81,5;0,13;0,23;0,003\n"
    )
    ds = read_acquisition(write(text, encoding="latin-1"))
    check_values(ds)
    assert ds["DG"].attrs["source_column"] == "Déplacement gauche (mm)"
    assert "encoding latin-1" in ds.attrs["source_format"]


def test_utf8_bom_and_french_headers(write):
    text = "Temps (s);Ft (N);Fn (N);Déplacement gauche (mm)\n0;1;-2;3\n1;2;-3;4\n"
    ds = read_acquisition(write(b"\xef\xbb\xbf" + text.encode()))
    assert ds["DG"].values.tolist() == [3.0, 4.0]
    assert "encoding utf-8" in ds.attrs["source_format"]


def test_trailing_empty_columns(write):
    lines = CANONICAL.splitlines()
    text = "\n".join(line if line.startswith("#") else line + ",," for line in lines) + "\n"
    ds = read_acquisition(write(text))
    check_values(ds)
    assert ds.attrs["warnings"] == ""


def test_trailing_separator_only_in_data(write):
    lines = CANONICAL.splitlines()
    text = "\n".join(line + "," if line[0].isdigit() else line for line in lines) + "\n"
    check_values(read_acquisition(write(text)))


@pytest.mark.parametrize(
    "header",
    [
        "time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]",
        "time (s),T (N),N (N),DG (mm),DD (mm),DT (mm)",
        "time,T,N,DG,DD,DT\ns,N,N,mm,mm,mm",
        "time,T,N,DG,DD,DT\n[s],[N],[N],[mm],[mm],[mm]",
    ],
    ids=["brackets", "parentheses", "unit-row", "unit-row-brackets"],
)
def test_unit_notations(write, header):
    text = CANONICAL.replace("time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]", header)
    check_values(read_acquisition(write(text)))


def test_unit_row_with_decimal_comma(write):
    text = "Temps;Ft;Fn\ns;N;N\n0;0,5;-80\n0,01;1,5;-80,5\n0,02;2,5;-81\n0,03;3,5;-81,5\n"
    check_values(read_acquisition(write(text)))


@pytest.mark.parametrize(
    ("time_unit", "t_unit", "d_unit", "t_factor", "time_factor", "d_factor"),
    [
        ("s", "N", "mm", 1.0, 1.0, 1.0),
        ("ms", "kN", "m", 1e-3, 1e3, 1e-3),
        ("ms", "mN", "um", 1e3, 1e3, 1e3),
        ("s", "N", "µm", 1.0, 1.0, 1e3),
        ("s", "N", "μm", 1.0, 1.0, 1e3),
    ],
)
def test_unit_conversion(write, time_unit, t_unit, d_unit, t_factor, time_factor, d_factor):
    # Values written in the file's units: SI value * factor.
    rows = "\n".join(
        f"{t * time_factor:.10g},{tt * t_factor:.10g},{n:.10g},{0.1 * k * d_factor:.10g}"
        for k, (t, tt, n) in enumerate(zip(TIME, T, N, strict=True))
    )
    text = f"time [{time_unit}],T [{t_unit}],N [N],DG [{d_unit}]\n{rows}\n"
    ds = read_acquisition(write(text))
    check_values(ds)
    np.testing.assert_allclose(ds["DG"].values, [0.0, 0.1, 0.2, 0.3], atol=1e-12)
    assert ds["T"].attrs["source_units"] == t_unit


def test_column_mapping(write):
    text = "Horloge (s);Cisaillement (N);Serrage (N)\n0;0,5;-80\n0,01;1,5;-80,5\n"
    text += "0,02;2,5;-81\n0,03;3,5;-81,5\n"
    ds = read_acquisition(
        write(text), columns={"Horloge": "time", "Cisaillement": "T", "Serrage": "N"}
    )
    check_values(ds)
    assert ds.attrs["missing_channels"] == "DG DD DT"


@pytest.mark.parametrize("names", [("t", "Ft", "Fn"), ("Time", "Tangential load", "Normal load")])
def test_aliases(write, names):
    rows = "\n".join(f"{a},{b},{c}" for a, b, c in zip(TIME, T, N, strict=True))
    text = f"{names[0]} [s],{names[1]} [N],{names[2]} [N]\n{rows}\n"
    check_values(read_acquisition(write(text)))


def test_unused_columns_are_reported(write):
    text = "time [s],T [N],N [N],Temperature [degC]\n0,1,-2,20\n1,2,-3,21\n"
    ds = read_acquisition(write(text))
    assert "columns not used: 'Temperature [degC]'" in ds.attrs["warnings"]
    assert set(ds.data_vars) == {"T", "N"}


def test_time_from_sample_rate(write):
    text = "# sample_rate_hz: 100\nT [N],N [N]\n0.5,-80\n1.5,-80.5\n2.5,-81\n3.5,-81.5\n"
    check_values(read_acquisition(write(text)))


def test_time_from_index_and_sample_rate(write):
    text = "# sample_rate_hz: 50\nindex,T [N],N [N]\n10,0.5,-80\n11,1.5,-80.5\n"
    ds = read_acquisition(write(text))
    np.testing.assert_allclose(ds["time"].values, [0.2, 0.22])


def test_missing_optional_channels(write):
    text = "time [s],T [N],N [N],DD [mm]\n0,1,-2,0.1\n1,2,-3,0.2\n"
    ds = read_acquisition(write(text))
    assert ds.attrs["missing_channels"] == "DG DT"
    assert "DG" not in ds and "DD" in ds


def test_truncated_last_line_dropped_with_warning(write):
    text = CANONICAL + "0.04,4.5,-8"  # stopped mid-write, no newline
    ds = read_acquisition(write(text))
    check_values(ds)
    assert "line 13: truncated last line (3 of 6 fields) dropped" in ds.attrs["warnings"]


def test_last_line_cut_inside_a_number(write):
    text = CANONICAL + "0.04,4.5,-82.0,0.14,0.24,1e-"
    ds = read_acquisition(write(text))
    check_values(ds)
    assert "line 13: the file ends inside this line" in ds.attrs["warnings"]


def test_nan_runs_counted(write):
    text = CANONICAL.replace("1.5,-80.5", ",-80.5").replace("2.5,-81.0", "NaN,-81.0")
    text = text.replace("0.13,0.23", ",0.23")
    ds = read_acquisition(write(text))
    assert ds["T"].attrs["nan_count"] == 2 and ds["T"].attrs["nan_runs"] == 1
    assert ds["DG"].attrs["nan_count"] == 1
    assert "T: 2 missing value(s) in 1 run(s), first at line 10" in ds.attrs["warnings"]
    assert "DG: 1 missing value(s) in 1 run(s), first at line 12" in ds.attrs["warnings"]


def test_blank_lines_skipped(write):
    text = CANONICAL.replace("0.01,1.5", "\n0.01,1.5") + "\n\n"
    ds = read_acquisition(write(text))
    check_values(ds)
    assert "3 blank line(s) in the data skipped" in ds.attrs["warnings"]


def test_metadata_cannot_overwrite_provenance(write):
    ds = read_acquisition(write("# source: forged\n" + CANONICAL))
    assert ds.attrs["source"] == "test.csv" and ds.attrs["meta_source"] == "forged"


def test_raw_file_not_modified(write):
    path = write(CANONICAL)
    os.chmod(path, 0o444)  # read-only: the reader must not need to write
    before = (path.read_bytes(), path.stat().st_mtime_ns)
    read_acquisition(path)
    assert (path.read_bytes(), path.stat().st_mtime_ns) == before


def test_netcdf_round_trip_identical(write, tmp_path):
    ds = read_acquisition(write(CANONICAL.replace("2.5,-81.0", "nan,-81.0")))
    out = write_dataset(ds, tmp_path / "out" / "rec.nc")
    back = read_dataset(out)
    xr.testing.assert_identical(back, ds)
    for name in ["T", "N", "DG", "DD", "DT", "time"]:
        assert np.array_equal(back[name].values, ds[name].values, equal_nan=True)
    assert back["T"].encoding["zlib"] is True


def test_text_is_written_whole_whatever_the_width_it_was_read_with(tmp_path):
    # two pieces read from files of different text widths, joined: the join keeps the
    # first piece's encoding (<U5), which must not cut the longer text when written
    short = xr.Dataset({"sequence": ("case", np.array(["a -> b"]))}, coords={"case": [0]})
    long = xr.Dataset({"sequence": ("case", np.array(["a -> b -> gross sliding"]))},
                      coords={"case": [1]})
    pieces = []
    for k, piece in enumerate((short, long)):
        pieces.append(read_dataset(write_dataset(piece, tmp_path / f"piece{k}.nc")))
    joined = xr.concat(pieces, dim="case")
    assert joined["sequence"].encoding["dtype"].itemsize < 4 * 23
    back = read_dataset(write_dataset(joined, tmp_path / "joined.nc"))
    assert back["sequence"].values.tolist() == ["a -> b", "a -> b -> gross sliding"]


def test_write_dataset_is_all_or_nothing(tmp_path):
    ds = xr.Dataset({"T": ("time", [1.0])}, coords={"time": [0.0]})
    target = tmp_path / "rec.nc"
    target.write_bytes(b"previous")
    bad = ds.assign_attrs(bad=object())  # stored as text: this must succeed
    write_dataset(bad, target)
    assert target.read_bytes() != b"previous"
    broken = ds.assign(T=("time", np.array([object()])))  # netCDF cannot store objects
    with pytest.raises(Exception):  # noqa: B017 - whatever xarray raises
        write_dataset(broken, target)
    assert read_dataset(target)["T"].values.tolist() == [1.0]
    assert [p.name for p in tmp_path.iterdir()] == ["rec.nc"]


@pytest.mark.parametrize("flavour", ["canonical", "vendor"])
def test_written_csv_reads_back(tmp_path, flavour):
    ds = sawtooth_recording(SawtoothBench(duration=60.0), seed=3)
    path = write_acquisition(ds, tmp_path / f"{flavour}.csv", flavour=flavour)
    back = read_acquisition(path)
    for name in ["T", "N", "DG", "DD", "DT"]:
        np.testing.assert_allclose(back[name].values, ds[name].values, rtol=1e-5, atol=1e-8)
    np.testing.assert_allclose(back["time"].values, ds["time"].values, atol=1e-9)
    assert back.attrs["test_id"] == "demo" and back.attrs["speed_mm_s"] == 0.048
    raw = path.read_bytes()
    if flavour == "vendor":
        assert b"\r\n" in raw and "Déplacement".encode("latin-1") in raw and b";" in raw
    else:
        assert b"time [s],T [N]" in raw


def test_default_campaign_files_read():
    folder = Path(__file__).parents[1] / "raw_data" / "bench"
    files = sorted(folder.glob("*.csv"))
    assert [f.name for f in files] == ["hl025.csv", "hl050.csv", "hl075.csv"]
    for path in files:
        ds = read_acquisition(path)
        assert ds.sizes["time"] == 28000 and float(ds["time"][-1]) == pytest.approx(279.99)
        assert float(ds["N"].values[-1]) == pytest.approx(-85.0, abs=1.5)
        assert ds["N"].attrs["compression_sign"] == "negative"
        assert 40.0 < float(ds["T"].max()) < 120.0 and ds.attrs["missing_channels"] == ""
        assert ds.attrs["sync_time_s"] == 2.0
    assert "decimal ','" in read_acquisition(folder / "hl025.csv").attrs["source_format"]
