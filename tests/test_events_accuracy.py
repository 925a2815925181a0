"""Event detection against the virtual bench's truth: seeds, noise levels, both CSV flavours.

The three tests of the default campaign (H/L = 0.5, 0.25, 0.75) are simulated
once; each is then recorded again through the bench's sensors with other
noise seeds and with twice and three times the sensor noise, and read back
from the vendor-flavour CSV. Scores are pooled over all recordings.

A truth event is expected to be found when it is visible (the bench's own
mark: a gross slip or a T drop of at least 0.5 N) and its drop is at least
10 times the T noise; a detection is right when it falls on any truth event
of its kind (a found micro-slip below the mark is not a false alarm).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from slipwave.bench.generate import BenchResult, load_tests, simulate_test
from slipwave.bench.sensors import DEFAULT_SENSORS, apply_sensors
from slipwave.events import detect_events
from slipwave.fit import edge_threshold
from slipwave.io import read_acquisition, write_acquisition
from slipwave.solver.signals import clean_signals

pytestmark = pytest.mark.slow  # whole virtual-bench tests: make test-fast leaves them out

ROOT = Path(__file__).parents[1]
MATCH = 0.1  # s: a detection belongs to the truth event whose onset is this close
SEEDS = (11, 12, 13)
NOISE_SCALES = (1.0, 2.0, 3.0)
CONVENTIONS = ("x_axis", "outward")  # edge sensors along +x, or each reading outward


@pytest.fixture(scope="module")
def campaign() -> dict[str, tuple[BenchResult, float]]:
    """Each default test's simulation and its gross/partial threshold, read off its slips."""
    config = yaml.safe_load((ROOT / "raw_data/bench/campaign.yaml").read_text())
    tests = {}
    for spec in load_tests(config):
        spec = dataclasses.replace(spec, video="none")
        result = simulate_test(spec, seed=0)
        tests[spec.test_id] = (result, edge_threshold(result.simulation))
    return tests


def _record(result: BenchResult, seed: int, scale: float, convention: str):
    spec = result.spec
    clean = clean_signals(result.simulation, speed=spec.speed, loading_time=spec.loading_time,
                          duration=spec.duration, sample_rate=spec.sample_rate,
                          wave_speed=spec.wave_speed)
    sensors = {name: dataclasses.replace(sensor, noise=scale * sensor.noise)
               for name, sensor in DEFAULT_SENSORS.items()}
    recording = apply_sensors(clean, sensors, seed=seed)
    if convention == "outward":  # its twin: the left sensor reads its edge's outward motion
        recording["DG"] = recording["DG"].copy(data=-recording["DG"].values)
    return recording


def _score(detected: pd.DataFrame, truth: pd.DataFrame, noise: float) -> pd.DataFrame:
    """One row per detection and per expected truth event, with what matched."""
    rows = []
    expected = truth[truth["visible"] & (truth["drop"] >= 10 * noise)]
    for _, event in detected.iterrows():
        gap = np.abs(truth["t_start"].to_numpy() - event["t_start"])
        nearest = truth.iloc[int(np.argmin(gap))]
        rows.append({"role": "detection", "kind": event["kind"],
                     "right": bool(gap.min() <= MATCH and nearest["kind"] == event["kind"])})
    for _, event in expected.iterrows():
        gap = np.abs(detected["t_start"].to_numpy() - event["t_start"]) if len(detected) \
            else np.array([np.inf])
        k = int(np.argmin(gap))
        found = bool(gap[k] <= MATCH and detected["kind"].iloc[k] == event["kind"])
        rows.append({
            "role": "truth", "kind": event["kind"], "right": found,
            "onset_error": abs(detected["t_start"].iloc[k] - event["t_start"]) if found
            else np.nan,
            "ratio_error": abs(detected["ratio_before"].iloc[k] / event["ratio_before"] - 1)
            if found else np.nan,
        })
    return pd.DataFrame(rows)


@pytest.fixture(scope="module")
def scores(campaign, tmp_path_factory) -> pd.DataFrame:
    parts = []
    folder = tmp_path_factory.mktemp("vendor")
    for test_id, (result, ratio) in campaign.items():
        for seed in SEEDS:
            for scale in NOISE_SCALES:
                for convention in CONVENTIONS:  # each recording and its twin, found by auto
                    recording = _record(result, seed, scale, convention)
                    if seed == SEEDS[0]:  # through the vendor CSV (kN, decimal comma, ...)
                        path = write_acquisition(
                            recording, folder / f"{test_id}_{scale}_{convention}.csv",
                            flavour="vendor")
                        recording = read_acquisition(path)
                    detected = detect_events(recording, gross_edge_ratio=ratio)
                    assert detected.attrs["edge_convention"] == convention
                    score = _score(detected, result.events, scale * DEFAULT_SENSORS["T"].noise)
                    parts.append(score.assign(test_id=test_id, seed=seed, scale=scale,
                                              convention=convention,
                                              detected=",".join(detected["kind"])))
    return pd.concat(parts, ignore_index=True)


def _rates(scores: pd.DataFrame, kind: str) -> tuple[float, float]:
    detections = scores[(scores["role"] == "detection") & (scores["kind"] == kind)]
    truths = scores[(scores["role"] == "truth") & (scores["kind"] == kind)]
    return float(detections["right"].mean()), float(truths["right"].mean())


def test_gross_slips_precision_and_recall(scores):
    precision, recall = _rates(scores, "gross_slip")
    assert (scores["kind"] == "gross_slip").sum() > 400  # 55 gross slips x 27 recordings
    assert precision >= 0.98, precision
    assert recall >= 0.98, recall


def test_partial_slips_precision_and_recall(scores):
    precision, recall = _rates(scores, "partial_slip")
    assert precision >= 0.90, precision
    assert recall >= 0.90, recall


def test_onsets_within_two_samples(scores):
    """Every gross slip, and every partial slip at the bench's own noise level.

    At two and three times that noise the smallest partial slips (T rising at
    ~1.9 N/s, then falling at ~2.5 N/s, under 0.08-0.12 N of noise) have
    kinks that noise moves by a few samples: there 95 % must be within 2.
    """
    found = scores[(scores["role"] == "truth") & scores["right"]]
    within = found["onset_error"] <= 2 * 0.01 + 1e-9  # the bench samples at 100 Hz
    gross = found["kind"] == "gross_slip"
    assert within[gross].all(), found[gross & ~within]
    own_noise = found["scale"] == 1.0
    assert within[~gross & own_noise].all(), found[~gross & own_noise & ~within]
    assert within[~gross & ~own_noise].mean() >= 0.95


def test_static_ratio_at_gross_slips_within_one_percent(scores):
    gross = scores[(scores["role"] == "truth") & (scores["kind"] == "gross_slip")
                   & scores["right"]]
    # The sensors' gain errors alone make 0.70 %. Since gross slips are located at their
    # onset inside a load step (issue 15), the rise before one can be a short step,
    # whose peak the samples catch less well: two gross slips of the 1042 scored are
    # above 1 %, at most 1.002 %.
    assert (gross["ratio_error"] <= 0.01).mean() >= 0.995, gross["ratio_error"].max()
    assert gross["ratio_error"].max() <= 0.0105, gross["ratio_error"].max()


def test_the_vendor_flavour_scores_like_the_canonical(scores):
    vendor = scores[scores["seed"] == SEEDS[0]]
    for kind in ("gross_slip", "partial_slip"):
        precision, recall = _rates(vendor, kind)
        assert min(precision, recall) >= 0.9



@pytest.mark.parametrize("convention", CONVENTIONS)
def test_each_edge_convention_scores_alike(scores, convention):
    """Outward sensors (the paper's bench) are found from the data and classify as +x ones."""
    chosen = scores[scores["convention"] == convention]
    assert min(_rates(chosen, "gross_slip")) >= 0.98
    assert min(_rates(chosen, "partial_slip")) >= 0.90
    # each outward recording gives exactly the kinds of its +x twin
    twins = scores.groupby(["test_id", "seed", "scale", "convention"])["detected"].first()
    assert (twins.xs("x_axis", level="convention")
            == twins.xs("outward", level="convention")).all()
