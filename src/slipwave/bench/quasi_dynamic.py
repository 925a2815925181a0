"""A virtual bench test made with the quasi-dynamic contact: waves whose speed is physics'.

:func:`simulate_quasi_dynamic_test` presses the slab on the flat without friction over the
loading time, then drives the flat at the test's speed under a rate-and-state law
(:func:`slipwave.solver.quasi_dynamic.simulate_quasi_dynamic`, the normal load held as
the bench's actuator holds it), records it through the card's sensors and films its
displacements at the camera's frames. The truth lists every wave the run's fronts make
(:func:`slipwave.solver.fronts.front_waves`) with the speed it ran at: unlike the
quasi-static bench's, whose waves run at the ``wave_speed`` it is given, these speeds
come from the law, the slab and its radiation damping.

What it leaves out, as the quasi-dynamic stage does: the actuator's machine spring (the
flat's travel is prescribed) and friction during the normal loading (the pressing is
frictionless; the card's channels and the frames over it are the drive's start scaled by
the load applied so far, as a linear slab on an unchanging contact would give).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping

import numpy as np
import pandas as pd
import xarray as xr

from slipwave.bench.generate import (
    LED_DURATION,
    BenchResult,
    BenchTest,
    camera_frame_times,
    camera_truth,
    card_recording,
    sample_phases,
)
from slipwave.bench.sensors import Sensor
from slipwave.errors import SlipwaveError
from slipwave.photoelastic import Photoelastic
from slipwave.resources import require_memory
from slipwave.simulate_waves import FILM_CHUNK, on_test_clock, rate_state_law
from slipwave.solver.fronts import front_waves
from slipwave.solver.quasi_dynamic import (
    Drive,
    contact_displacements,
    simulate_quasi_dynamic,
    slab_body,
)
from slipwave.solver.signals import quasi_dynamic_signals

RUN_FIELDS = 7
"""The fields the run records at every frame (slip rate, state, p, q, contact, ux, uy)."""


class QuasiDynamicResult(BenchResult):
    """A test made quasi-dynamically: its frames film the run's displacements."""

    def frames(self) -> Iterator[np.ndarray]:
        """The video's frames, rendered a chunk at a time (memory does not grow)."""
        spec, run = self.spec, self.simulation
        camera = Photoelastic(spec.slab(), spec.camera)
        rng = np.random.default_rng([self.seed, 99])
        field_time = run["field_time"].values
        displacements = contact_displacements(run)
        times = spec.camera.acquisition_time(self.frame_times)
        # the run recorded its fields at the frames' times; the loading is ramped
        records = np.minimum(np.searchsorted(field_time, times - 1e-9), field_time.size - 1)
        leds = (spec.sync_time <= times) & (times < spec.sync_time + LED_DURATION)
        for first in range(0, times.size, FILM_CHUNK):
            chunk = slice(first, first + FILM_CHUNK)
            u = displacements[records[chunk]]
            loading = times[chunk] < spec.loading_time
            u[loading] = (times[chunk][loading, None] / spec.loading_time) * displacements[0]
            yield from camera.render_frames(camera.stresses(u), rng, leds=leds[chunk])


def simulate_quasi_dynamic_test(spec: BenchTest, *, seed: int = 0,
                                memory_limit_gb: float | None = None,
                                sensors: Mapping[str, Sensor] | None = None
                                ) -> QuasiDynamicResult:
    """Generate one test quasi-dynamically: recording, truth and a frame iterator.

    Parameters
    ----------
    spec
        The test, with its ``rate_state`` law.
    seed
        Noise seed (card and camera).
    memory_limit_gb
        Refuse a test whose run would need more (GB); ``None``:
        :func:`slipwave.resources.require_memory`'s default.
    sensors
        The card's sensors by channel; ``None``: :data:`~slipwave.bench.sensors.DEFAULT_SENSORS`.

    Returns
    -------
    QuasiDynamicResult
        The recording, the truth (each wave with its ``speed``, mm/s) and the frames; its
        ``simulation`` is the run, on the test's clock.

    Raises
    ------
    SlipwaveError
        For a test without a rate-and-state law, one too large for the memory, or a run
        that fails.

    Examples
    --------
    >>> law = {"a": 0.01, "b": 0.015, "dc_um": 2.0, "mu0": 0.9, "v0_um_s": 1.0}
    >>> result = simulate_quasi_dynamic_test(BenchTest(
    ...     "demo", elements=40, duration=60.0, rate_state=law, video="none"))
    >>> first = result.events.iloc[0]  # 36 s into the drive, at metres per second
    >>> print(first["kind"], round(float(first["t_start"]), 1), first["direction"],
    ...       float(first["speed"]) > 1000)
    partial_slip 45.8 left_to_right True
    """
    if spec.rate_state is None:
        raise SlipwaveError(f"bench test {spec.test_id!r} has no rate_state law")
    loading = spec.loading_time
    driven = spec.duration - loading
    if driven <= 0:
        raise SlipwaveError(f"bench test {spec.test_id!r}: its duration ({spec.duration} s) "
                            f"ends before its loading time ({loading} s)")
    frame_times = camera_frame_times(spec)
    filmed = spec.camera.acquisition_time(frame_times) - loading
    field_times = np.unique(np.concatenate(
        [[0.0], filmed[(filmed >= 0.0) & (filmed <= driven)] if spec.video != "none" else []]))
    nodes = spec.elements + 1
    require_memory(int(8 * (RUN_FIELDS * field_times.size * nodes
                            + 8 * driven * spec.sample_rate)),
                   f"the quasi-dynamic virtual test {spec.test_id!r} ({spec.elements} "
                   f"elements, {field_times.size} frames)", limit_gb=memory_limit_gb)
    run = simulate_quasi_dynamic(
        slab_body(spec.slab()), rate_state_law(spec.rate_state),
        Drive(normal_load=spec.normal_load, drive_speed=spec.speed, normal_control="force"),
        duration=driven, sample_rate=spec.sample_rate, field_times=field_times)
    run = on_test_clock(run, loading)
    clean = quasi_dynamic_signals(run, loading=loading, duration=spec.duration,
                                  sample_rate=spec.sample_rate)
    recording = card_recording(spec, clean, seed=seed, sensors=sensors,
                               generator="slipwave virtual bench, quasi-dynamic")
    events = _events(spec, run)
    phases = sample_phases(spec, events, clean["time"].values)
    if not events.empty:
        before, after = _displacements_around(run, events)
        events = camera_truth(spec, events, before, after, frame_times)
    return QuasiDynamicResult(spec, run, recording, events, phases, frame_times, seed)


def _events(spec: BenchTest, run: xr.Dataset) -> pd.DataFrame:
    """Every wave of the run with the loads and edge displacements either side of it."""
    waves = front_waves(run)
    if waves.empty:
        return pd.DataFrame()
    before, after = _either_side(run["time"].values, waves)  # the card's samples
    T, N = run["T"].values, run["N"].values
    DG, DD = run["DG"].values, run["DD"].values
    events = pd.DataFrame({
        "kind": np.where(waves["kind"] == "gross", "gross_slip", "partial_slip"),
        "t_start": waves["t_start"],
        "t_end": waves["t_end"],
        "x_first": waves["x_start"],
        "x_last": waves["x_end"],
        "x_min": waves["x_min"],
        "x_max": waves["x_max"],
        "extent": waves["extent"],
        "direction": waves["direction"],
        "speed": waves["speed"],
        "T_before": T[before],
        "T_after": T[after],
        "N_before": N[before],
        "N_after": N[after],
        "ratio_before": T[before] / N[before],
        "ratio_after": T[after] / N[after],
        "drop": T[before] - T[after],
        "DG_jump": DG[after] - DG[before],
        "DD_jump": DD[after] - DD[before],
    })
    events["visible"] = (events["kind"] == "gross_slip") | (events["drop"] >= spec.min_event_drop)
    events.insert(0, "test_id", spec.test_id)
    return events


def _displacements_around(run: xr.Dataset, events: pd.DataFrame
                          ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Each wave's contact displacements at the frames either side of it."""
    displacements = contact_displacements(run)
    before, after = _either_side(run["field_time"].values, events)
    return [displacements[k] for k in before], [displacements[k] for k in after]


def _either_side(times: np.ndarray, waves: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Each wave's last record before it starts and first after it ends (indices)."""
    last = times.size - 1
    before = np.clip(np.searchsorted(times, waves["t_start"], side="right") - 1, 0, last)
    after = np.clip(np.searchsorted(times, waves["t_end"], side="left"), 0, last)
    return before, after
