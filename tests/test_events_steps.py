"""Load drops and edge jumps of single signals: noise, spikes, drift, oscillations, gaps."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from slipwave.errors import SlipwaveError
from slipwave.events import STEP_COLUMNS, despike, edge_jumps, load_drops, noise_level

RATE = 100.0


def sawtooth(kinks, drops, fall, *, size=20000, rise=0.02, noise=0.04, seed=0):
    """Ramp at ``rise`` per sample, falling by ``drops[k]`` over ``fall`` samples at ``kinks[k]``.

    The ramp goes on during the fall, so the signal falls by ``drops[k] - rise * fall``.
    Kinks fall between samples (at k + 0.3); the true onset sample is the kink's floor.
    """
    i = np.arange(size, dtype=float)
    clean = rise * i
    for kink, drop in zip(kinks, drops, strict=True):
        clean -= drop * np.clip((i - kink) / fall, 0.0, 1.0)
    rng = np.random.default_rng(seed)
    return i / RATE, clean + rng.normal(0.0, noise, size)


def test_noise_level_ignores_ramps_steps_and_spikes():
    _, load = sawtooth([5000.3, 12000.3], [8.0, 5.0], 20)
    load[::997] += 30.0
    assert noise_level(load) == pytest.approx(0.04, rel=0.05)


def test_noise_level_of_a_quantised_signal_is_not_zero():
    rng = np.random.default_rng(1)
    quantised = np.round(rng.normal(0.0, 0.3, 10000))  # mostly equal neighbours
    assert 0.1 < noise_level(quantised) < 0.6
    assert noise_level(np.full(100, 2.0)) == 0.0


def test_despike_removes_short_spikes_of_any_height():
    values = np.zeros(50)
    values[[7, 21, 22]] = [1e6, -1e6, -1e6]
    assert np.all(despike(values, max_spike=2) == 0.0)


def test_onsets_on_the_last_sample_of_the_ramp():
    kinks = [3000.3, 7000.3, 11000.3, 15000.3]
    # net falls of 6.2, 1.2, 12.2 and 1.0 over 20 samples: the last at 2.5 times the ramp's rate
    time, load = sawtooth(kinks, [6.6, 1.6, 12.6, 1.4], 20)
    drops = load_drops(time, load)
    assert list(drops.columns) == list(STEP_COLUMNS)
    assert np.abs(drops["i_start"].to_numpy() - np.floor(kinks)).max() <= 2
    assert np.abs(drops["i_end"].to_numpy() - np.ceil(np.add(kinks, 20))).max() <= 2
    assert drops["drop"].to_numpy() == pytest.approx([6.2, 1.2, 12.2, 1.0], abs=0.1)
    assert drops.attrs["noise"] == pytest.approx(0.04, rel=0.05)


@pytest.mark.parametrize("height", [0.5, 5.0, 500.0])
def test_spikes_are_not_drops_whatever_their_height(height):
    rng = np.random.default_rng(2)
    time, load = sawtooth([], [], 1, size=30000)
    where = rng.choice(30000, 60, replace=False)
    load[where] -= height
    load[where[:20] + 1] -= height  # some two samples wide
    assert load_drops(time, load).empty


def test_white_noise_drift_and_an_oscillation_make_no_drop():
    time = np.arange(100000) / RATE
    rng = np.random.default_rng(3)
    assert load_drops(time, rng.normal(0, 1, time.size)).empty
    assert load_drops(time, 5 - 0.01 * time + rng.normal(0, 0.04, time.size)).empty
    wave = 3.0 * np.sin(2 * np.pi * time / 7.0) + rng.normal(0, 0.04, time.size)
    assert load_drops(time, wave).empty


def test_creep_before_slip_does_not_move_the_onset():
    """The ramp bends over (creep) for 3 s before the slip: the onset stays at the slip."""
    i = np.arange(20000, dtype=float)
    creep = np.where(i < 9700, 0.02 * i, 0.02 * 9700 + 0.02 * 300 * (1 - np.exp(-(i - 9700)
                                                                                 / 300)))
    clean = np.where(i < 10000.3, creep, creep - 8.0 * np.clip((i - 10000.3) / 15, 0, 1))
    load = clean + np.random.default_rng(4).normal(0, 0.04, i.size)
    drops = load_drops(i / RATE, load)
    assert drops["i_start"].tolist() == pytest.approx([10000], abs=2)


def test_gaps_are_bridged_and_bad_input_is_refused():
    time, load = sawtooth([5000.3], [6.0], 20)
    load[2000:2300] = np.nan
    assert load_drops(time, load)["i_start"].tolist() == pytest.approx([5000], abs=2)
    with pytest.raises(SlipwaveError, match="no finite value"):
        load_drops(time, np.full(time.size, np.nan))
    with pytest.raises(SlipwaveError, match="1-D of one length"):
        load_drops(time[:-1], load)
    constant = load_drops(time, np.full(time.size, 3.0))
    assert constant.empty and list(constant.columns) == list(STEP_COLUMNS)


def test_min_drop_overrides_the_noise_threshold():
    time, load = sawtooth([5000.3, 12000.3], [8.0, 1.0], 20)
    assert len(load_drops(time, load)) == 2
    assert load_drops(time, load, min_drop=3.0)["drop"].round().tolist() == [8.0]


@settings(max_examples=40, deadline=None, derandomize=True)  # the same cases in every run
@given(
    drops=st.lists(st.floats(0.6, 20.0), min_size=1, max_size=5),
    fall=st.integers(1, 40),
    rise=st.floats(0.005, 0.05),
    seed=st.integers(0, 2**16),
)
def test_every_saw_tooth_drop_is_found_at_its_onset(drops, fall, rise, seed):
    """Drops of at least 15 noise levels, falling over 1 to 40 samples, 3 times faster or more.

    Within 2 samples where the fall is at least 3 noise levels a sample steeper than
    the ramp (a kink the noise cannot hide), within 4 otherwise.
    """
    fall = min(fall, int(min(drops) / (3 * rise)) + 1)  # at least 3 times faster than the rise
    kinks = [2000.3 + 3000 * k for k in range(len(drops))]
    time, load = sawtooth(kinks, np.add(drops, rise * fall), fall,
                          size=3000 * len(drops) + 2000, rise=rise, seed=seed)
    found = load_drops(time, load)
    assert len(found) == len(drops)
    error = np.abs(found["i_start"].to_numpy() - np.floor(kinks))
    sharp = np.asarray(drops) / fall + rise >= 3 * 0.04
    assert error[sharp].max(initial=0) <= 2
    assert error.max() <= 4
    assert np.abs(found["drop"].to_numpy() - drops).max() <= 0.15


def test_edge_jumps_of_either_sign_and_across_given_drops():
    time = np.arange(20000) / RATE
    rng = np.random.default_rng(5)
    edge = -0.2 * (time > 50.003) + 0.05 * (time > 120.003) - 0.3 * (time > 170.003)
    edge = edge + rng.normal(0, 0.0015, time.size)
    jumps = edge_jumps(time, edge)
    assert jumps["i_start"].tolist() == pytest.approx([5000, 12000, 17000], abs=2)
    assert jumps["jump"].to_numpy() == pytest.approx([-0.2, 0.05, -0.3], abs=0.005)
    drops = pd.DataFrame({"i_start": [5000, 9000, 17000], "i_end": [5001, 9001, 17001]})
    at = edge_jumps(time, edge, at=drops)
    assert at["significant"].tolist() == [True, False, True]
    assert at["jump"].to_numpy() == pytest.approx([-0.2, 0.0, -0.3], abs=0.005)


@settings(max_examples=40, deadline=None)
@given(st.integers(min_value=4, max_value=60), st.integers(min_value=0, max_value=2**31 - 1))
def test_the_compiled_hinge_is_the_best_two_segment_line(size, seed):
    """Each breakpoint's continuous two-segment line fitted by lstsq: the hinge's is the best."""
    from slipwave.events.steps import _hinge

    rng = np.random.default_rng(seed)
    values = np.cumsum(rng.normal(size=size))
    i = np.arange(size, dtype=float)
    candidates = np.arange(1, size - 2)
    residuals = []
    for k in candidates:
        basis = np.column_stack([np.ones(size), i, np.maximum(i - k, 0.0)])
        fit = np.linalg.lstsq(basis, values, rcond=None)[0]
        residuals.append(float(np.sum((values - basis @ fit) ** 2)))
    best = _hinge(values, candidates)
    assert residuals[best - 1] <= min(residuals) * (1 + 1e-9) + 1e-12
    with pytest.raises(ValueError, match="breakpoints"):
        _hinge(values, np.array([size]))


@settings(max_examples=40, deadline=None)
@given(st.integers(min_value=1, max_value=40), st.integers(min_value=-3, max_value=45),
       st.integers(min_value=0, max_value=2**31 - 1))
def test_the_compiled_line_is_the_least_squares_line(size, at, seed):
    from slipwave.events.steps import _line_at

    values = np.random.default_rng(seed).normal(size=size) + 0.3 * np.arange(size)
    if size < 3:  # too short for a line: the nearest sample
        expected = values[min(max(at, 0), size - 1)]
    else:
        slope, intercept = np.polyfit(np.arange(size, dtype=float), values, 1)
        expected = intercept + slope * at
    assert _line_at(values, at) == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_window_median_skips_non_finite_samples_and_thins_long_windows():
    from slipwave.events.steps import window_median

    values = np.array([5.0, np.nan, 1.0, np.inf, 3.0, 2.0])
    assert window_median(values, 0, 6) == np.median([5.0, 1.0, 3.0, 2.0])  # 2.5
    assert window_median(values, -4, 3) == 3.0  # clipped to the signal: 5 and 1
    assert np.isnan(window_median(values, 1, 2)) and np.isnan(window_median(values, 4, 4))
    long = np.arange(10_001, dtype=float)
    assert window_median(long, 0, long.size) == np.median(long[::10])
