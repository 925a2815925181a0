"""detect_events, phases, friction ratios and their files, on recordings with known truth."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from scipy import stats

from slipwave.bench.generate import BenchTest, simulate_test
from slipwave.bench.sawtooth import SawtoothBench, sawtooth_events, sawtooth_recording
from slipwave.cli import main
from slipwave.errors import SlipwaveError
from slipwave.events import (
    EVENT_COLUMNS,
    classify_events,
    detect_events,
    events_dataset,
    friction_ratio,
    phase_labels,
    segment_phases,
    wave_counts,
)
from slipwave.io import read_acquisition, read_dataset, write_dataset

ROOT = Path(__file__).parents[1]
BENCH = ROOT / "raw_data" / "bench"


@pytest.fixture(scope="module")
def saw():
    bench = SawtoothBench()
    return sawtooth_recording(bench, seed=3), sawtooth_events(bench)


@pytest.fixture(scope="module")
def hl050():
    return read_acquisition(BENCH / "hl050.csv")


def test_sawtooth_events_and_their_kinds(saw):
    recording, truth = saw
    events = detect_events(recording)
    assert list(events.columns) == list(EVENT_COLUMNS)
    assert len(events) == len(truth)
    assert np.abs(events["t_start"].to_numpy() - truth["t_start"].to_numpy()).max() < 0.03
    assert events["kind"].tolist() == truth["kind"].tolist()
    assert events.attrs["warnings"] == ""
    assert (events["ratio_before"] > events["ratio_after"]).all()


def test_without_edges_the_drops_remain_with_a_warning(saw):
    recording, truth = saw
    events = detect_events(recording.drop_vars(["DG", "DD"]))
    assert len(events) == len(truth)
    assert set(events["kind"]) == {"unclassified"}
    assert "no usable DG or DD channel" in events.attrs["warnings"]
    assert events["DG_jump"].isna().all()
    assert wave_counts(events) == {"partial_slip": 0, "gross_slip": 0,
                                   "unclassified": len(truth)}
    nan_right = recording.copy()
    nan_right["DD"] = nan_right["DD"] * np.nan  # a dead sensor reads NaN throughout
    events = detect_events(nan_right)
    assert "no usable DD channel" in events.attrs["warnings"]
    assert set(events["kind"]) == {"unclassified"}


def test_dead_or_flat_load_channels(saw):
    recording, _ = saw
    dead = recording.assign(T=recording["T"] * np.nan)
    dead.attrs["source"] = "raw/test7.csv"
    with pytest.raises(SlipwaveError, match=r"raw/test7.csv: channel T is missing or has no "
                                            r"finite value"):
        detect_events(dead)
    force_only = detect_events(recording.drop_vars(["N", "DG", "DD"]))  # a T-only record
    assert len(force_only) > 0 and set(force_only["kind"]) == {"unclassified"}
    assert force_only["ratio_before"].isna().all()
    assert "no usable N channel" in force_only.attrs["warnings"]
    phase = phase_labels(segment_phases(recording.drop_vars(["N", "DG", "DD"]), force_only))
    assert "normal_loading" not in phase and "partial_slip" not in phase
    assert (phase == "unclassified_slip").sum() > 0
    flat = detect_events(recording.assign(T=recording["T"] * 0 + 12.0))
    assert flat.empty and list(flat.columns) == list(EVENT_COLUMNS)
    phase = segment_phases(recording, flat)
    assert set(phase_labels(phase)) == {"normal_loading", "stick"}


def test_classification_rule():
    drops = pd.DataFrame({"t_start": [1.0, 2.0, 3.0, 4.0], "t_end": [1.3, 2.3, 3.3, 4.3]})
    drops.attrs["sample_interval"] = 0.01
    dg = pd.DataFrame({"t_start": [1.0, 2.0, 3.2, 4.05], "t_end": [1.3, 2.3, 3.3, 4.3],
                       "jump": [-0.2, -0.05, -0.1, 0.03],
                       "significant": [True, True, True, True]})
    dd = pd.DataFrame({"t_start": [1.0, 2.0, 3.0, 4.0], "t_end": [1.3, 2.3, 3.3, 4.3],
                       "jump": [-0.15, -0.1, -0.1, -0.08],
                       "significant": [True, True, True, True]})
    table = classify_events(drops, {"DG": dg, "DD": dd})
    # same way and at least 0.9 times as far: gross; less far or the other way: partial
    assert table["kind"].tolist() == ["gross_slip", "partial_slip", "gross_slip",
                                      "partial_slip"]
    # the left edge moved 0.2 s after the right one: the wave ran right to left (0.05 s
    # is less than a quarter of the drop: unresolved)
    assert table["direction"].tolist() == ["unresolved", "unresolved", "right_to_left",
                                           "unresolved"]
    assert classify_events(drops, {"DG": dg, "DD": dd}, gross_edge_ratio=1.5)[
        "kind"].tolist() == ["partial_slip"] * 4
    quiet = dg.assign(significant=False)
    assert set(classify_events(drops, {"DG": quiet, "DD": dd})["kind"]) == {"partial_slip"}


def test_phases_match_the_bench_truth(hl050):
    events = detect_events(hl050)
    phase = phase_labels(segment_phases(hl050, events))
    truth = pd.read_csv(BENCH / "truth" / "hl050_phases.csv")["phase"].to_numpy()
    assert phase.size == truth.size
    assert (phase == truth).mean() > 0.995
    for label in ("normal_loading", "stick", "partial_slip", "gross_slip"):
        assert ((phase == label) == (truth == label)).mean() > 0.995


def test_friction_ratio_statistics():
    events = pd.DataFrame({"kind": ["gross_slip"] * 4 + ["partial_slip"],
                           "t_start": [1.0, 2.0, 3.0, 4.0, 5.0],
                           "ratio_before": [0.95, 1.05, 1.0, 1.1, 0.4],
                           "ratio_after": [0.6, 0.62, 0.61, 0.63, 0.39]})
    ratio = friction_ratio(events, confidence=0.9)
    static = np.array([0.95, 1.05, 1.0, 1.1])
    half = stats.t.ppf(0.95, 3) * static.std(ddof=1) / 2
    assert ratio.sizes["slip"] == 4
    assert float(ratio["static_mean"]) == pytest.approx(static.mean())
    assert float(ratio["static_std"]) == pytest.approx(static.std(ddof=1))
    assert float(ratio["static_ci_high"]) == pytest.approx(static.mean() + half)
    assert float(ratio["dynamic_mean"]) == pytest.approx(0.615)
    assert ratio["static"].attrs["units"] == "1"
    none = friction_ratio(events[events["kind"] == "partial_slip"])
    assert none.sizes["slip"] == 0 and np.isnan(float(none["static_mean"]))


def test_events_dataset_round_trip(hl050, tmp_path):
    events = detect_events(hl050)
    dataset = events_dataset(events, segment_phases(hl050, events))
    path = write_dataset(dataset, tmp_path / "events.nc")
    back = read_dataset(path)
    assert back.sizes["event"] == len(events)
    assert back["ratio_before"].attrs["units"] == "1"
    assert back["t_start"].attrs["units"] == "s"
    assert back.attrs["gross_slip"] == 9  # the truth: raw_data/bench/truth
    assert back["kind"].values.tolist() == events["kind"].tolist()
    xr.testing.assert_equal(back["phase"], dataset["phase"])


def test_command_line_detect_summary_report(tmp_path, capsys):
    recording = tmp_path / "hl050.nc"
    assert main(["ingest", str(BENCH / "hl050.csv"), "-o", str(recording),
                 "--test-id", "hl050"]) == 0
    events_csv, events_nc = tmp_path / "events.csv", tmp_path / "events.nc"
    assert main(["detect", str(recording), "-o", str(events_csv), "--netcdf",
                 str(events_nc)]) == 0
    assert "32 events (23 partial_slip, 9 gross_slip)" in capsys.readouterr().out
    table = pd.read_csv(events_csv, comment="#")
    assert list(table.columns) == list(EVENT_COLUMNS) and len(table) == 32
    summary = tmp_path / "summary.csv"
    assert main(["summary", str(events_nc), "-o", str(summary)]) == 0
    row = pd.read_csv(summary).iloc[0]
    assert row["test_id"] == "hl050"
    assert row["gross_slip_waves"] == 9 and row["partial_slip_waves"] == 23
    assert row["static_ratio_ci_low"] < row["static_ratio_mean"] < row["static_ratio_ci_high"]
    assert row["normal_loading_s"] == pytest.approx(10.0, abs=0.3)
    page = tmp_path / "page.html"
    assert main(["report", str(recording), "--events", str(events_nc), "-o", str(page)]) == 0
    html = page.read_text()
    assert "23 partial slip, 9 gross slip" in html and "T/|N| at gross slips" in html


def test_command_line_detect_on_a_bad_file_fails_cleanly(tmp_path, capsys):
    bad = tmp_path / "nothing.nc"
    write_dataset(xr.Dataset({"T": ("time", [np.nan] * 10), "N": ("time", [-1.0] * 10)},
                             coords={"time": np.arange(10.0)},
                             attrs={"source": "x.csv", "product": "recording"}), bad)
    assert main(["detect", str(bad), "-o", str(tmp_path / "e.csv")]) == 1
    assert "x.csv: channel T is missing or has no finite value" in capsys.readouterr().err
    assert not (tmp_path / "e.csv").exists()


def test_edge_convention_found_given_or_warned(saw, tmp_path):
    recording, _ = saw
    found = detect_events(recording)
    assert found.attrs["edge_convention"] == "x_axis"
    assert found.attrs["edge_convention_evidence"].startswith("measured: DG rose with T over")
    outward = recording.assign(DG=-recording["DG"])
    twin = detect_events(outward)
    assert twin.attrs["edge_convention"] == "outward"
    assert twin["kind"].tolist() == found["kind"].tolist()
    np.testing.assert_allclose(twin["DG_jump"], found["DG_jump"])  # always along +x
    # told, it is not measured: an outward reading taken as +x classifies otherwise
    told = detect_events(outward, edge_convention="x_axis")
    assert told.attrs["edge_convention_evidence"] == "given"
    assert told["kind"].tolist() != found["kind"].tolist()
    # DG that does not follow T cannot tell: +x assumed, with a warning
    rng = np.random.default_rng(0)
    blind = recording.assign(DG=("time", rng.normal(0, 1e-4, recording.sizes["time"])))
    assumed = detect_events(blind)
    assert assumed.attrs["edge_convention"] == "x_axis"
    assert "convention cannot be told from the data" in assumed.attrs["warnings"]
    stored = events_dataset(twin, segment_phases(outward, twin))
    write_dataset(stored, tmp_path / "events.nc")
    assert read_dataset(tmp_path / "events.nc").attrs["edge_convention"] == "outward"


def test_the_bench_writes_outward_edge_sensors():
    spec = BenchTest("out", elements=40, duration=80.0, video="none", edge_convention="outward")
    result = simulate_test(spec, seed=2)
    events = detect_events(result.recording)
    assert events.attrs["edge_convention"] == "outward"
    twin = simulate_test(dataclasses.replace(spec, edge_convention="x_axis"), seed=2)
    assert detect_events(twin.recording)["kind"].tolist() == events["kind"].tolist()
    assert (events["kind"] == "gross_slip").sum() >= 1
