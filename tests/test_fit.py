"""The fit stage: features, thresholds, intervals, and a law recovered from a virtual test."""

from __future__ import annotations

import dataclasses
import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from fuzzing import valid_fit
from slipwave.bench.generate import BenchTest, simulate_test, write_test
from slipwave.cli import main
from slipwave.errors import SlipwaveError
from slipwave.events.detect import DEFAULT_DETECTION
from slipwave.fit import (
    FIRST_SLIP_REACH,
    PARTIAL_DROP_SIGMA,
    RATIO_SIGMA,
    ROUGHNESS_STEP,
    SLIP_SIGMA,
    ZONE_ELEMENTS,
    LawObjective,
    SlipFeatures,
    edge_threshold,
    feature_residuals,
    first_slip_match,
    fit_test,
    law_misfit,
    law_of,
    measured_events,
    misfit_intervals,
    slip_features,
    split_edge_ratios,
)
from slipwave.fits import fits_table
from slipwave.io import read_acquisition
from slipwave.setup import TestSetup, read_test_setup
from slipwave.solver import SolverCache

CELLS = {"youngs_modulus_mpa": "7", "poisson_ratio": "0.48", "edge_reference": "frame"}
TRUTH = {"fs": 0.9, "fd": 0.6}


@pytest.fixture(scope="module")
def virtual(tmp_path_factory):
    """A short Coulomb test on the fit's mesh (80 elements): its files and its truth."""
    spec = BenchTest("v", elements=80, duration=90.0, video="none", fs_final=None, **TRUTH)
    result = simulate_test(spec, seed=5)
    folder = tmp_path_factory.mktemp("virtual")
    paths = write_test(result, folder)
    return result, paths["csv"]


def test_edge_threshold_lies_between_partial_and_gross_slips(virtual):
    result, _ = virtual
    threshold = edge_threshold(result.simulation)
    events = result.events
    ratio = events["DG_jump"] / events["DD_jump"]
    gross = events["kind"] == "gross_slip"
    assert (ratio[gross] >= threshold).all()
    moved = ~gross & (events["DG_jump"].abs() >= 0.2 * events.loc[gross, "DG_jump"].abs().median())
    assert (ratio[moved] < threshold).all()


def test_edge_threshold_needs_a_gross_slip(virtual):
    result, _ = virtual
    quiet = result.simulation.assign(wave=result.simulation["wave"].where(
        result.simulation["wave"] != "gross", "partial"))
    with pytest.raises(SlipwaveError, match="no gross slip"):
        edge_threshold(quiet)


def test_features_classify_by_edges_and_residuals_vanish_on_themselves(virtual):
    result, csv = virtual
    events = measured_events(read_acquisition(csv))
    features = slip_features(events, gross_edge_ratio=edge_threshold(result.simulation),
                             min_drop=0.3, duration=90.0, sample_rate=100.0)
    truth = result.events[result.events["visible"]]
    assert len(features.gross) == (truth["kind"] == "gross_slip").sum()
    assert features.partial_slips == (truth["kind"] == "partial_slip").sum()
    # one gross slip's T/|N| off by 0.03, six times its 0.005: its residual says so, and
    # no other feature moves
    shifted = features.gross.copy()
    shifted.loc[0, "ratio_before"] += 0.03
    moved = feature_residuals(dataclasses.replace(features, gross=shifted), features,
                              calibration_error=0.0)
    assert np.count_nonzero(moved) >= 1 and np.abs(moved).max() > 1.0
    fewer = slip_features(events.iloc[:0], gross_edge_ratio=1.0, min_drop=0.3, duration=90.0,
                          sample_rate=100.0)
    missing = feature_residuals(fewer, features)
    # a gross slip the simulation lacks
    assert missing[0] == pytest.approx(0.1 / np.hypot(RATIO_SIGMA, SLIP_SIGMA))


def _cycle(count: int, period: float, before: float) -> SlipFeatures:
    """Gross slips of one stick-slip cycle, from 20 s, every ``period`` seconds."""
    gross = pd.DataFrame({"t_start": 20.0 + period * np.arange(count),
                          "ratio_before": np.full(count, before),
                          "ratio_after": np.full(count, 0.6), "drop": np.full(count, 8.0)})
    return SlipFeatures(gross, 10, 0.3, 280.0, 100.0)


def test_a_cycle_a_little_off_costs_once_not_per_slip():
    """The law's own cycle: its offset, period and count are judged once each."""
    measured = _cycle(40, 6.0, 0.70)
    # every gross slip 0.01 higher: the cycle's offset, about (0.01 / 0.015)^2
    higher = float(np.sum(feature_residuals(_cycle(40, 6.0, 0.71), measured) ** 2))
    assert 0.3 < higher < 0.6
    # a period 10 % longer, 36 slips instead of 40: a recurrence and a count 10 % off
    # (0.4 sigma each), and the first slip on time; slip by slip it would be hundreds
    longer = feature_residuals(_cycle(36, 6.6, 0.70), measured)
    assert float(np.sum(longer**2)) == pytest.approx(2 * 0.4**2, rel=0.05)


def test_the_partial_slips_size_is_a_feature_as_uncertain_as_the_sequence_makes_it():
    """Partial slips twice as large cost (1 / PARTIAL_DROP_SIGMA)^2 (the measured
    median's own error is small beside it); none costs by their number alone."""
    measured = replace(_cycle(40, 6.0, 0.70), partial_slips=10,
                       partial_drops=np.linspace(1.9, 2.1, 10))
    same = feature_residuals(measured, measured)
    assert same.size == feature_residuals(_cycle(40, 6.0, 0.70), measured).size
    larger = feature_residuals(replace(measured, partial_drops=2.0 * measured.partial_drops),
                               measured)
    assert float(np.sum(larger**2)) == pytest.approx(PARTIAL_DROP_SIGMA**-2, rel=0.05)
    none = feature_residuals(replace(measured, partial_slips=0, partial_drops=np.zeros(0)),
                             measured)
    assert float(np.sum(none**2)) == pytest.approx((10 / 3) ** 2)  # the count's, 10 off 3
    # too few measured partial slips for a median: no such feature
    two = replace(measured, partial_slips=2, partial_drops=np.array([1.0, 3.0]))
    assert feature_residuals(two, two).size == same.size - 1


def test_first_slip_load_rises_steadily_with_fs(tmp_path):
    """The feature that carries fs: T/|N| before the first visible slip (80 elements)."""
    firsts = []
    for fs in (0.8, 0.85, 0.9):
        spec = BenchTest("w", elements=80, duration=90.0, video="none", fs=fs, fd=0.6,
                         fs_final=None)
        recording = read_acquisition(write_test(simulate_test(spec, seed=5),
                                                tmp_path / str(fs))["csv"])
        features = slip_features(measured_events(recording), gross_edge_ratio=1.0,
                                 min_drop=0.3, duration=90.0, sample_rate=100.0)
        assert 0.3 < features.first_ratio < fs and features.first_time > 0
        firsts.append(features.first_ratio)
    slopes = np.diff(firsts) / 0.05
    assert np.all((slopes > 0.9) & (slopes < 1.6))  # at gross slips: up and down with fs


class _FirstSlipObjective:
    """A stand-in for the fit's objective: the first slip at T/|N| 0.1 + slope fs + 0.5 Dc."""

    def __init__(self, target: float, slope: float = 0.6):
        self.measured = SlipFeatures(pd.DataFrame(), 0, 0.3, 90.0, 100.0,
                                     first_time=10.0, first_ratio=target)
        self.slope = slope
        self.features: dict[tuple[float, ...], SlipFeatures] = {}
        self.cache: dict[tuple[float, ...], float] = {}

    def clip(self, theta):
        return tuple(round(float(value), 6) for value in theta)

    def __call__(self, theta):
        key = self.clip(theta)
        first = 0.1 + self.slope * key[0] + 0.5 * key[2]
        self.features[key] = replace(self.measured, first_ratio=first)
        self.cache[key] = ((first - self.measured.first_ratio) / 0.01) ** 2
        return self.cache[key]


def test_a_weakening_start_moves_fs_until_its_first_slip_comes_at_the_tests():
    # the truth: fs 0.9 at Dc 0.1; Coulomb's fs, 1.1, reads it high
    objective = _FirstSlipObjective(target=0.1 + 0.6 * 0.9 + 0.5 * 0.1)
    start = first_slip_match(objective, (1.1, 0.6, 0.1))
    # first step at the nominal slope (1.2, twice the true one) halfway, then the
    # secant of the two runs all the way
    assert [theta[0] for theta in objective.cache] == pytest.approx([1.1, 1.0, 0.9])
    assert start == pytest.approx((0.9, 0.6, 0.1))
    # without a measured first slip there is nothing to match: the start as given
    blind = _FirstSlipObjective(target=float("nan"))
    assert first_slip_match(blind, (1.1, 0.6, 0.1)) == (1.1, 0.6, 0.1)
    assert len(blind.cache) == 1


def test_a_weakening_start_stops_where_its_first_slip_does_not_follow_fs():
    # a first slip nearly blind to fs (slope 0.1: a gross slip where the test's first
    # was partial): one step at the nominal slope, then no wild secant step
    flat = _FirstSlipObjective(target=0.1 + 0.1 * 0.9 + 0.5 * 0.1, slope=0.1)
    assert first_slip_match(flat, (1.1, 0.6, 0.1)) == pytest.approx((1.1 - 0.02 / 1.2, 0.6,
                                                                      0.1))
    assert len(flat.cache) == 2
    # a first slip far above the test's: fs moves by at most FIRST_SLIP_REACH a step
    far = _FirstSlipObjective(target=0.1 + 0.6 * 0.5 + 0.5 * 0.1)
    first_slip_match(far, (1.2, 0.6, 0.1))
    assert [theta[0] for theta in far.cache] == pytest.approx(
        [1.2, 1.2 - FIRST_SLIP_REACH, 1.2 - 2 * FIRST_SLIP_REACH])
    # a match asking for fs at or below fd is not run
    below = _FirstSlipObjective(target=0.1 + 0.6 * 0.5 + 0.5 * 0.1)
    first_slip_match(below, (0.8, 0.6, 0.1))
    assert all(theta[0] > 0.6 for theta in below.cache)


def test_a_partial_slip_moving_the_edges_as_gross_ones_do_sets_no_threshold():
    """hl025's coarse Coulomb fit: gross slips at DG/DD 1.105, one partial at 1.099."""
    ratio = np.array([1.105, 1.105, 1.106, 1.099, -1.32, -1.229, -1.199])
    far = np.array([0.045, 0.045, 0.046, 0.009, 0.022, 0.029, 0.042])
    gross = np.array([True, True, True, False, False, False, False])
    # no partial slip below the gross ones that the edges tell: half their median
    assert split_edge_ratios(ratio, far, gross) == pytest.approx(0.5 * 1.105)
    # a partial slip that the edges do tell (0.8) sets it halfway
    ratio[3] = 0.8
    assert split_edge_ratios(ratio, far, gross) == pytest.approx(np.sqrt(1.105 * 0.8))


def _quadratic_history() -> list[tuple[tuple[float, ...], float]]:
    """80 evaluations of a misfit 20 + ((fs - 1) / 0.01)^2 + ((fd - 0.6) / 0.002)^2."""
    rng = np.random.default_rng(0)
    points = rng.uniform(-1, 1, (80, 2)) * [0.03, 0.006] + [1.0, 0.6]
    misfit = ((points[:, 0] - 1.0) / 0.01) ** 2 + ((points[:, 1] - 0.6) / 0.002) ** 2 + 20.0
    return [(tuple(p), float(m)) for p, m in zip(points, misfit, strict=True)]


def test_intervals_from_curvature_match_a_known_quadratic():
    history = _quadratic_history()
    low, high, method = misfit_intervals(history, (1.0, 0.6), 20.0, 40)
    assert method == "curvature"
    assert 1.0 - low[0] == pytest.approx(high[0] - 1.0, rel=0.03)  # a symmetric quadratic
    # chi-square 20 over 38 degrees of freedom: no scaling; sigma 0.01 and 0.002
    # (the likelihood-ratio region of the evaluations agrees, to their spacing)
    assert high[0] - 1.0 == pytest.approx(1.96 * 0.01, rel=0.03)
    assert high[1] - 0.6 == pytest.approx(1.96 * 0.002, rel=0.03)


def test_intervals_widen_with_the_laws_mismatch_not_its_luckiest_misfit():
    history = _quadratic_history()
    low, high, _ = misfit_intervals(history, (1.0, 0.6), 20.0, 40)
    # neighbours four times the degrees of freedom: every half-width twice as wide
    wide_low, wide_high, _ = misfit_intervals(history, (1.0, 0.6), 20.0, 40, mismatch=4 * 38.0)
    for k, centre in enumerate((1.0, 0.6)):
        assert wide_high[k] - centre == pytest.approx(2 * (high[k] - centre), rel=0.05)
        assert centre - wide_low[k] == pytest.approx(2 * (centre - low[k]), rel=0.05)
    # a mismatch within the noise changes nothing
    assert misfit_intervals(history, (1.0, 0.6), 20.0, 40, mismatch=30.0)[:2] == (low, high)


def test_law_of_names_unknown_laws():
    assert law_of("run-in", {"fs": 0.8, "fd": 0.5, "fs_final": 1.0, "runin_slips": 3}
                  ).static_after(3) == 1.0
    with pytest.raises(SlipwaveError, match="unknown friction law 'stribeck'"):
        law_of("stribeck", {})


@pytest.mark.slow
def test_coulomb_fit_recovers_the_hidden_law_and_its_intervals_hold_it(virtual):
    _, csv = virtual
    recording = read_acquisition(csv)
    setup = read_test_setup(recording, {"test_id": "v", **CELLS})
    events = measured_events(recording)
    fit = fit_test(setup, events, laws=["coulomb"], elements=80, max_evaluations=12)
    law = fit["laws"]["coulomb"]["parameters"]
    for name, truth in TRUTH.items():
        assert law[name]["value"] == pytest.approx(truth, rel=0.02)
        # an interval that says something: narrower than 10 % of the value
        assert law[name]["high"] - law[name]["low"] < 0.1 * law[name]["value"]
    # two gross slips in 90 s: fs is known to a few percent, and its interval says so
    assert law["fs"]["low"] <= TRUTH["fs"] <= law["fs"]["high"]
    assert fit["laws"]["coulomb"]["interval_method"] == "secant"
    # the chosen law refitted at twice the mesh: each parameter's change recorded; fd,
    # read after the gross slips, converges with the mesh under every law (docs "Mesh
    # convergence"); Coulomb's law has no process zone
    finer = fit["mesh_check"]
    assert finer["elements"] == 160 and finer["law"] == "coulomb"
    assert finer["process_zone_mm"] is None and finer["evaluations"] >= 3
    for name, value in law.items():
        refitted = finer["parameters"][name]["value"]
        assert finer["change"][name] == pytest.approx((refitted - value["value"])
                                                      / value["value"], abs=1e-5)
    assert abs(finer["change"]["fd"]) < 0.02
    table = fits_table([fit])
    assert table.loc[0, "law"] == "coulomb" and table.loc[0, "height_ratio"] == 0.5
    assert table.loc[0, "fs_mesh_change"] == finer["change"]["fs"]
    assert TestSetup.from_dict(fit["setup"]).to_dict() == fit["setup"]
    # one law's misfit on its own: the fit's at its optimum, and far worse off it
    fitted = {name: value["value"] for name, value in law.items()}
    misfit = law_misfit(setup, events, "coulomb", fitted, threshold=fit["edge_threshold"],
                        elements=80)
    assert misfit == pytest.approx(fit["laws"]["coulomb"]["misfit"], rel=1e-3, abs=1e-3)
    off = law_misfit(setup, events, "coulomb", {**fitted, "fs": fitted["fs"] + 0.2},
                     threshold=fit["edge_threshold"], elements=80)
    assert off > misfit + 10.0
    # the optimum's neighbours, its coefficients 0.2 % lower and higher, as reported
    nearby = [law_misfit(setup, events, "coulomb",
                         {name: value * scale for name, value in fitted.items()},
                         threshold=fit["edge_threshold"], elements=80)
              for scale in (1 - ROUGHNESS_STEP, 1 + ROUGHNESS_STEP)]
    assert fit["laws"]["coulomb"]["misfit_nearby"] == pytest.approx(nearby, rel=1e-3, abs=1e-3)


@pytest.mark.parametrize("law", ["run-in", "slip-weakening"])
def test_a_law_fitted_without_coulomb_starts_from_its_coulomb_limit(virtual, law):
    _, csv = virtual
    recording = read_acquisition(csv)
    setup = read_test_setup(recording, {"test_id": "v", **CELLS})
    fit = fit_test(setup, measured_events(recording), laws=[law], elements=80,
                   max_evaluations=2, check_mesh=False)
    assert list(fit["laws"]) == [law] and fit["chosen"] == law and fit["mesh_check"] is None
    parameters = fit["laws"][law]["parameters"]
    assert parameters["fd"]["value"] == pytest.approx(TRUTH["fd"], rel=0.05)
    assert len(parameters) == (4 if law == "run-in" else 3)


def test_missing_geometry_is_one_error_naming_the_column_and_nothing_is_written(
        virtual, tmp_path, capsys):
    _, csv = virtual
    lines = [line for line in csv.read_text().splitlines(keepends=True)
             if "height_mm" not in line]
    bare = tmp_path / "bare.csv"
    bare.write_text("".join(lines))
    netcdf, out = tmp_path / "bare.nc", tmp_path / "fit.json"
    assert main(["ingest", str(bare), "-o", str(netcdf)]) == 0
    status = main(["fit", str(netcdf), "-o", str(out), "--setting",
                   *(f"{k}={v}" for k, v in CELLS.items())])
    assert status == 1
    error = capsys.readouterr().err
    assert "add the column height_mm to the campaign table" in error
    assert not out.exists() and set(tmp_path.iterdir()) == {bare, netcdf}


def test_fits_table_reads_every_law(tmp_path):
    fit = {"test_id": "a", "chosen": "run-in", "parameters": {"fs": 1.0},
           "setup": {"height_mm": {"value": 20.0}, "length_mm": {"value": 80.0}},
           "measured": {"gross_slips": 4},
           "laws": {law: {"delta_aic": d, "parameters": {
               name: {"value": 1.0, "low": 0.9, "high": 1.1} for name in names}}
               for (law, names), d in zip({"coulomb": ("fs", "fd"),
                                           "run-in": ("fs", "fd", "fs_final")}.items(),
                                          (12.0, 0.0), strict=True)}}
    table = fits_table([fit])
    assert table.loc[0, "height_ratio"] == 0.25 and table.loc[0, "coulomb_delta_aic"] == 12.0
    assert {"fs", "fd_low", "run_in_fs_final_high"} <= set(table.columns)
    # the command reads a whole fit.json (slipwave.fit.read_fit checks it)
    (tmp_path / "f.json").write_text(json.dumps(valid_fit()))
    assert main(["fits", str(tmp_path / "f.json"), "-o", str(tmp_path / "fits.csv")]) == 0
    assert pd.read_csv(tmp_path / "fits.csv")["law"].tolist() == ["coulomb"]


def test_a_slip_weakening_law_keeps_its_process_zone_resolved_by_the_fit_mesh(virtual):
    """Dc is raised to the shortest whose zone spans ZONE_ELEMENTS elements, no shorter."""
    _, csv = virtual
    recording = read_acquisition(csv)
    setup = read_test_setup(recording, CELLS)
    events = measured_events(recording)
    objective = LawObjective(setup, events, "slip-weakening", 80, 1.0, 0.0,
                             DEFAULT_DETECTION, SolverCache())
    shortest = objective.shortest_dc(0.9, 0.6)
    zone = setup.process_zone(law_of("slip-weakening", {"fs": 0.9, "fd": 0.6, "dc": shortest}))
    assert zone == pytest.approx(ZONE_ELEMENTS * setup["length_mm"] / 80)
    assert objective.clip((0.9, 0.6, shortest / 10))[2] == pytest.approx(shortest, abs=1e-6)
    assert objective.clip((0.9, 0.6, 2 * shortest))[2] == pytest.approx(2 * shortest, abs=1e-6)
    # twice the mesh resolves half the Dc
    finer = LawObjective(setup, events, "slip-weakening", 160, 1.0, 0.0, DEFAULT_DETECTION,
                         SolverCache())
    assert finer.shortest_dc(0.9, 0.6) == pytest.approx(shortest / 2)
