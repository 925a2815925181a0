"""A machine-driven simulation as time series, sampled like the acquisition card.

:func:`clean_signals` turns a machine-driven simulation (load steps) into time
series: the normal loading over ``loading_time``, then the actuator at speed V;
between steps the loads follow the stuck response up to the step's peak (its state
before the wave), and a wave brings them down to the step's final state over the time
the wave takes to cross its extent. The signals are noise-free; the virtual bench
adds what real sensors add (:mod:`slipwave.bench.sensors`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from slipwave.defaults import CONVENTIONS
from slipwave.errors import SlipwaveError
from slipwave.io.channels import CHANNEL_ATTRS, CHANNELS

CARD_SIGN = {"T": 1.0, "N": -1.0, "DG": 1.0, "DD": 1.0, "DT": 1.0}
"""Signs of the card's channels relative to the simulation: N reads negative in compression."""

SIGNAL_VARIABLES = ("phase", "actuator", "cascade_round", *CHANNELS,
                    *(f"{name}_before_wave" for name in CHANNELS))
"""The variables of a simulation that :func:`clean_signals` reads (``simulate``'s
``variables``)."""


def step_times(simulation: xr.Dataset, *, speed: float, loading_time: float) -> np.ndarray:
    """Time (s) at the end of each load step.

    Normal steps share ``loading_time`` in proportion to their normal load; a
    tangential step ends when the actuator, moving at ``speed`` (mm/s) from the
    end of the normal loading, reaches its travel.

    Parameters
    ----------
    simulation
        From :func:`slipwave.solver.simulate` along the bench's load path.
    speed
        The actuator's speed, mm/s.
    loading_time
        Duration of the normal loading, s.

    Returns
    -------
    numpy.ndarray
        One time per step, s.

    """
    phase = simulation["phase"].values
    normal = phase == "normal"
    times = np.empty(phase.size)
    N = simulation["N"].values
    times[normal] = loading_time * N[normal] / N[normal].max()
    actuator = simulation["actuator"].values
    if np.isnan(actuator[~normal]).any():
        raise SlipwaveError("the simulation has no actuator travel: run it with "
                            "LoadPath(machine_stiffness=...)")
    times[~normal] = loading_time + actuator[~normal] / speed
    return times


def wave_durations(simulation: xr.Dataset, *, wave_speed: float) -> np.ndarray:
    """Time (s) each step's wave takes to sweep its extent at ``wave_speed`` (mm/s).

    Zero for steps without a wave.

    Parameters
    ----------
    simulation
        From :func:`slipwave.solver.simulate`.
    wave_speed
        Speed of the slip front, mm/s.

    Returns
    -------
    numpy.ndarray
        One duration per step, s.

    """
    slipped = simulation["cascade_round"].values >= 0
    x = simulation["x"].values
    spacing = float(x[1] - x[0])
    extent = np.where(
        slipped.any(axis=1),
        np.where(slipped, x, -np.inf).max(axis=1) - np.where(slipped, x, np.inf).min(axis=1)
        + spacing,
        0.0,
    )
    return extent / wave_speed


def wave_windows(
    simulation: xr.Dataset, *, speed: float, loading_time: float, wave_speed: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(start, peak, end) time of every step.

    A step runs from ``start`` (the previous step's end) to ``end``; the stuck
    response rises until ``peak``, and the step's wave, if any, runs from
    ``peak`` to ``end``, taking the time it needs to sweep its extent (at most
    half the step).

    Parameters
    ----------
    simulation
        From :func:`slipwave.solver.simulate`.
    speed, loading_time
        As in :func:`step_times`.
    wave_speed
        As in :func:`wave_durations`.

    Returns
    -------
    tuple of numpy.ndarray
        start, peak and end of every step, s.

    """
    ends = step_times(simulation, speed=speed, loading_time=loading_time)
    starts = np.concatenate([[0.0], ends[:-1]])
    waves = wave_durations(simulation, wave_speed=wave_speed)
    peaks = ends - np.minimum(waves, 0.5 * (ends - starts))
    return starts, peaks, ends


def clean_signals(
    simulation: xr.Dataset,
    *,
    speed: float,
    loading_time: float,
    duration: float,
    sample_rate: float,
    wave_speed: float,
) -> xr.Dataset:
    """Noise-free channels T, N, DG, DD, DT sampled at ``sample_rate`` over ``duration``.

    Loads are for the full width, N with the card's sign (negative in
    compression). The test starts unloaded at t = 0.

    Parameters
    ----------
    simulation
        From :func:`slipwave.solver.simulate` along the bench's load path.
    speed, loading_time
        As in :func:`step_times`.
    duration
        Length of the recording, s.
    sample_rate
        The card's sampling rate, Hz.
    wave_speed
        As in :func:`wave_durations`.

    Returns
    -------
    xarray.Dataset
        The noise-free channels along ``time``.

    Examples
    --------
    >>> from slipwave.solver import Slab, Coulomb, LoadPath, simulate
    >>> sim = simulate(Slab(elements=40), Coulomb(fs=1.0, fd=0.85),
    ...                LoadPath(normal_load=85.0, normal_control="force",
    ...                         machine_stiffness=100.0, max_travel=1.0, travel_step=0.05))
    >>> ds = clean_signals(sim, speed=0.05, loading_time=5.0, duration=25.0,
    ...                    sample_rate=10.0, wave_speed=200.0)
    >>> ds.sizes["time"], round(float(ds["N"][60]), 6)
    (250, -85.0)
    """
    starts, peaks, ends = wave_windows(simulation, speed=speed, loading_time=loading_time,
                                       wave_speed=wave_speed)
    if duration > ends[-1] + 1e-9:
        raise SlipwaveError(f"the simulation covers {ends[-1]:.3f} s, less than the "
                            f"{duration} s asked")
    time = np.arange(round(duration * sample_rate)) / sample_rate
    k = np.searchsorted(ends, time, side="left")  # the step each sample belongs to
    rising, falling = step_progress(time, k, starts, peaks, ends)
    signals = {}
    for name in CHANNELS:
        final = simulation[name].values
        peak = simulation[f"{name}_before_wave"].values
        start_value = np.concatenate([[0.0], final[:-1]])
        value = start_value[k] + (peak[k] - start_value[k]) * rising
        value = value + (final[k] - peak[k]) * falling
        signals[name] = CARD_SIGN[name] * value
    attrs = {"Conventions": CONVENTIONS}
    return xr.Dataset(
        {name: ("time", values, dict(CHANNEL_ATTRS[name])) for name, values in signals.items()},
        coords={"time": ("time", time, dict(CHANNEL_ATTRS["time"]))},
        attrs=attrs,
    )


def step_progress(
    time: np.ndarray, k: np.ndarray, starts: np.ndarray, peaks: np.ndarray, ends: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """How far the rise and the wave of step ``k`` have gone at ``time`` (0 to 1 each).

    Parameters
    ----------
    time
        Sample times, s.
    k
        The step of each sample.
    starts, peaks, ends
        From :func:`wave_windows`.

    Returns
    -------
    tuple of numpy.ndarray
        Rise and wave progress of each sample, 0 to 1.

    """
    rising = np.clip((time - starts[k]) / np.maximum(peaks[k] - starts[k], 1e-12), 0, 1)
    falling = np.clip((time - peaks[k]) / np.maximum(ends[k] - peaks[k], 1e-12), 0, 1)
    return rising, falling


def quasi_dynamic_signals(run: xr.Dataset, *, loading: float, duration: float,
                          sample_rate: float) -> xr.Dataset:
    """A quasi-dynamic run as the card records it, noise-free: the pressing, then the run.

    Parameters
    ----------
    run
        From :func:`slipwave.solver.quasi_dynamic.simulate_quasi_dynamic`, on the test's
        clock (its drive starts at ``loading``).
    loading
        The normal loading's time, s: the loads rise from zero to the run's first
        record over it.
    duration
        The recording's length, s.
    sample_rate
        The card's samples per second.

    Returns
    -------
    xarray.Dataset
        The channels over ``time``, signed as the card's (:data:`CARD_SIGN`).

    Examples
    --------
    >>> run = xr.Dataset({name: ("time", [2.0, 4.0]) for name in CHANNELS},
    ...                  coords={"time": [1.0, 2.0]})
    >>> quasi_dynamic_signals(run, loading=1.0, duration=2.0, sample_rate=2.0)["N"].values
    array([-0., -1., -2., -3.])
    """
    time = np.arange(round(duration * sample_rate)) / sample_rate
    run_time = run["time"].values
    pressing = np.clip(time / loading, 0.0, 1.0)
    signals = {}
    for name in CHANNELS:
        values = run[name].values
        signal = np.where(time < loading, pressing * values[0],
                          np.interp(time, run_time, values))
        signals[name] = CARD_SIGN[name] * signal
    return xr.Dataset(
        {name: ("time", values, dict(CHANNEL_ATTRS[name])) for name, values in signals.items()},
        coords={"time": ("time", time, dict(CHANNEL_ATTRS["time"]))},
        attrs={"Conventions": CONVENTIONS})
