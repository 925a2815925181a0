"""A spring-slider record's features: drops, recurrence, stuck share, creep and regime."""

from __future__ import annotations

import numpy as np
import pytest

from slipwave.events import noise_level, without_spikes
from slipwave.events.stick_slip import (
    FEATURES,
    REGIMES,
    lowpass,
    noise_floor,
    regime_of,
    slider_window_features,
)

RATE = 2000.0
BENCH = {"stiffness": 1000.0, "drive_speed": 7.5e-6, "normal_load": 0.3, "mass": 0.03}
LOADING = 1000.0 * 7.5e-6 / 0.3  # K V / N, per second


def _sawtooth(period: float, drop: float, creep_rate: float = 1.0) -> tuple[np.ndarray, ...]:
    """A stuck slider loading at K V / N (slowed to creep_rate of it in the last fifth of
    each rise), slipping by ``drop`` every ``period`` s (within one sample)."""
    time = np.arange(0.0, 20.0, 1 / RATE)
    phase = (time % period) / period
    rise = period * LOADING
    late = np.clip(phase - 0.8, 0.0, None)
    ratio = 0.3 + rise * (np.minimum(phase, 0.8) + creep_rate * late) - drop * (time // period)
    ratio += rise * (time // period) * (0.8 + 0.2 * creep_rate)
    return time, ratio


def test_a_sawtooth_is_stick_slip_with_its_drops_and_period() -> None:
    time, ratio = _sawtooth(period=2.0, drop=0.05)
    features = slider_window_features(time, ratio, **BENCH)
    assert list(features) == list(FEATURES)
    assert features["recurrence"] == pytest.approx(2.0, abs=0.01)
    assert features["drop"] == pytest.approx(0.05, rel=0.1)  # the filter's overshoot
    assert features["stuck_share"] == pytest.approx(9 * 0.05 / (LOADING * 20.0), rel=0.1)
    assert features["creep"] == pytest.approx(1.0, abs=0.05)
    assert regime_of(features["stuck_share"]) == "stick-slip"


def test_creep_before_the_slips_is_measured() -> None:
    time, ratio = _sawtooth(period=2.0, drop=0.05, creep_rate=0.5)
    assert slider_window_features(time, ratio, **BENCH)["creep"] == pytest.approx(0.5, abs=0.1)


def test_steady_sliding_has_no_slip() -> None:
    time = np.arange(0.0, 5.0, 1 / RATE)
    ratio = 0.3 + np.random.default_rng(1).normal(0.0, 0.002, time.size)
    features = slider_window_features(time, ratio, **BENCH)
    assert features["drop"] == 0.0
    assert features["recurrence"] == pytest.approx(time[-1])
    assert features["stuck_share"] == 0.0
    assert regime_of(features["stuck_share"]) == "sliding"


def test_one_sample_spikes_are_no_slips() -> None:
    time = np.arange(0.0, 5.0, 1 / RATE)
    ratio = 0.3 + np.random.default_rng(2).normal(0.0, 0.002, time.size)
    ratio[::400] -= 0.15  # a spike every 0.2 s, each one sample long (as in the Colas records)
    ratio[1::800] -= 0.15  # and a pair of samples every 0.4 s
    features = slider_window_features(time, ratio, **BENCH)
    assert features["drop"] == 0.0
    assert regime_of(features["stuck_share"]) == "sliding"


def test_the_low_pass_keeps_the_inertial_oscillation_and_drops_the_noise() -> None:
    natural = np.sqrt(BENCH["stiffness"] / BENCH["mass"]) / (2 * np.pi)  # 29 Hz
    time = np.arange(0.0, 4.0, 1 / RATE)
    oscillation = 0.05 * np.sin(2 * np.pi * natural * time)
    noise = np.random.default_rng(2).normal(0.0, 0.01, time.size)
    smooth = lowpass(oscillation + noise, RATE, stiffness=BENCH["stiffness"],
                     mass=BENCH["mass"])
    inner = slice(int(RATE) // 2, -int(RATE) // 2)
    assert np.std(smooth[inner] - oscillation[inner]) < 0.35 * 0.01
    assert np.std(smooth[inner]) == pytest.approx(np.std(oscillation[inner]), rel=0.05)


@pytest.mark.parametrize(("share", "regime"),
                         [(0.95, "stick-slip"), (2 / 3, "stick-slip"), (0.5, "mixed"),
                          (0.2, "sliding"), (0.0, "sliding")])
def test_regimes_follow_the_stuck_share(share: float, regime: str) -> None:
    assert regime_of(share) == regime
    assert list(REGIMES) == ["stick-slip", "mixed", "sliding"]


def _quantised_oscillation(noise: float) -> np.ndarray:
    """An inertial oscillation at 4300 um/s's pace (0.1 at 55 Hz) with white noise, read
    through a converter whose step is 0.007 (as the Colas record at 2254 N/m)."""
    time = np.arange(0.0, 4.0, 1 / RATE)
    ratio = 0.35 + 0.1 * np.sin(2 * np.pi * 55.0 * time)
    ratio += np.random.default_rng(3).normal(0.0, noise, time.size)
    return np.round(ratio / 0.007) * 0.007


def test_spikes_are_judged_against_their_neighbours_on_a_steep_quantised_record() -> None:
    ratio = _quantised_oscillation(0.005)
    ratio[100::200] -= 0.15  # one-sample spikes
    cleaned = without_spikes(ratio)
    assert np.all(cleaned[100::200] > ratio[100::200] + 0.1)
    # the others stay: judged against a window holding them, half were replaced
    assert np.mean(cleaned != ratio) < 0.01


def test_the_noise_floor_is_the_white_noise_the_features_see() -> None:
    ratio = _quantised_oscillation(0.005)
    mass = BENCH["stiffness"] / (2 * np.pi * 55.0) ** 2  # the oscillation at the bench's own
    floor = noise_floor(ratio, RATE, stiffness=BENCH["stiffness"], mass=mass)
    # the converter's step adds its own 0.007 / sqrt(12)
    assert floor == pytest.approx(np.hypot(0.005, 0.007 / np.sqrt(12)), rel=0.1)
    assert noise_level(ratio) > 1.5 * floor  # the first differences read the oscillation
