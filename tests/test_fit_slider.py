"""The spring-slider fit's likelihood: it prefers the law that made a record."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from slipwave.errors import SlipwaveError
from slipwave.events.stick_slip import FEATURES
from slipwave.fit import slider
from slipwave.solver.rate_state import RateState, steady_friction
from slipwave.solver.spring_slider import SpringSlider, simulate_spring_slider

MASS, NORMAL_LOAD = 0.0307, 0.301
TRUTH = np.array([0.01, 0.005, -6.0, 0.35])  # a, b - a, log10 Dc, mu0


@pytest.fixture(scope="module")
def record() -> slider.SliderRecord:
    """Eight seconds of a virtual Colas bench at 1002 N/m and 1.1 mm/s, with sensor noise."""
    law = slider.law_at(TRUTH)
    bench = SpringSlider(mass=MASS, stiffness=1002.0, drive_speed=1.1e-3,
                         normal_load=NORMAL_LOAD)
    made = simulate_spring_slider(bench, law, duration=10.0, sample_rate=2000.0,
                                  initial_ratio=float(steady_friction(law, 1.1e-3)) - 1e-3)
    kept = made.sel(time=slice(2.0, None))
    noisy = kept.friction_ratio.values + np.random.default_rng(7).normal(0, 0.003, kept.time.size)
    ds = xr.Dataset({"friction_ratio": ("time", noisy)},
                    coords={"time": kept.time.values - kept.time.values[0]})
    return slider.slider_record("virtual", ds, stiffness=1002.0, drive_speed=1.1e-3,
                                mass=MASS, normal_load=NORMAL_LOAD, window=1.0)


def test_a_record_is_read_into_windows(record: slider.SliderRecord) -> None:
    assert record.windows == 8
    assert len(record.observed) == len(FEATURES)
    assert record.noise == pytest.approx(0.003, rel=0.15)
    assert record.regime in ("stick-slip", "mixed", "sliding")
    law = slider.law_at(TRUTH)
    assert (law.a, law.b, law.dc, law.mu0) == pytest.approx((0.01, 0.015, 1e-6, 0.35))


def test_the_likelihood_prefers_the_law_that_made_the_record(
        record: slider.SliderRecord) -> None:
    at_truth = slider.loglik([record], TRUTH, members=4, seed=3)
    for change in ([0.0, 0.0, 0.0, 0.05], [0.01, 0.0, 0.0, 0.0], [0.0, 0.0, 0.7, 0.0],
                   [0.0, 0.005, 0.0, 0.0]):
        assert slider.loglik([record], TRUTH + np.array(change), members=4, seed=3) < at_truth


def test_the_prediction_of_a_record_says_what_it_measured(
        record: slider.SliderRecord) -> None:
    samples = TRUTH + np.random.default_rng(0).normal(0.0, 1e-4, (10, 4))
    posterior = slider.SliderPosterior(samples, samples, np.zeros(10), ("virtual",))
    predicted = slider.predict_record(record, posterior, draws=3, members=3, seed=1)
    for name in ("drop", "recurrence", "stuck_share"):
        entry = predicted[name]
        assert entry["low"] <= entry["predicted"] <= entry["high"]  # type: ignore[index]
        assert entry["inside"]  # type: ignore[index]
    assert predicted["regime"]["predicted"] == record.regime  # type: ignore[index]
    interval = posterior.interval()
    assert interval["dc"][0] == pytest.approx(1e-6, rel=0.01)
    assert interval["b"][0] == pytest.approx(0.015, abs=1e-3)


def test_a_record_shorter_than_a_window_is_refused() -> None:
    bench = SpringSlider(mass=MASS, stiffness=168.0, drive_speed=42e-6, normal_load=NORMAL_LOAD)
    time = np.arange(0.0, 1.0, 1 / 2000)
    with pytest.raises(SlipwaveError, match="no window of 10 s"):
        slider.window_vectors(time, 0.3 + 0 * time, bench, 10.0)


def test_a_law_the_integrator_cannot_follow_costs_nothing_but_its_likelihood(
        record: slider.SliderRecord, monkeypatch: pytest.MonkeyPatch) -> None:
    def failing(*args: object, **kwargs: object) -> None:
        raise SlipwaveError("integration failed")
    monkeypatch.setattr(slider, "simulate_spring_slider", failing)
    members = slider.simulated_windows(record, RateState(a=0.01, b=0.02, dc=1e-6, mu0=0.4),
                                       4, 0)
    assert np.isnan(members).all()
    assert slider.record_loglik(record, members) == float("-inf")


def test_a_two_state_posterior_keeps_its_second_state() -> None:
    box = slider.prior_box(2)
    assert box.shape == (6, 2) and len(slider.parameters(2)) == 6
    law = slider.law_at(np.array([0.01, 0.005, -6.0, 0.35, -0.004, -4.5]))
    assert law.b2 == -0.004 and law.dc2 == pytest.approx(10**-4.5)
    samples = box[:, 0] + np.random.default_rng(3).random((50, 6)) * np.diff(box, axis=1)[:, 0]
    samples[:, 1] = np.abs(samples[:, 1])  # b >= 0
    posterior = slider.SliderPosterior(samples, samples[:8], np.zeros(8), ("x",))
    settings = slider.SliderFitSettings(states=2)
    back = slider.posterior_of(slider.posterior_dataset(posterior, settings, 1.0))
    assert back.states == 2
    np.testing.assert_array_equal(back.samples, samples)
    interval = back.interval()
    assert box[4, 0] <= interval["b2"][1] <= interval["b2"][0] <= interval["b2"][2] <= box[4, 1]
    assert 10 ** box[5, 0] <= interval["dc2"][1] < interval["dc2"][2] <= 10 ** box[5, 1]
    assert slider._inside(samples).all() and not slider._inside(samples[:, :4] * 10).any()


def test_a_two_state_search_starts_where_the_one_state_fit_ended(
        record: slider.SliderRecord) -> None:
    points = TRUTH + np.random.default_rng(4).normal(0.0, 1e-3, (10, 4))
    logliks = -np.arange(10.0)[::-1]  # the last four the best
    one_state = slider.SliderPosterior(points, points, logliks, ("virtual",))
    start = slider.nested_start(one_state)
    assert start.shape == (slider.NESTED_START_GUESSES, 6)
    np.testing.assert_array_equal(start[:, :4], points[-4:])
    assert (start[:, 4] == 0.0).all() and slider._inside(start).all()
    # with b2 = 0 the two-state law is the one-state law: the same likelihood, but for the
    # integrator's steps over one more variable
    assert slider.loglik([record], start[-1], members=3, seed=2) == pytest.approx(
        slider.loglik([record], points[-1], members=3, seed=2), abs=0.01)
    with pytest.raises(SlipwaveError, match="starts from a one-state fit"):
        slider.nested_start(slider.SliderPosterior(start, start, np.zeros(4), ("x",)))


def test_a_cutoff_law_is_searched_kept_and_started_from_one_state(
        record: slider.SliderRecord, tmp_path: Path) -> None:
    assert slider.parameters(1, cutoff=True)[-1] == "log10_vc"
    assert slider.law_shape(5) == (1, True) and slider.law_shape(7) == (2, True)
    law = slider.law_at(np.array([0.01, 0.005, -6.0, 0.35, -3.0]))
    assert law.cutoff_speed == pytest.approx(1e-3) and law.dc2 is None
    box = slider.prior_box(1, cutoff=True)
    samples = box[:, 0] + np.random.default_rng(5).random((40, 5)) * np.diff(box, axis=1)[:, 0]
    samples[:, 1] = np.abs(samples[:, 1])
    posterior = slider.SliderPosterior(samples, samples[:6], np.zeros(6), ("x",))
    slider.posterior_dataset(posterior, slider.SliderFitSettings(cutoff=True), 1.0).to_netcdf(
        tmp_path / "posterior.nc")
    back = slider.posterior_of(xr.load_dataset(tmp_path / "posterior.nc"))
    assert back.cutoff and back.states == 1
    low, high = 10.0 ** box[4]
    assert low <= back.interval()["cutoff_speed"][1] < back.interval()["cutoff_speed"][2] <= high
    # started from a one-state fit at the prior's top speed, the cut-off changes the
    # likelihood by little (b's effect lowered by under 1 % in this record's slips)
    points = TRUTH + np.random.default_rng(4).normal(0.0, 1e-3, (10, 4))
    one_state = slider.SliderPosterior(points, points, -np.arange(10.0)[::-1], ("virtual",))
    start = slider.nested_start(one_state, states=1, cutoff=True)
    assert start.shape == (slider.NESTED_START_GUESSES, 5) and slider._inside(start).all()
    nested = slider.loglik([record], start[-1], members=3, seed=2)
    plain = slider.loglik([record], points[-1], members=3, seed=2)
    assert nested == pytest.approx(plain, abs=0.5)
    # a cut-off at the slowest bound leaves no stick-slip: far less likely
    slow = start[-1].copy()
    slow[4] = box[4, 0]
    assert slider.loglik([record], slow, members=3, seed=2) < plain - 10.0
    with pytest.raises(SlipwaveError, match="nothing to nest"):
        slider.nested_start(one_state, states=1, cutoff=False)
