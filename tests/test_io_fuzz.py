"""Random and mutated files: each reader returns what it promises or raises SlipwaveError.

The acquisition reader, the campaign table's reader and checks, and the fit.json reader,
whose content the simulate, compare, fits and report stages then use: a fit it accepts
must be one they can use.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fuzzing import (
    csv_like_text,
    mutated_csv,
    mutated_fit,
    mutated_table,
    table_like_text,
    use_fit,
    valid_fit,
)
from slipwave.campaign import check_campaign, read_campaign
from slipwave.errors import SlipwaveError
from slipwave.fit import read_fit
from slipwave.io import read_acquisition

TABLE_SCHEMA = json.loads(
    (Path(__file__).parents[1] / "src/slipwave/schemas/tests.schema.json").read_text())
_folder = Path(tempfile.mkdtemp(prefix="slipwave-fuzz-"))


def read_or_fail(content: bytes) -> None:
    path = _folder / "fuzz.csv"
    path.write_bytes(content)
    try:
        result = read_acquisition(path)
    except SlipwaveError:
        return
    # what is read is a recording: its time rises, each channel is as long as it
    time = result["time"].values
    assert time.size > 0 and np.all(np.diff(time) > 0)
    assert all(result[name].shape == time.shape for name in result.data_vars)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=400))
def test_random_bytes(content):
    read_or_fail(content)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(csv_like_text)
def test_random_csv_like_text(text):
    read_or_fail(text.encode("utf-8"))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_csv())
def test_mutated_files(content):
    read_or_fail(content)


def read_table_or_fail(content: bytes) -> None:
    path = _folder / "fuzz.tsv"
    path.write_bytes(content)
    config = {"detection": {"gross_edge_ratio": 0.9}, "column_maps": {"labview_en": {"a": "T"}}}
    try:
        check_campaign(config, read_campaign(path), TABLE_SCHEMA)
    except SlipwaveError:
        return


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_table())
def test_mutated_campaign_tables(content):
    read_table_or_fail(content)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(table_like_text)
def test_random_campaign_tables(text):
    read_table_or_fail(text.encode("utf-8"))


def read_fit_or_fail(content: bytes) -> None:
    path = _folder / "fit.json"
    path.write_bytes(content)
    try:
        fit = read_fit(path)
    except SlipwaveError:
        return
    use_fit(fit)  # what the reader accepts, the stages can use


def test_the_valid_fit_is_read():
    path = _folder / "valid.json"
    path.write_text(json.dumps(valid_fit()))
    assert read_fit(path)["chosen"] == "coulomb"


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_fit())
def test_mutated_fit_json(content):
    read_fit_or_fail(json.dumps(content).encode("utf-8"))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_damaged_fit_json_text(data):
    text = json.dumps(valid_fit(), indent=2).encode("utf-8")
    cut = data.draw(st.integers(0, len(text)))
    noise = data.draw(st.binary(max_size=8))
    read_fit_or_fail(text[:cut] + noise + text[cut + len(noise):])
