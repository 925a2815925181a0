"""The fit of a filmed test's rate-and-state law: its statistic, likelihood and search."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from slipwave import fit_waves
from slipwave.errors import SlipwaveError
from slipwave.setup import Setting, TestSetup
from slipwave.simulate_waves import rate_state_law, simulate_waves

# A slab of the bench's (H 40 mm, 85 N, 0.048 mm/s) under a law of slow fronts: slips every
# 12-13 s from about 58 s after the drive starts, fronts the camera follows
LAW = {"a": 0.01, "b": 0.04, "dc_um": 80.0, "mu0": 0.9, "v0_um_s": 1.0}
TRUTH = np.array([0.01, 0.03, np.log10(80e-6), 0.9])


def setup_of(duration: float) -> TestSetup:
    values = {"length_mm": 80.0, "height_mm": 40.0, "width_mm": 10.0,
              "youngs_modulus_mpa": 7.0, "poisson_ratio": 0.48, "normal_load_n": 85.0,
              "speed_mm_s": 0.048, "machine_stiffness_n_mm": 40.0, "duration_s": duration,
              "loading_time_s": 10.0}
    return TestSetup("slow", {k: Setting(v, "test") for k, v in values.items()}, "frame")


def card(run: xr.Dataset, setup: TestSetup) -> xr.Dataset:
    from slipwave.solver.signals import quasi_dynamic_signals

    recording = quasi_dynamic_signals(run, loading=setup["loading_time_s"],
                                      duration=setup["duration_s"], sample_rate=100.0)
    recording.attrs["test_id"] = setup.test_id
    return recording


@pytest.fixture(scope="module")
def observed() -> fit_waves.FilmedTest:
    """A test made by the stage at 40 elements (the run kept whole), filmed."""
    setup = setup_of(230.0)
    made = simulate_waves(setup, rate_state_law(LAW), elements=40, field_rate=25.0,
                          sample_rate=100.0, frame_rate=25.0)
    waves = made.waves.assign(t_start_card=made.waves["t_start"])  # the film's clock is the card's
    return fit_waves.filmed_test(setup, card(made.run, setup), waves, frame_rate=25.0)


def test_a_filmed_test_is_cut_into_windows_of_three_recurrences(observed):
    assert observed.windows >= 2
    assert 30.0 < observed.window < 45.0  # three recurrences of 12-13 s
    peak, drop, recurrence = observed.observed
    assert 0.7 < peak < 0.85 and 0.02 < drop < 0.1
    assert np.exp(recurrence) == pytest.approx(observed.window / 3, rel=0.2)
    assert observed.followed >= 2 and 100.0 < np.median(observed.speeds) < 1000.0


@pytest.mark.slow
def test_the_likelihood_prefers_the_law_that_made_the_test(observed):
    # the same mesh and the camera's noise of another seed: the law that made it against
    # one of D_c three times shorter (faster fronts, shorter cycle) and one weakening less
    runs = {name: fit_waves.simulate_guess(observed, fit_waves.law_at(point), elements=40,
                                           members=3, seed=7)
            for name, point in {"truth": TRUTH,
                                "short dc": TRUTH - [0.0, 0.0, np.log10(3.0), 0.0],
                                "less weakening": TRUTH - [0.0, 0.01, 0.0, 0.0]}.items()}
    at = {name: fit_waves.loglik(observed, run) for name, run in runs.items()}
    assert np.isfinite(at["truth"])
    assert at["truth"] > at["short dc"] + 3.0 and at["truth"] > at["less weakening"] + 3.0
    # the emulator's likelihood, given the runs' own features exactly, orders them alike
    emulated = fit_waves.emulated_loglik(observed, fit_waves.RunScatter.of(list(runs.values())),
                                         fit_waves.mesh_error(None, None), members=3)
    features = np.array([fit_waves.run_features(run) for run in runs.values()])
    # a run the camera followed too few waves of has no speed: it stands at the fastest
    # followed, as the emulator takes it where too few runs have one
    features = np.where(np.isnan(features), fit_waves.ABSENT_FEATURES, features)
    truth, short, weaker = emulated(features, np.zeros_like(features))
    assert truth > short + 3.0 and truth > weaker + 3.0


def test_a_failed_run_or_a_run_without_slips_has_no_likelihood(observed):
    assert fit_waves.loglik(observed, None) == -np.inf
    empty = fit_waves.Simulated(np.full((3, 3), np.nan), 0, 0, np.zeros(0))
    assert fit_waves.loglik(observed, empty) == -np.inf


def test_windows_like_the_test_s_score_higher_than_shifted_ones(observed):
    rng = np.random.default_rng(0)
    spread = np.asarray(observed.spread) + 1e-3
    like = np.asarray(observed.observed) + rng.normal(0.0, 1.0, (6, 3)) * spread
    speeds = np.asarray(observed.speeds)
    alike = fit_waves.Simulated(like, observed.waves, observed.followed, speeds)
    higher = fit_waves.Simulated(like + np.array([0.05, 0.0, 0.0]), observed.waves,
                                 observed.followed, speeds)
    faster = fit_waves.Simulated(like, observed.waves, observed.followed, 3.0 * speeds)
    # none followed: taken at the fastest speed the frames follow, far above these
    unfollowed = fit_waves.Simulated(like, observed.waves, 0, np.zeros(0))
    best = fit_waves.loglik(observed, alike)
    for other in (higher, faster, unfollowed):
        assert fit_waves.loglik(observed, other) < best - 5.0


def test_a_test_with_too_few_slips_is_refused_with_its_name():
    setup = setup_of(60.0)
    time = np.arange(0.0, 60.0, 0.01)
    recording = xr.Dataset({"T": ("time", 0.5 * time), "N": ("time", np.full(time.size, -85.0)),
                            "DG": ("time", 0.001 * time), "DD": ("time", 0.001 * time),
                            "DT": ("time", 0.048 * time)}, coords={"time": time},
                           attrs={"test_id": "steady"})
    with pytest.raises(SlipwaveError, match="test 'steady': 0 slips"):
        fit_waves.filmed_test(setup, recording, pd.DataFrame(), frame_rate=25.0)
