"""One virtual bench test: recording, video and ground truth, from the solver.

:func:`simulate_test` runs the contact solver along the bench's load path
(normal loading, then the flat driven by an actuator through the machine's
spring, past gross sliding), samples it like the acquisition card, records it
through the sensors, films it with the photoelastic camera and lists the truth:
every wave with its kind, times, extent and direction, and the phase of every
sample. :func:`write_test` writes the files a real test would leave, and the
truth beside them.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd
import xarray as xr
from tqdm import tqdm

from slipwave.bench.camera import write_image_sequence, write_video
from slipwave.bench.sensors import DEFAULT_SENSORS, Sensor, apply_sensors
from slipwave.defaults import (
    BAND_MM,
    BENCH_ELEMENTS,
    CONTACT_LENGTH_MM,
    CONVENTIONS,
    POISSON_RATIO,
    SAMPLE_RATE_HZ,
    SLAB_HEIGHT_MM,
    SLAB_WIDTH_MM,
    TRAVEL_STEP_MM,
    YOUNGS_MODULUS_MPA,
)
from slipwave.errors import SlipwaveError
from slipwave.io import atomic_output, write_acquisition
from slipwave.photoelastic import Camera, Photoelastic
from slipwave.resources import require_memory
from slipwave.setup import TestSetup, driven_load_path
from slipwave.solver import (
    Coulomb,
    LoadPath,
    Slab,
    SlipWeakening,
    SolverCache,
    simulate,
    simulation_memory,
)
from slipwave.solver.signals import clean_signals, step_progress, wave_windows
from slipwave.validation import check, load_schema, read_yaml

LED_DURATION = 0.2  # s the sync LED stays lit
FRONT_WIDTH = 4.0  # mm over which a wave front blends the states before and after it
CAMERA_SNR = 5.0  # a wave the camera sees changes the band by 5 noise sigmas on average
CAMERA_FRAMES = 3  # and its front shows in at least 3 frames


@dataclass(frozen=True)
class BenchTest:
    """Everything that defines a virtual test (mm, N, s).

    The interface follows Coulomb's law with a static coefficient that grows
    from ``fs`` to ``fs_final`` over the first ``runin_slips`` gross slips
    (run-in; with ``fs_peak``, through a turn: :class:`~slipwave.solver.Coulomb`) and
    a dynamic one ``fd``; with ``dc`` (mm), linear slip-weakening
    instead: a slipping node's coefficient falls from fs to fd over a slip Dc.
    Waves whose T drop is below ``min_event_drop`` (micro-slips at the edge of
    the contact) are listed in the truth as not visible. ``edge_convention`` is
    how the card's edge sensors read: both along +x, or each its own edge's
    outward displacement (the paper's bench: the left sensor's sign is turned).

    With ``rate_state`` (the workflow's ``simulate_waves`` keys: ``a``, ``b``,
    ``dc_um``, ``mu0``, ``v0_um_s``) the interface follows that rate-and-state law
    instead, and the test is made with the quasi-dynamic contact
    (:mod:`slipwave.bench.quasi_dynamic`): its waves' speeds are the physics', and
    ``wave_speed``, ``machine_stiffness`` and the Coulomb coefficients are not used.
    """

    test_id: str
    height: float = SLAB_HEIGHT_MM
    length: float = CONTACT_LENGTH_MM
    width: float = SLAB_WIDTH_MM
    youngs_modulus: float = YOUNGS_MODULUS_MPA
    poisson_ratio: float = POISSON_RATIO
    elements: int = BENCH_ELEMENTS
    fs: float = 0.9
    fd: float = 0.6
    fs_final: float | None = 1.3
    runin_slips: float = 4
    fs_peak: float | None = None
    dc: float | None = None
    rate_state: dict[str, float] | None = None
    normal_load: float = 85.0
    speed: float = 0.048
    duration: float = 280.0
    loading_time: float = 10.0
    machine_stiffness: float = 40.0
    travel_step: float = TRAVEL_STEP_MM
    wave_speed: float = 200.0
    sample_rate: float = SAMPLE_RATE_HZ
    min_event_drop: float = 0.5
    sync_time: float = 2.0
    flavour: Literal["canonical", "vendor"] = "canonical"
    edge_convention: Literal["x_axis", "outward"] = "x_axis"
    video: Literal["ffv1", "vp9", "png", "none"] = "vp9"
    camera: Camera = field(default_factory=Camera)

    def __post_init__(self) -> None:
        # the same rules as a campaign YAML's (bench.schema.json), for tests made in Python
        check(asdict(self), load_schema("bench")["$defs"]["test"],
              source=f"bench test {self.test_id!r}")

    def slab(self) -> Slab:
        """The slab of this test.

        Returns
        -------
        Slab
            Its geometry, material and mesh.

        """
        return Slab(length=self.length, height=self.height, width=self.width,
                    youngs_modulus=self.youngs_modulus, poisson_ratio=self.poisson_ratio,
                    elements=self.elements)

    def friction(self) -> Coulomb:
        """The interface's friction law.

        Returns
        -------
        Coulomb
            Coulomb's law with run-in, or linear slip-weakening (:class:`SlipWeakening`)
            when ``dc`` is set.

        """
        runin = self.runin_slips if self.fs_final is not None else 0
        if self.dc is not None:
            return SlipWeakening(fs=self.fs, fd=self.fd, fs_final=self.fs_final,
                                 runin_slips=runin, fs_peak=self.fs_peak, dc=self.dc)
        return Coulomb(fs=self.fs, fd=self.fd, fs_final=self.fs_final, runin_slips=runin,
                       fs_peak=self.fs_peak)

    def load_path(self) -> LoadPath:
        """The bench's load path: N held, the flat driven through the machine.

        Returns
        -------
        LoadPath
            Normal load held, then the actuator's travel
            (:func:`slipwave.setup.driven_load_path`).

        """
        return driven_load_path(normal_load=self.normal_load, speed=self.speed,
                                duration=self.duration, loading_time=self.loading_time,
                                machine_stiffness=self.machine_stiffness,
                                travel_step=self.travel_step)


def setup_bench_test(setup: TestSetup, friction: Coulomb, *, elements: int) -> BenchTest:
    """The virtual-bench spec that runs a real test's setup with a friction law (no video).

    Parameters
    ----------
    setup
        The test's configuration (:func:`slipwave.setup.read_test_setup`).
    friction
        The law (:class:`~slipwave.solver.Coulomb`, with run-in, or
        :class:`~slipwave.solver.SlipWeakening`).
    elements
        Elements along the contact.

    Returns
    -------
    BenchTest
        The test's geometry, material, loads, drive and duration with the law.

    """
    return BenchTest(
        setup.test_id, height=setup["height_mm"], length=setup["length_mm"],
        width=setup["width_mm"], youngs_modulus=setup["youngs_modulus_mpa"],
        poisson_ratio=setup["poisson_ratio"], elements=elements, fs=friction.fs,
        fd=friction.dynamic, fs_final=friction.fs_final,
        runin_slips=friction.runin_slips if friction.fs_final is not None else 4,
        fs_peak=friction.fs_peak,
        dc=getattr(friction, "dc", None), normal_load=setup["normal_load_n"],
        speed=setup["speed_mm_s"], duration=setup["duration_s"],
        loading_time=setup["loading_time_s"],
        machine_stiffness=setup["machine_stiffness_n_mm"], video="none")


@dataclass
class BenchResult:
    """A generated test: what the card and the camera recorded, and the truth."""

    spec: BenchTest
    simulation: xr.Dataset
    recording: xr.Dataset
    events: pd.DataFrame
    phases: pd.DataFrame
    frame_times: np.ndarray
    seed: int

    def frames(self) -> Iterator[np.ndarray]:
        """The video's frames, rendered one at a time (memory does not grow)."""
        yield from _render(self)


def simulate_test(spec: BenchTest, *, seed: int = 0, memory_limit_gb: float | None = None,
                  cache: SolverCache | None = None,
                  sensors: Mapping[str, Sensor] | None = None) -> BenchResult:
    """Generate one test in memory: recording, truth and a frame iterator.

    A test with a rate-and-state law is made quasi-dynamically
    (:func:`slipwave.bench.quasi_dynamic.simulate_quasi_dynamic_test`).

    Parameters
    ----------
    spec
        The test.
    seed
        Noise seed (card and camera).
    memory_limit_gb
        Refuse a test whose simulation would need more (GB); ``None``:
        :func:`slipwave.resources.require_memory`'s default.
    cache
        The solver's cache (a campaign's tests share their slabs'); ``None``: computed
        afresh.
    sensors
        The card's sensors by channel; ``None``: :data:`~slipwave.bench.sensors.DEFAULT_SENSORS`.

    Returns
    -------
    BenchResult
        The recording, the truth and the frames.

    Examples
    --------
    >>> result = simulate_test(BenchTest("demo", elements=40, duration=40.0, video="none"))
    >>> result.recording.attrs["test_id"], result.recording.sizes["time"]
    ('demo', 4000)
    """
    if spec.rate_state is not None:
        # the quasi-dynamic test builds on this module's BenchTest, BenchResult and truth
        from slipwave.bench.quasi_dynamic import simulate_quasi_dynamic_test
        return simulate_quasi_dynamic_test(spec, seed=seed, memory_limit_gb=memory_limit_gb,
                                           sensors=sensors)
    slab = spec.slab()
    require_memory(simulation_memory(slab, spec.load_path(),
                                     samples=spec.duration * spec.sample_rate,
                                     recovery=spec.video != "none"),
                   f"the virtual test {spec.test_id!r} ({spec.elements} elements, H = "
                   f"{spec.height:g} mm)", limit_gb=memory_limit_gb)
    simulation = simulate(slab, spec.friction(), spec.load_path(), cache=cache)
    clean = clean_signals(simulation, speed=spec.speed, loading_time=spec.loading_time,
                          duration=spec.duration, sample_rate=spec.sample_rate,
                          wave_speed=spec.wave_speed)
    recording = card_recording(spec, clean, seed=seed, sensors=sensors,
                               generator="slipwave virtual bench")
    events = _events(spec, simulation)
    phases = sample_phases(spec, events, clean["time"].values)
    frame_times = camera_frame_times(spec)
    if not events.empty:
        events = _camera_truth(spec, simulation, events, frame_times)
    return BenchResult(spec, simulation, recording, events, phases, frame_times, seed)


def card_recording(spec: BenchTest, clean: xr.Dataset, *, seed: int,
                   sensors: Mapping[str, Sensor] | None, generator: str) -> xr.Dataset:
    """What the card records of a test's noise-free channels, with the test's attributes.

    Parameters
    ----------
    spec
        The test (its edge convention, geometry, loads and camera).
    clean
        The noise-free channels over ``time`` (:func:`slipwave.solver.signals.clean_signals`).
    seed
        The card's noise seed.
    sensors
        The card's sensors by channel; ``None``: :data:`~slipwave.bench.sensors.DEFAULT_SENSORS`.
    generator
        What made the test, for the ``generator`` attribute.

    Returns
    -------
    xarray.Dataset
        The recording, as :func:`slipwave.io.read_acquisition` reads one.

    """
    if spec.edge_convention == "outward":  # the left sensor reads its edge's outward motion
        clean["DG"] = clean["DG"].copy(data=-clean["DG"].values)
    recording = apply_sensors(clean, dict(sensors or DEFAULT_SENSORS), seed=seed)
    recording.attrs = {
        "test_id": spec.test_id,
        "sample_rate_hz": spec.sample_rate,
        "length_mm": spec.length,
        "height_mm": spec.height,
        "width_mm": spec.width,
        "speed_mm_s": spec.speed,
        "normal_load_n": spec.normal_load,
        "sync_time_s": spec.sync_time,
        "camera_fps": spec.camera.fps,
        "generator": generator,
        "Conventions": CONVENTIONS,
    }
    return recording


def camera_frame_times(spec: BenchTest) -> np.ndarray:
    """The camera's timestamps of the frames it takes during the test.

    Parameters
    ----------
    spec
        The test (its duration and camera).

    Returns
    -------
    numpy.ndarray
        Camera times, s, of the frames taken between the card's start and the test's end.

    """
    camera = spec.camera
    camera_end = (spec.duration - camera.clock_offset) / (1 + camera.clock_rate_error)
    frame_times = np.arange(0.0, camera_end, 1.0 / camera.fps)
    return frame_times[camera.acquisition_time(frame_times) >= 0.0]


def _direction(first: float, last: float) -> str:
    return "right_to_left" if last < first else "left_to_right"


def _events(spec: BenchTest, simulation: xr.Dataset) -> pd.DataFrame:
    _, peaks, ends = wave_windows(simulation, speed=spec.speed,
                                       loading_time=spec.loading_time,
                                       wave_speed=spec.wave_speed)
    x = simulation["x"].values
    rows = []
    for k in np.flatnonzero(simulation["wave"].values != "none"):
        if ends[k] > spec.duration or simulation["phase"].values[k] != "tangential":
            continue
        order = simulation["cascade_round"].values[k]
        slipped = order >= 0
        first = float(x[slipped & (order <= np.quantile(order[slipped], 0.1))].mean())
        last = float(x[slipped & (order >= np.quantile(order[slipped], 0.9))].mean())
        T0, T1 = float(simulation["T_before_wave"][k]), float(simulation["T"][k])
        N0, N1 = float(simulation["N_before_wave"][k]), float(simulation["N"][k])
        kind = "gross_slip" if simulation["wave"].values[k] == "gross" else "partial_slip"
        contact = simulation["state"].values[k] != 0
        rows.append({
            "kind": kind,
            "t_start": float(peaks[k]),
            "t_end": float(ends[k]),
            "x_first": first,
            "x_last": last,
            "x_min": float(x[slipped].min()),
            "x_max": float(x[slipped].max()),
            "swept_fraction": float((slipped & contact).sum() / max(contact.sum(), 1)),
            "direction": _direction(first, last),
            "T_before": T0,
            "T_after": T1,
            "N_before": N0,
            "N_after": N1,
            "ratio_before": T0 / N0,
            "ratio_after": T1 / N1,
            "drop": T0 - T1,
            "DG_jump": float(simulation["DG"][k] - simulation["DG_before_wave"][k]),
            "DD_jump": float(simulation["DD"][k] - simulation["DD_before_wave"][k]),
            "static_friction": float(simulation["static_friction"][k]),
            "step": int(k),
        })
    events = pd.DataFrame(rows)
    if events.empty:
        return events
    events["visible"] = (events["kind"] == "gross_slip") | (events["drop"] >= spec.min_event_drop)
    events.insert(0, "test_id", spec.test_id)
    return events


def _camera_truth(spec: BenchTest, simulation: xr.Dataset, events: pd.DataFrame,
                  frame_times: np.ndarray) -> pd.DataFrame:
    """The camera's view of the quasi-static waves: each one's displacements either side."""
    before = [np.concatenate([simulation["ux_before_wave"].values[step],
                              simulation["uy_before_wave"].values[step]])
              for step in events["step"]]
    after = [np.concatenate([simulation["ux"].values[step], simulation["uy"].values[step]])
             for step in events["step"]]
    return camera_truth(spec, events, before, after, frame_times)


def camera_truth(spec: BenchTest, events: pd.DataFrame, before: Sequence[np.ndarray],
                 after: Sequence[np.ndarray], frame_times: np.ndarray) -> pd.DataFrame:
    """What the camera can see of each wave: its image change, frames and visibility.

    ``camera_change`` is the mean absolute change of the noise-free fringe
    intensity (8-bit grey levels) that the wave makes in the kymograph's band
    (:data:`slipwave.defaults.BAND_MM` above the interface), over its slipped
    range; ``camera_frames`` the number of frames taken while it runs. A wave is
    ``camera_visible`` when its change is at least ``CAMERA_SNR`` times the sensor
    noise and its front shows in at least ``CAMERA_FRAMES`` frames (fewer, and neither
    its direction nor its extent can be measured). Without a video, none is.

    Parameters
    ----------
    spec
        The test.
    events
        Its waves: ``t_start``, ``t_end`` (s, the card's clock), ``x_min``, ``x_max`` (mm).
    before, after
        Each wave's contact displacements ``[ux, uy]`` (mm) before and after it.
    frame_times
        The frames' camera timestamps, s.

    Returns
    -------
    pandas.DataFrame
        ``events`` with ``camera_change``, ``camera_frames`` and ``camera_visible``.

    """
    events = events.copy()
    if spec.video == "none":
        events["camera_change"] = np.nan
        events["camera_frames"] = 0
        events["camera_visible"] = False
        return events
    camera = Photoelastic(spec.slab(), spec.camera)
    rows = np.nonzero(camera.inside)[0]
    height = (camera.interface_row - (rows + 0.5)) / camera.scale
    band = (height >= BAND_MM[0]) & (height <= BAND_MM[1])
    x = camera.pixel_x[band]
    changes = []
    for u_before, u_after, low, high in zip(before, after, events["x_min"], events["x_max"],
                                            strict=True):
        shown = [np.sin(np.pi * camera.fringe_order(camera.stress(u)[:, band])) ** 2
                 for u in (u_before, u_after)]
        swept = (x >= low) & (x <= high)
        difference = np.abs(shown[1] - shown[0])[swept] * spec.camera.intensity
        changes.append(float(difference.mean()) if swept.any() else 0.0)
    acquisition = spec.camera.acquisition_time(frame_times)
    frames = (np.searchsorted(acquisition, events["t_end"], side="right")
              - np.searchsorted(acquisition, events["t_start"], side="right"))
    events["camera_change"] = changes
    events["camera_frames"] = frames
    events["camera_visible"] = (np.asarray(changes) >= CAMERA_SNR * spec.camera.noise) & (
        frames >= CAMERA_FRAMES)
    return events


def sample_phases(spec: BenchTest, events: pd.DataFrame, time: np.ndarray) -> pd.DataFrame:
    """Each sample's phase: normal loading, stick, or within a visible wave.

    Parameters
    ----------
    spec
        The test.
    events
        Its waves (``kind``, ``t_start``, ``t_end``, ``visible``).
    time
        The samples' times, s.

    Returns
    -------
    pandas.DataFrame
        ``time`` and ``phase`` (``normal_loading``, ``stick``, ``partial_slip``,
        ``gross_slip``; a gross slip wins where both overlap).

    """
    phase = np.where(time < spec.loading_time, "normal_loading", "stick").astype(object)
    if not events.empty:
        for kind in ("partial_slip", "gross_slip"):  # gross wins where both overlap
            chosen = events[(events["kind"] == kind) & events["visible"]]
            for start, end in zip(chosen["t_start"], chosen["t_end"], strict=True):
                phase[(time >= start) & (time <= end)] = kind
    return pd.DataFrame({"time": time, "phase": phase})


def _render(result: BenchResult) -> Iterator[np.ndarray]:
    spec, simulation = result.spec, result.simulation
    camera = Photoelastic(spec.slab(), spec.camera)
    starts, peaks, ends = wave_windows(simulation, speed=spec.speed,
                                       loading_time=spec.loading_time,
                                       wave_speed=spec.wave_speed)
    ux, uy = simulation["ux"].values, simulation["uy"].values
    ux0, uy0 = simulation["ux_before_wave"].values, simulation["uy_before_wave"].values
    order = simulation["cascade_round"].values
    x = simulation["x"].values
    rng = np.random.default_rng([result.seed, 99])
    cache: dict[tuple[int, str], np.ndarray] = {}

    def stress(k: int, which: str) -> np.ndarray:
        key = (k, which)
        if key not in cache:
            if len(cache) > 8:
                cache.pop(next(iter(cache)))
            if k < 0:
                cache[key] = np.zeros((3, camera.pixel_x.size))
            elif which == "final":
                cache[key] = camera.stress(np.concatenate([ux[k], uy[k]]))
            else:
                cache[key] = camera.stress(np.concatenate([ux0[k], uy0[k]]))
        return cache[key]

    times = spec.camera.acquisition_time(result.frame_times)
    steps = np.searchsorted(ends, times, side="left")
    rising, falling = step_progress(times, steps, starts, peaks, ends)
    for t, k, up, down in zip(times, steps, rising, falling, strict=True):
        k = int(min(k, ends.size - 1))
        before = stress(k - 1, "final")
        peak = stress(k, "peak")
        field = before + (peak - before) * up
        if down > 0:
            slipped = order[k] >= 0
            first = x[slipped & (order[k] <= np.quantile(order[k][slipped], 0.1))].mean()
            last = x[slipped & (order[k] >= np.quantile(order[k][slipped], 0.9))].mean()
            # The front sweeps the slipped range at the wave speed, from the end where
            # the slip began (the first tenth of the cascade) to the other.
            low, high = x[slipped].min(), x[slipped].max()
            start, stop = (high, low) if last < first else (low, high)
            front = start + (stop - start) * down
            # Pixels the front has passed show the state after the wave, across a
            # smooth band of FRONT_WIDTH mm; outside the slipped range the slab
            # relaxes gradually over the wave, without a front.
            passed = (camera.pixel_x - front) * np.sign(start - stop) / FRONT_WIDTH + 0.5
            swept = (camera.pixel_x >= low - FRONT_WIDTH / 2) & (
                camera.pixel_x <= high + FRONT_WIDTH / 2)
            weight = np.where(swept, np.clip(passed, 0.0, 1.0), down)
            field = field + (stress(k, "final") - field) * weight
        led = spec.sync_time <= t < spec.sync_time + LED_DURATION
        yield camera.render(field, rng, led=bool(led))


def write_test(
    result: BenchResult, folder: str | PathLike[str], *, progress: bool = False
) -> dict[str, Path]:
    """Write a test's CSV, video and truth (under ``truth/``) into ``folder``.

    The video is ``<test_id>.mkv`` (``ffv1`` or ``vp9``) or, for ``png``, the
    numbered images of ``<test_id>_frames/``.

    Returns
    -------
    dict
        The paths written: ``csv``, ``video`` (if any), ``events``, ``phases``,
        ``parameters``.

    Parameters
    ----------
    result
        From :func:`simulate_test`.
    folder
        The campaign folder.
    progress
        Show a progress bar while filming.

    """
    folder = Path(folder)
    spec = result.spec
    paths: dict[str, Path] = {}
    paths["csv"] = write_acquisition(result.recording, folder / f"{spec.test_id}.csv",
                                     flavour=spec.flavour, float_format="%.7g")
    frames = tqdm(result.frames(), total=result.frame_times.size, unit="frame",
                  desc=spec.test_id, leave=False, disable=not progress)
    if spec.video == "png":
        paths["video"] = write_image_sequence(frames, result.frame_times,
                                              folder / f"{spec.test_id}_frames")
    elif spec.video != "none":
        paths["video"] = write_video(frames, result.frame_times,
                                     folder / f"{spec.test_id}.mkv", codec=spec.video,
                                     fps=spec.camera.fps)
    truth = folder / "truth"
    paths["events"] = truth / f"{spec.test_id}_events.csv"
    paths["phases"] = truth / f"{spec.test_id}_phases.csv"
    paths["parameters"] = truth / f"{spec.test_id}.json"
    with atomic_output(paths["events"]) as temporary:
        result.events.to_csv(temporary, index=False, float_format="%.6g")
    with atomic_output(paths["phases"]) as temporary:
        result.phases.to_csv(temporary, index=False, float_format="%.6g")
    gross = result.events[result.events["kind"] == "gross_slip"] if not result.events.empty \
        else result.events
    summary: dict[str, Any] = {
        "test": asdict(spec),
        "seed": result.seed,
        "files": {key: path.name for key, path in paths.items()},
        "ratio_at_gross_slips": [] if gross.empty else gross["ratio_before"].round(6).tolist(),
        "events": int(result.events["visible"].sum()) if not result.events.empty else 0,
    }
    with atomic_output(paths["parameters"]) as temporary:
        temporary.write_text(json.dumps(summary, indent=2, default=str), encoding="utf-8")
    return paths


def read_bench_config(path: str | PathLike[str]) -> list[BenchTest]:
    """The tests of a campaign YAML file (``defaults`` and ``tests``).

    Parameters
    ----------
    path
        The YAML file.

    Returns
    -------
    list of BenchTest
        One per entry of ``tests``, as :func:`load_tests` makes them.

    Raises
    ------
    ConfigError
        If the file cannot be read as YAML or breaks the bench schema
        (``slipwave/schemas/bench.schema.json``), naming the line and the setting.

    """
    config, line_of = read_yaml(path)
    return load_tests(config, source=str(path), line_of=line_of)


def load_tests(config: dict[str, Any], *, source: str = "the bench config",
               line_of: Callable[[Sequence[str | int]], int | None] | None = None
               ) -> list[BenchTest]:
    """Tests of a campaign config: ``defaults`` merged into each of ``tests``.

    Parameters
    ----------
    config
        The campaign's mapping (``defaults``, ``tests``), checked against
        ``slipwave/schemas/bench.schema.json``.
    source
        Where it came from, for error messages.
    line_of
        The line of a setting in the source (:func:`slipwave.validation.read_yaml`).

    Returns
    -------
    list of BenchTest
        One per entry of ``tests``.

    Raises
    ------
    SlipwaveError
        If there is no test, an unknown setting or a repeated id.

    """
    check(config, load_schema("bench"), source=source, line_of=line_of)
    defaults = dict(config.get("defaults") or {})
    tests = config["tests"]
    specs = []
    for entry in tests:
        merged = {**defaults, **entry}
        camera = merged.pop("camera", None)
        try:
            specs.append(BenchTest(**merged, camera=Camera(**(camera or {}))))
        except TypeError as err:
            raise SlipwaveError(f"bench test {entry.get('test_id', '?')!r}: {err}") from err
    ids = [spec.test_id for spec in specs]
    if len(set(ids)) != len(ids):
        raise SlipwaveError(f"bench test ids repeat: {ids}")
    return specs


def write_campaign(
    specs: list[BenchTest], folder: str | PathLike[str], *, seed: int = 0, progress: bool = True,
    memory_limit_gb: float | None = None, cache: SolverCache | None = None,
) -> Path:
    """Write every test of a campaign and its table ``tests.tsv``; returns the table.

    Test k uses the seed ``seed + k``.

    Parameters
    ----------
    specs
        The tests.
    folder
        The campaign folder.
    seed
        Noise seed of the first test.
    progress
        Show progress bars.
    memory_limit_gb
        As in :func:`simulate_test`.
    cache
        The solver's cache, shared by the tests; ``None``: the campaign's own.

    Returns
    -------
    Path
        The campaign table ``tests.tsv``.

    """
    folder = Path(folder)
    cache = cache or SolverCache()
    rows = []
    for k, spec in enumerate(tqdm(specs, desc="virtual bench", unit="test", disable=not progress)):
        result = simulate_test(spec, seed=seed + k, memory_limit_gb=memory_limit_gb,
                               cache=cache)
        paths = write_test(result, folder, progress=progress)
        video = paths.get("video")
        rows.append({"test_id": spec.test_id, "csv": paths["csv"].name,
                     "frames": video.name if video else "", "columns": ""})
    table = folder / "tests.tsv"
    with atomic_output(table) as temporary:
        pd.DataFrame(rows).to_csv(temporary, sep="\t", index=False)
    return table
