"""What real sensors add to a simulated test's noise-free signals.

:func:`apply_sensors` adds gain and offset errors, a slow drift, white noise, short
spikes and ADC quantisation to the channels of
:func:`slipwave.solver.signals.clean_signals`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from slipwave.io.channels import CHANNELS


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
