"""Simulated tests sampled like the acquisition card, and the sensor model."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from slipwave.bench import DEFAULT_SENSORS, Sensor, apply_sensors
from slipwave.errors import SlipwaveError
from slipwave.io import read_acquisition, write_acquisition
from slipwave.solver import Coulomb, LoadPath, Slab, simulate
from slipwave.solver.signals import (
    SIGNAL_VARIABLES,
    clean_signals,
    step_times,
    wave_durations,
)

SPEED, LOADING, RATE = 0.048, 10.0, 200.0


@pytest.fixture(scope="module")
def simulation() -> xr.Dataset:
    path = LoadPath(normal_load=85.0, normal_control="force", machine_stiffness=100.0,
                    max_travel=4.0, travel_step=0.04)
    return simulate(Slab(height=40.0, elements=80), Coulomb(fs=1.0, fd=0.85), path)


@pytest.fixture(scope="module")
def clean(simulation) -> xr.Dataset:
    duration = float(step_times(simulation, speed=SPEED, loading_time=LOADING)[-1]) - 0.5
    return clean_signals(simulation, speed=SPEED, loading_time=LOADING, duration=duration,
                         sample_rate=RATE, wave_speed=200.0)


def test_the_signals_need_only_their_variables(simulation, clean):
    # a fit's simulations keep only these (simulate's variables)
    kept = simulation[list(SIGNAL_VARIABLES)]
    xr.testing.assert_identical(clean_signals(kept, speed=SPEED, loading_time=LOADING,
                                              duration=float(clean["time"][-1]) + 1 / RATE,
                                              sample_rate=RATE, wave_speed=200.0), clean)


def test_phases_in_time(simulation, clean):
    time = clean["time"].values
    loading = time <= LOADING
    assert np.all(np.abs(clean["T"].values[loading]) < 1e-9)  # T is 0 while pressing
    assert clean["N"].values[0] == 0.0 and clean["N"].values[-1] == pytest.approx(-85.0)
    assert np.all(np.diff(clean["N"].values[loading]) <= 1e-12)  # N grows (negative)
    assert clean["DT"].values[loading].max() == 0.0


def test_steps_are_met_at_their_end_times(simulation, clean):
    ends = step_times(simulation, speed=SPEED, loading_time=LOADING)
    time = clean["time"].values
    inside = (ends > 0) & (ends < time[-1])
    for name in ["T", "DG", "DD", "DT"]:
        at_ends = np.interp(ends[inside], time, clean[name].values)
        np.testing.assert_allclose(at_ends, simulation[name].values[inside], atol=0.02)


def test_gross_slips_reach_their_peak_then_drop(simulation, clean):
    ends = step_times(simulation, speed=SPEED, loading_time=LOADING)
    waves = wave_durations(simulation, wave_speed=200.0)
    time, T = clean["time"].values, clean["T"].values
    gross = [k for k in np.flatnonzero(simulation["wave"].values == "gross")
             if ends[k] < time[-1]]
    assert len(gross) >= 2
    for k in gross:
        window = (time > ends[k - 1]) & (time <= ends[k])
        peak = float(simulation["T_before_wave"][k])
        assert T[window].max() == pytest.approx(peak, abs=0.05)
        # A gross wave crosses the whole contact (the open end excluded).
        x = simulation["x"].values[simulation["state"].values[k] != 0]
        assert waves[k] == pytest.approx((x.max() - x.min() + 1.0) / 200.0, rel=1e-9)
        assert T[window][-1] < peak - 1.0  # the drop happens inside the step


def test_needs_a_machine_drive():
    plain = simulate(Slab(elements=40), Coulomb(fs=1.0), LoadPath())
    with pytest.raises(SlipwaveError, match="machine_stiffness"):
        clean_signals(plain, speed=SPEED, loading_time=1.0, duration=2.0, sample_rate=10.0,
                      wave_speed=100.0)


def test_sensor_quantisation_noise_and_spikes():
    rng = np.random.default_rng(3)
    time = np.arange(100_000) / 100.0
    true = np.zeros_like(time)
    noisy = Sensor(noise=0.05, bits=16, full_scale=250.0).record(true, time, rng)
    step = 500.0 / 2**16
    np.testing.assert_allclose(noisy / step, np.round(noisy / step), atol=1e-6)
    assert noisy.std() == pytest.approx(0.05, rel=0.03)
    spiky = Sensor(spike_rate=0.1, spike_height=5.0, bits=24).record(true, time, rng)
    spikes = np.abs(spiky) > 1.0
    assert spikes.sum() == pytest.approx(0.1 * 1000, rel=0.35)
    shifted = Sensor(gain=0.01, offset=2.0, bits=24).record(np.full(10, 100.0), time[:10], rng)
    np.testing.assert_allclose(shifted, 103.0, atol=1e-4)


def test_recording_is_seeded(clean):
    a = apply_sensors(clean, seed=1)
    b = apply_sensors(clean, seed=1)
    c = apply_sensors(clean, seed=2)
    for name in ["T", "N", "DG", "DD", "DT"]:
        np.testing.assert_array_equal(a[name].values, b[name].values)
        difference = a[name].values - c[name].values
        assert np.any(difference != 0)
        sensor = DEFAULT_SENSORS[name]
        # A new seed changes noise and spikes, not the signal: away from spikes the
        # two recordings differ by a few noise levels at most.
        typical = np.median(np.abs(difference))
        assert typical < 3 * sensor.noise + 2 * sensor.full_scale / 2**sensor.bits


def test_recorded_signals_round_trip_through_the_card_format(clean, tmp_path):
    recorded = apply_sensors(clean, seed=5).assign_attrs(test_id="virtual", sample_rate_hz=RATE)
    for flavour in ["canonical", "vendor"]:
        path = write_acquisition(recorded, tmp_path / f"{flavour}.csv", flavour=flavour,
                                 float_format="%.7g")
        back = read_acquisition(path)
        for name in ["T", "N", "DG", "DD", "DT"]:
            np.testing.assert_allclose(back[name].values, recorded[name].values, rtol=1e-6,
                                       atol=1e-6)
        assert back["N"].attrs["compression_sign"] == "negative"
