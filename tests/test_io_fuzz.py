"""Random and mutated files: the reader returns a Dataset or raises SlipwaveError, nothing else."""

from __future__ import annotations

import tempfile
from pathlib import Path

import xarray as xr
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from slipwave.errors import SlipwaveError
from slipwave.io import read_acquisition

from conftest import CANONICAL

VARIANTS = [
    CANONICAL,
    CANONICAL.replace(",", ";").replace(".", ","),
    CANONICAL.replace(",", "\t").replace("\n", "\r\n"),
    "Temps;Ft;Fn\ns;N;N\n0;0,5;-80\n0,01;1,5;-80,5\n",
    "# sample_rate_hz: 100\nT [N],N [N]\n1,2\n3,4\n",
]
_folder = Path(tempfile.mkdtemp(prefix="slipwave-fuzz-"))


def read_or_fail(content: bytes) -> None:
    path = _folder / "fuzz.csv"
    path.write_bytes(content)
    try:
        result = read_acquisition(path)
    except SlipwaveError:
        return
    assert isinstance(result, xr.Dataset)
    assert result["time"].size > 0


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=400))
def test_random_bytes(content):
    read_or_fail(content)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(alphabet=st.sampled_from(list("0123456789.,;\t\n\r-+eE#: []()TNDGtimsµk")),
               max_size=300))
def test_random_csv_like_text(text):
    read_or_fail(text.encode("utf-8"))


@st.composite
def mutated(draw):
    content = bytearray(draw(st.sampled_from(VARIANTS)).encode("utf-8"))
    for _ in range(draw(st.integers(1, 6))):
        action = draw(st.sampled_from(["delete", "insert", "replace", "truncate", "duplicate"]))
        if not content:
            break
        at = draw(st.integers(0, len(content) - 1))
        if action == "delete":
            del content[at : at + draw(st.integers(1, 8))]
        elif action == "insert":
            content[at:at] = draw(st.binary(min_size=1, max_size=6))
        elif action == "replace":
            content[at] = draw(st.sampled_from(b"0.,;\t\n\r-xe# []()"))
        elif action == "truncate":
            del content[at:]
        else:
            end = content.find(b"\n", at)
            start = content.rfind(b"\n", 0, at)
            content[end:end] = content[start:end]
    return bytes(content)


@settings(max_examples=500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutated_files(content):
    read_or_fail(content)
