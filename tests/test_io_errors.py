"""Every bad input gives an AcquisitionError naming the file, line, column and fault."""

from __future__ import annotations

import re

import pytest

from slipwave.errors import AcquisitionError
from slipwave.io import read_acquisition

from conftest import CANONICAL


def fails(path, pattern: str, *, line: int | None = None, column: str | None = None, **kw):
    with pytest.raises(AcquisitionError) as info:
        read_acquisition(path, **kw)
    error = info.value
    assert str(error).startswith(str(path))
    assert re.search(pattern, str(error)), str(error)
    assert error.line == line
    assert error.column == column
    return error


def test_empty_file(write):
    fails(write(""), r": the file is empty$")


def test_whitespace_only(write):
    fails(write("\n\r\n  \n"), r": the file is empty$")


def test_missing_file(tmp_path):
    fails(tmp_path / "nope.csv", r"nope.csv: no such file$")


def test_only_metadata(write):
    fails(write("# test_id: x\n# sample_rate_hz: 10\n"), r"no header row")


def test_header_only(write):
    error = fails(write("# test_id: x\ntime [s],T [N],N [N]\n"), r"no data rows after the header",
                  line=2)
    assert str(error) == f"{error.path}, line 2: no data rows after the header"


def test_missing_required_channel(write):
    fails(write("time [s],N [N]\n0,1\n1,2\n"), r"no column for the required channel T ",
          line=1)


def test_force_only_recording(write):
    ds = read_acquisition(write("time [s],T [N]\n0,1\n0.01,2\n"))  # a spring-slider's
    assert list(ds.data_vars) == ["T"] and ds.attrs["missing_channels"] == "N DG DD DT"


def test_non_numeric_cell(write):
    text = CANONICAL.replace("2.5,-81.0", "2.5,abc")
    error = fails(write(text), r"'abc' is not a number$", line=11, column="N [N]")
    assert str(error).endswith("test.csv, line 11, column 'N [N]': 'abc' is not a number")


def test_non_numeric_cell_with_decimal_comma(write):
    text = CANONICAL.replace(",", ";").replace(".", ",").replace("0,12;", "0.1.2;")
    fails(write(text), r"'0.1.2' is not a number", line=11, column="DG [mm]")


def test_duplicated_time(write):
    text = CANONICAL.replace("0.02,2.5", "0.01,2.5")
    fails(write(text), r"time 0\.01 repeats 0\.01 s on the line before; time must increase",
          line=11)


def test_decreasing_time(write):
    text = CANONICAL.replace("0.03,3.5", "0.015,3.5")
    fails(write(text), r"time 0\.015 goes backwards from 0\.02 s", line=12)


def test_missing_time_value(write):
    text = CANONICAL.replace("0.02,2.5", ",2.5")
    fails(write(text), r"time is missing", line=11)


def test_unknown_unit(write):
    text = CANONICAL.replace("T [N]", "T [zorks]")
    fails(write(text), r"unknown unit 'zorks'$", line=8, column="T [zorks]")


def test_unit_of_wrong_kind_velocity(write):
    text = CANONICAL.replace("T [N]", "T [furlongs per fortnight]")
    fails(write(text), r"unit 'furlongs per fortnight' is not a force", line=8,
          column="T [furlongs per fortnight]")


def test_unit_of_wrong_kind(write):
    text = CANONICAL.replace("DG [mm]", "DG [N]")
    fails(write(text), r"unit 'N' is not a length, as channel DG needs", line=8, column="DG [N]")


def test_unknown_unit_in_unit_row(write):
    text = "time,T,N\ns,N,zorks\n0,1,2\n"
    fails(write(text), r"unknown unit 'zorks'", line=2, column="N")


@pytest.mark.parametrize(
    ("old", "new", "fields", "line"),
    [
        ("0.11,0.21,0.001", "0.11,0.21,0.001,9", 7, 10),
        ("0.11,0.21,0.001", "0.11,0.21", 5, 10),
        ("0.10,0.20,0.000", "0.10,0.20,0.000,7", 7, 9),
        ("0.10,0.20,0.000", "0.10,0.20", 5, 9),
    ],
    ids=["more", "fewer", "more-in-first", "fewer-in-first"],
)
def test_inconsistent_column_count(write, old, new, fields, line):
    text = CANONICAL.replace(old, new)
    fails(write(text), rf": {fields} fields where the header has 6$", line=line)


def test_no_time_and_no_rate(write):
    fails(write("T [N],N [N]\n1,2\n"), r"no time column and no '# sample_rate_hz")


def test_bad_sample_rate(write):
    fails(write("# sample_rate_hz: fast\nT [N],N [N]\n1,2\n"), r"sample_rate_hz is 'fast'")


def test_two_columns_for_one_channel(write):
    fails(write("time [s],T [N],Ft [N],N [N]\n0,1,1,2\n"), r"'T \[N\]' and 'Ft \[N\]' both map "
          r"to channel T", line=1)


def test_mapping_to_unknown_channel(write):
    fails(write(CANONICAL), r"columns mapping sends 'T' to 'Tangential'",
          columns={"T": "Tangential"})


def test_directory(tmp_path):
    fails(tmp_path, r"is a directory")
