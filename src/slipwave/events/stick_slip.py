"""What a spring-slider record says: its slips' drops and recurrence, its creep, its regime.

A spring-slider's force over the normal load f rises at K V / N while the slider
is stuck and falls when it slips. The record's impulsive spikes are taken out first
(:func:`slipwave.events.without_spikes`, at the record's own rate), then it is
low-passed at a multiple of the bench's natural frequency (a
zero-phase Butterworth filter: the sensor's white noise goes, the slips and the
inertial oscillations stay), its drops are found
by :func:`slipwave.events.load_drops` with a fixed smallest drop, and each window
of it is summarised by:

- ``level``: the median of f;
- ``drop``: the median drop of f in a slip;
- ``recurrence``: the median time between slips' onsets, s;
- ``stuck_share``: the drops' sum over the loading K V / N would have given over the
  window: the share of the drive's travel the spring took up while the slider was
  stuck (1 in a saw-tooth, 0 in steady sliding);
- ``creep``: the median, over the slips, of the rise rate in the last fifth of the
  rise before the slip over K V / N (1 without creep; below 1 where the slider
  creeps before it slips).

The regime follows the stuck share (:data:`REGIMES`): "stick-slip" when the slider
is stuck most of the time, "sliding" when it seldom is, "mixed" between.

>>> t = np.arange(0, 10, 1 / 2000)
>>> f = 0.3 + 0.05 * ((t * 0.5) % 1.0)  # a saw-tooth: rises 0.05 in 2 s, drops at once
>>> window = slider_window_features(t, f, stiffness=1000.0, drive_speed=7.5e-6,
...                                 normal_load=0.3, mass=0.03)
>>> round(window["drop"], 3), round(window["recurrence"], 2), round(window["stuck_share"], 2)
(0.054, 2.0, 0.87)
"""

from __future__ import annotations

import numpy as np
from scipy.signal import butter, sosfiltfilt, welch

from slipwave.events.steps import load_drops, without_spikes

LOWPASS_NATURAL_MULTIPLE = 3.0
"""The low-pass filter's corner, in multiples of the bench's natural frequency
sqrt(K / M) / (2 pi): the inertial oscillations (at the natural frequency) stay."""

LOWPASS_ORDER = 4
"""The Butterworth filter's order (applied forwards and backwards)."""

MIN_DROP = 0.02
"""The smallest drop of f counted as a slip: the same on a record and on a simulation, so
that small slips the noise hides on one are not counted on the other."""

CREEP_PART = 0.2
"""The last part of each rise over which the creep's rise rate is measured."""

REGIMES = {"stick-slip": 2 / 3, "mixed": 1 / 3, "sliding": 0.0}
"""Each regime and the smallest stuck share it takes, in order."""

FEATURES = ("level", "drop", "recurrence", "stuck_share", "creep")
"""The features of a window, in order."""

SPECTRUM_SEGMENT = 1024
"""Samples per segment of the spectrum :func:`noise_floor` reads (Welch's method)."""


def lowpass(ratio: np.ndarray, sample_rate: float, *, stiffness: float, mass: float
            ) -> np.ndarray:
    """The record low-passed below :data:`LOWPASS_NATURAL_MULTIPLE` natural frequencies.

    Parameters
    ----------
    ratio
        The spring's force over the normal load, sampled at a constant rate.
    sample_rate
        Samples per second.
    stiffness
        The spring's stiffness, N/m.
    mass
        The slider's mass, kg.

    Returns
    -------
    numpy.ndarray
        The filtered record (the input when the corner lies above the Nyquist frequency).
    """
    corner = lowpass_corner(stiffness, mass)
    if corner >= 0.5 * sample_rate:
        return np.asarray(ratio, dtype=float)
    sections = butter(LOWPASS_ORDER, corner, fs=sample_rate, output="sos")
    return np.asarray(sosfiltfilt(sections, ratio))


def lowpass_corner(stiffness: float, mass: float) -> float:
    """The low-pass filter's corner: :data:`LOWPASS_NATURAL_MULTIPLE` natural frequencies.

    Parameters
    ----------
    stiffness
        The spring's stiffness, N/m.
    mass
        The slider's mass, kg.

    Returns
    -------
    float
        The corner, Hz.
    """
    return float(LOWPASS_NATURAL_MULTIPLE * np.sqrt(stiffness / mass) / (2 * np.pi))


def noise_floor(ratio: np.ndarray, sample_rate: float, *, stiffness: float, mass: float
                ) -> float:
    """The standard deviation of the white noise a record's features see.

    The spectrum's median level above the low-pass corner (:func:`lowpass_corner`), where
    a spring-slider record holds little but its noise, of the record without its spikes
    (:func:`slipwave.events.without_spikes`, as the features take them out). Not
    :func:`slipwave.events.noise_level`: from the first differences, it reads the
    signal's own changes where the slider oscillates (the Colas records at 4300 um/s: 1.7
    times this floor) and the converter's step where the noise is about one step (the
    other Colas records: 0.83 times it).

    Parameters
    ----------
    ratio
        The spring's force over the normal load, sampled at a constant rate.
    sample_rate
        Samples per second.
    stiffness
        The spring's stiffness, N/m.
    mass
        The slider's mass, kg.

    Returns
    -------
    float
        The noise's standard deviation, in the ratio's unit (white noise of variance s^2
        has the one-sided density 2 s^2 / rate).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> t = np.arange(0, 20, 1 / 2000)
    >>> f = 0.3 + 0.05 * np.sin(2 * np.pi * 40 * t) + rng.normal(0, 0.004, t.size)
    >>> round(noise_floor(f, 2000.0, stiffness=1000.0, mass=0.03), 4)
    0.004
    """
    values = without_spikes(np.asarray(ratio, dtype=float))
    frequency, density = welch(values - values.mean(), fs=sample_rate,
                               nperseg=min(SPECTRUM_SEGMENT, values.size))
    above = frequency >= min(lowpass_corner(stiffness, mass), 0.5 * frequency[-1])
    return float(np.sqrt(np.median(density[above]) * sample_rate / 2.0))


def regime_of(stuck_share: float) -> str:
    """The regime a stuck share falls in (:data:`REGIMES`).

    Parameters
    ----------
    stuck_share
        The share of the drive's travel taken up while stuck.

    Returns
    -------
    str
        ``"stick-slip"``, ``"mixed"`` or ``"sliding"``.
    """
    return next(name for name, low in REGIMES.items() if stuck_share >= low)


def slider_window_features(time: np.ndarray, ratio: np.ndarray, *, stiffness: float,
                           drive_speed: float, normal_load: float, mass: float
                           ) -> dict[str, float]:
    """The features of one window of a spring-slider record (the module's list).

    Parameters
    ----------
    time
        Sample times, s (a constant step).
    ratio
        The spring's force over the normal load.
    stiffness
        The spring's stiffness K, N/m.
    drive_speed
        The drive's speed V, m/s.
    normal_load
        The normal load N, newtons.
    mass
        The slider's mass M, kg.

    Returns
    -------
    dict
        :data:`FEATURES`. With fewer than two slips, ``recurrence`` is the window's
        length (no slip recurred within it) and ``drop`` and ``creep`` are those of the
        slips there are (``drop`` 0 and ``creep`` 1 with none).
    """
    time = np.asarray(time, dtype=float)
    # Spikes go before the low-pass, which would spread each into a slip of 0.02-0.03 (a
    # Colas record's one-sample spikes made two thirds of its counted slips); at the
    # record's rate, as despike's block medians would make load_drops' own spike rule take
    # an inertial oscillation's quick drops for spikes.
    smooth = lowpass(without_spikes(np.asarray(ratio, dtype=float)),
                     1.0 / float(time[1] - time[0]), stiffness=stiffness, mass=mass)
    drops = load_drops(time, smooth, min_drop=MIN_DROP)
    span = float(time[-1] - time[0])
    loading = stiffness * drive_speed / normal_load
    onsets = drops["t_start"].to_numpy()
    creeps = _creep_rates(time, smooth, drops["i_start"].to_numpy(),
                          drops["i_end"].to_numpy()) / loading
    return {
        "level": float(np.median(smooth)),
        "drop": float(drops["drop"].median()) if len(drops) else 0.0,
        "recurrence": float(np.median(np.diff(onsets))) if len(onsets) > 1 else span,
        "stuck_share": float(drops["drop"].sum() / (loading * span)),
        "creep": float(np.median(creeps)) if creeps.size else 1.0,
    }


def _creep_rates(time: np.ndarray, smooth: np.ndarray, starts: np.ndarray,
                 ends: np.ndarray) -> np.ndarray:
    """The rise rate over the last :data:`CREEP_PART` of each rise between two slips."""
    rates = []
    for before_end, start in zip(ends[:-1], starts[1:], strict=True):
        first = start - max(int(CREEP_PART * (start - before_end)), 2)
        if first <= before_end:
            continue
        rates.append(np.polyfit(time[first:start + 1], smooth[first:start + 1], 1)[0])
    return np.asarray(rates)
