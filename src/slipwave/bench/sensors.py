"""From a simulated test to what the acquisition card records.

:func:`clean_signals` turns a machine-driven simulation (load steps) into time
series sampled like the card: the normal loading over ``loading_time``, then the
actuator at speed V; between steps the loads follow the stuck response up to the
step's peak (its state before the wave), and a wave brings them down to the
step's final state over the time the wave takes to cross its extent.
:func:`apply_sensors` then adds what real sensors add: gain and offset errors, a
slow drift, white noise, short spikes and ADC quantisation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from slipwave.defaults import CONVENTIONS
from slipwave.errors import SlipwaveError
from slipwave.io.channels import CHANNEL_ATTRS, CHANNELS

CARD_SIGN = {"T": 1.0, "N": -1.0, "DG": 1.0, "DD": 1.0, "DT": 1.0}
"""Signs of the card's channels relative to the simulation: N reads negative in compression."""


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


@dataclass(frozen=True)
class Sensor:
    """What a sensor and its acquisition channel do to the true signal.

    Attributes
    ----------
    gain
        Relative gain error (recorded = true * (1 + gain)).
    offset
        Zero offset, in the channel's unit.
    drift
        Slow drift over the whole test (unit per second, with a slow wobble).
    noise
        Standard deviation of white noise.
    spike_rate
        Spikes per second (single-sample, electrical).
    spike_height
        Typical spike amplitude.
    bits
        ADC resolution.
    full_scale
        ADC range, +-``full_scale``.
    """

    gain: float = 0.0
    offset: float = 0.0
    drift: float = 0.0
    noise: float = 0.0
    spike_rate: float = 0.0
    spike_height: float = 0.0
    bits: int = 16
    full_scale: float = 200.0

    def record(self, true: np.ndarray, time: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The recorded values of ``true`` sampled at ``time``.

        Parameters
        ----------
        true
            The true signal.
        time
            Its sample times, s.
        rng
            The channel's random stream.

        Returns
        -------
        numpy.ndarray
            What the card records.

        Examples
        --------
        >>> import numpy as np
        >>> sensor = Sensor(bits=8, full_scale=1.0)
        >>> sensor.record(np.array([0.0, 0.5, 2.0]), np.arange(3.0), np.random.default_rng(0))
        array([0.       , 0.5      , 0.9921875])
        """
        span = max(float(time[-1] - time[0]), 1e-12)
        wobble = 0.5 * np.sin(2 * np.pi * (time - time[0]) / span)
        recorded = true * (1.0 + self.gain) + self.offset + self.drift * (time + wobble * span / 4)
        if self.noise:
            recorded = recorded + rng.normal(0.0, self.noise, true.shape)
        if self.spike_rate and self.spike_height:
            count = rng.poisson(self.spike_rate * span)
            where = rng.integers(0, true.size, count)
            recorded[where] += self.spike_height * rng.choice([-1.0, 1.0], count) * (
                0.5 + rng.random(count))
        step = 2 * self.full_scale / 2**self.bits
        return np.clip(np.round(recorded / step) * step, -self.full_scale,
                       self.full_scale - step)


DEFAULT_SENSORS = {
    "T": Sensor(gain=0.004, offset=0.15, drift=0.0004, noise=0.04, spike_rate=0.02,
                spike_height=3.0, bits=16, full_scale=250.0),
    "N": Sensor(gain=-0.003, offset=-0.2, drift=-0.0003, noise=0.05, spike_rate=0.02,
                spike_height=3.0, bits=16, full_scale=250.0),
    "DG": Sensor(gain=0.002, offset=0.01, drift=0.00002, noise=0.0015, spike_rate=0.01,
                 spike_height=0.05, bits=16, full_scale=10.0),
    "DD": Sensor(gain=-0.002, offset=-0.01, drift=0.00002, noise=0.0015, spike_rate=0.01,
                 spike_height=0.05, bits=16, full_scale=10.0),
    "DT": Sensor(gain=0.001, offset=0.0, drift=0.00001, noise=0.001, spike_rate=0.005,
                 spike_height=0.05, bits=16, full_scale=25.0),
}
"""Sensors of the default bench: noise of tens of mN and a few um, 16-bit cards."""


def apply_sensors(
    clean: xr.Dataset,
    sensors: dict[str, Sensor] | None = None,
    *,
    seed: int = 0,
) -> xr.Dataset:
    """Record clean channels through sensors (all of :data:`DEFAULT_SENSORS` by default).

    Each channel draws from its own random stream (seeded from ``seed`` and the
    channel), so a channel's noise does not depend on which others exist.

    Parameters
    ----------
    clean
        From :func:`clean_signals`.
    sensors
        Channel -> sensor; ``None``: :data:`DEFAULT_SENSORS`.
    seed
        Noise seed.

    Returns
    -------
    xarray.Dataset
        The recorded channels, as :func:`slipwave.io.read_acquisition` returns them.

    """
    sensors = DEFAULT_SENSORS if sensors is None else sensors
    recorded = clean.copy()
    time = clean["time"].values
    for position, name in enumerate(CHANNELS):
        if name in clean and name in sensors:
            rng = np.random.default_rng([seed, position])
            recorded[name] = ("time", sensors[name].record(clean[name].values, time, rng),
                              dict(clean[name].attrs))
    return recorded
