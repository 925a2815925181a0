"""The simulate stage: a test run again through the solver with its fitted law.

:func:`replay_test` follows the test's own load path (its setup, from
:func:`slipwave.setup.read_test_setup`) with a friction law and returns what the
measurement has, in the measurement's shapes: a recording like
:func:`slipwave.io.read_acquisition`'s (T, N, DG, DD, DT against time, noise-free,
the edges in the test's edge reference), and the contact's history: the zone state of
every node at every step and the simulated photoelastic kymograph
(:mod:`slipwave.photoelastic`, the band the video's kymograph reads), so that detection, the
kymograph's readers and the comparison run on both unchanged. :func:`sequence_scatter`
runs the law's neighbours (fs or fd a load cell's calibration off) for the
simulation's own scatter, which the comparison's tolerances hold.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd
import xarray as xr

from slipwave.compare import EVENT_FEATURES, ORIGIN, SCATTER_STEP, event_features, first_wave
from slipwave.defaults import BAND_MM, CONVENTIONS, SAMPLE_RATE_HZ
from slipwave.errors import SlipwaveError, SolverError
from slipwave.events.detect import DEFAULT_DETECTION, DetectionSettings, detect_events
from slipwave.fit import detected_edge_threshold, simulated_recording
from slipwave.photoelastic import Camera, Photoelastic
from slipwave.setup import TestSetup
from slipwave.solver import Coulomb, Slab, SolverCache
from slipwave.solver.signals import step_times

STATE_NAMES = "open stick slip"
"""Zone state codes 0, 1, 2 (the solver's)."""


@dataclass
class Replay:
    """A test simulated along its own load path.

    Attributes
    ----------
    simulation
        The solver's steps (:func:`slipwave.solver.simulate`).
    recording
        T, N, DG, DD, DT against time, as :func:`slipwave.io.read_acquisition` returns.
    contact
        ``state(time, x)`` and ``intensity(time, x)`` (the simulated kymograph) at each
        step's end.

    """

    simulation: xr.Dataset
    recording: xr.Dataset
    contact: xr.Dataset


def replay_test(setup: TestSetup, friction: Coulomb, *, min_drop: float, elements: int,
                sample_rate: float = SAMPLE_RATE_HZ, kymograph: bool = True,
                band_mm: tuple[float, float] = BAND_MM,
                detection: DetectionSettings = DEFAULT_DETECTION,
                cache: SolverCache | None = None) -> Replay:
    """Simulate a test with a friction law and shape it like the measurement.

    Parameters
    ----------
    setup
        The test's configuration.
    friction
        The law (usually the fit's chosen one).
    min_drop
        The measurement's smallest drop, N (``fit.json``'s ``measured.min_drop_n``): the
        simulated slips are read as detection reads the measured ones.
    elements
        Elements along the contact (the fit's).
    sample_rate
        The recording's sampling rate, Hz.
    kymograph
        Also render the simulated kymograph.
    band_mm
        The kymograph's band above the interface, mm (the video's).
    detection
        The detection's settings (the measurement's), for the simulated slips.
    cache
        The solver's cache; ``None``: computed afresh.

    Returns
    -------
    Replay
        The simulation, its recording and its contact history. The recording's attrs
        hold ``gross_edge_ratio``, the test's gross/partial edge threshold read off the
        simulated slips (:func:`slipwave.fit.detected_edge_threshold`).

    """
    slab = setup.slab(elements)
    simulation = setup.simulate(friction, elements, cache=cache)
    recording = simulated_recording(simulation, setup, sample_rate=sample_rate)
    recording.attrs.update({
        "product": "simulated recording",
        "test_id": setup.test_id, "source": f"simulation of {setup.test_id}",
        "sample_rate_hz": sample_rate, "edge_reference": setup.edge_reference,
        "gross_edge_ratio": detected_edge_threshold(simulation, setup, min_drop=min_drop,
                                                    sample_rate=sample_rate,
                                                    detection=detection),
        "friction_law": simulation.attrs.get("friction_law", type(friction).__name__),
        "Conventions": CONVENTIONS,
        **{key: setting.value for key, setting in setup.settings.items()}})
    times = step_times(simulation, speed=setup["speed_mm_s"],
                       loading_time=setup["loading_time_s"])
    contact = contact_history(simulation, times, slab if kymograph else None, band_mm=band_mm)
    contact.attrs.update(product="contact history", test_id=setup.test_id)
    return Replay(simulation, recording, contact)


def neighbouring_laws(friction: Coulomb, step: float = SCATTER_STEP) -> list[Coulomb]:
    """The law with fs, then fd, moved down and up.

    Parameters
    ----------
    friction
        The law.
    step
        How far each coefficient moves, relative.

    Returns
    -------
    list of Coulomb
        fs - step, fs + step, then fd - step, fd + step (relative), the rest of the law
        kept; a move that would break fd <= fs is left out.

    Examples
    --------
    >>> [(law.fs, law.fd) for law in neighbouring_laws(Coulomb(fs=1.0, fd=0.5), 0.01)]
    [(0.99, 0.5), (1.01, 0.5), (1.0, 0.495), (1.0, 0.505)]
    """
    factors = (1.0 - step, 1.0 + step)
    moves = ([(friction.fs * factor, friction.fd) for factor in factors]
             + [(friction.fs, friction.dynamic * factor) for factor in factors])
    laws = []
    for fs, fd in moves:
        try:
            laws.append(replace(friction, fs=fs, fd=fd))
        except SlipwaveError:  # fd above fs
            continue
    return laws


def sequence_scatter(setup: TestSetup, friction: Coulomb, *, min_drop: float,
                     gross_edge_ratio: float, elements: int,
                     sample_rate: float = SAMPLE_RATE_HZ, step: float = SCATTER_STEP,
                     detection: DetectionSettings = DEFAULT_DETECTION,
                     cache: SolverCache | None = None) -> pd.DataFrame:
    """The compared features of the law's neighbouring simulations.

    Under fs > fd a law settles in a cycle of slips that changes by whole slips with
    coefficients closer than the load cells tell apart: the numbers of slips, their
    recurrence, the first gross slip's time and the drops' medians scatter about
    their trend. The law is run at :func:`neighbouring_laws` and each run's events are
    read as the comparison reads the simulation's, so that
    :func:`slipwave.compare.compare_test` can hold against the law only what its own
    scatter does not cover.

    Parameters
    ----------
    setup, friction, min_drop, elements, sample_rate, detection, cache
        As in :func:`replay_test`.
    gross_edge_ratio
        The gross/partial edge threshold of the simulation compared (its recording's
        attrs), used for every neighbour.
    step
        How far the coefficients move, relative.

    Returns
    -------
    pandas.DataFrame
        One row per neighbour the solver follows over the whole test: ``fs``, ``fd``
        and the values of :data:`slipwave.compare.EVENT_FEATURES` and
        :data:`slipwave.compare.ORIGIN`. A neighbour it does not follow (a law next to
        one where the quasi-static contact has no solution) is left out, and
        ``attrs["left_out"]`` says which and where the solver stopped.

    """
    columns = ["fs", "fd", *(feature.name for feature in EVENT_FEATURES), ORIGIN.name]
    rows = []
    left_out = []
    for law in neighbouring_laws(friction, step):
        try:
            simulation = setup.simulate(law, elements, cache=cache)
        except SlipwaveError as err:  # the law itself was followed: the solver's words
            cause = err.__cause__ if isinstance(err.__cause__, SolverError) else err
            left_out.append(f"fs {law.fs:.6g}, fd {law.dynamic:.6g} (stopped at {cause})")
            continue
        events = detect_events(simulated_recording(simulation, setup, sample_rate=sample_rate),
                               **detection.keywords(min_drop=min_drop, edge_convention="x_axis",
                                                    gross_edge_ratio=gross_edge_ratio))
        rows.append({"fs": law.fs, "fd": law.dynamic, **event_features(events),
                     ORIGIN.name: first_wave(simulation)[0]})
    table = pd.DataFrame(rows, columns=columns)
    table.attrs["left_out"] = "; ".join(left_out)
    return table


def left_out_neighbours(friction: Coulomb, step: float, scatter: pd.DataFrame
                        ) -> list[dict[str, float]]:
    """The neighbouring laws a scatter table lacks (those the solver did not follow).

    Parameters
    ----------
    friction
        The law whose scatter it is.
    step
        How far its neighbours' coefficients moved (:func:`neighbouring_laws`).
    scatter
        :func:`sequence_scatter`'s table, as written (coefficients to 6 figures).

    Returns
    -------
    list of dict
        ``fs`` and ``fd`` of each neighbour with no row, in :func:`neighbouring_laws`'
        order.

    Examples
    --------
    >>> table = pd.DataFrame({"fs": [0.99, 1.01, 1.0], "fd": [0.5, 0.5, 0.505]})
    >>> left_out_neighbours(Coulomb(fs=1.0, fd=0.5), 0.01, table)
    [{'fs': 1.0, 'fd': 0.495}]
    """
    rows = scatter[["fs", "fd"]].to_numpy(dtype=float)
    left_out = []
    for law in neighbouring_laws(friction, step):
        found = np.isclose(rows, [law.fs, law.dynamic], rtol=1e-5, atol=0.0).all(axis=1)
        if not found.any():
            left_out.append({"fs": float(law.fs), "fd": float(law.dynamic)})
    return left_out


def contact_history(simulation: xr.Dataset, times: np.ndarray, slab: Slab | None = None, *,
                    band_mm: tuple[float, float] = BAND_MM) -> xr.Dataset:
    """Zone states and, with ``slab``, the simulated kymograph, against time.

    Parameters
    ----------
    simulation
        The solver's steps.
    times
        Each step's end, s (:func:`slipwave.solver.signals.step_times`).
    slab
        The slab simulated; ``None``: no kymograph.
    band_mm
        The kymograph's band above the interface, mm (low, high).

    Returns
    -------
    xarray.Dataset
        ``state(time, x)`` (0 open, 1 stick, 2 slip), ``wave(time)`` and, with a slab,
        ``intensity(time, x_image)``: the dark-field intensity (grey levels, no noise)
        averaged over the video kymograph's band above the interface.

    """
    keep = np.concatenate([np.diff(times) > 0, [True]])  # one row per distinct time
    ds = xr.Dataset(
        {"state": (("time", "x"), simulation["state"].values[keep].astype(np.int8),
                   {"long_name": "zone state of the contact node", "units": "1",
                    "flag_values": [0, 1, 2], "flag_meanings": STATE_NAMES}),
         "wave": ("time", simulation["wave"].values[keep].astype(str),
                  {"long_name": "the step's wave: none, partial or gross"})},
        coords={"time": ("time", times[keep], {"units": "s", "long_name": "time"}),
                "x": ("x", simulation["x"].values, {"units": "mm",
                                                    "long_name": "position along the contact"})},
        attrs={"Conventions": CONVENTIONS})
    if slab is None:
        return ds
    camera = Camera(noise=0.0)
    image = Photoelastic(slab, camera)
    rows = np.nonzero(image.inside)[0]
    height = (image.interface_row - (rows + 0.5)) / image.scale
    band = (height >= band_mm[0]) & (height <= band_mm[1])
    x = image.pixel_x[band]
    edges = np.linspace(-slab.length / 2, slab.length / 2, 2 * slab.elements + 1)
    column = np.clip(np.digitize(x, edges) - 1, 0, edges.size - 2)
    counts = np.bincount(column, minlength=edges.size - 1)
    ux, uy = simulation["ux"].values[keep], simulation["uy"].values[keep]
    rows_out = np.empty((ux.shape[0], edges.size - 1), dtype=np.float32)
    for k in range(ux.shape[0]):
        stress = image.stress(np.concatenate([ux[k], uy[k]]))[:, band]
        shown = camera.intensity * np.sin(np.pi * image.fringe_order(stress)) ** 2
        rows_out[k] = np.bincount(column, shown, minlength=edges.size - 1) / np.maximum(counts, 1)
    ds = ds.assign_coords(x_image=("x_image", 0.5 * (edges[1:] + edges[:-1]),
                                   {"units": "mm", "long_name": "position in the image"}))
    ds["intensity"] = (("time", "x_image"), rows_out,
                       {"units": "1", "long_name": "simulated dark-field intensity in the "
                        f"band {band_mm[0]}-{band_mm[1]} mm above the interface (grey levels)"})
    return ds.merge(first_gross_frames(simulation, times, image))


def first_gross_frames(simulation: xr.Dataset, times: np.ndarray, image: Photoelastic
                       ) -> xr.Dataset:
    """Simulated frames around the first gross slip: before, at its peak, after.

    The solver is quasi-static, so its frames are its states: the ends of the two
    steps before the gross slip's, the stuck peak of that step (just before the
    wave), and its end (after the wave); rendered by the camera model without noise.

    Parameters
    ----------
    simulation
        The solver's steps (with ``ux``, ``uy`` and their ``_before_wave``).
    times
        Each step's end, s.
    image
        The camera model of the slab.

    Returns
    -------
    xarray.Dataset
        ``frame(frame, row, column)`` (8-bit grey levels), ``frame_time(frame)``,
        ``frame_label(frame)``; empty without a gross slip.

    """
    gross = np.flatnonzero((simulation["wave"].values == "gross")
                           & (simulation["phase"].values == "tangential"))
    if not gross.size:
        return xr.Dataset()
    k = int(gross[0])
    rng = np.random.default_rng(0)
    chosen = [(max(k - 2, 0), "final", "two steps before"), (max(k - 1, 0), "final",
                                                             "step before"),
              (k, "before_wave", "peak, just before the gross slip"),
              (k, "final", "after the gross slip")]
    frames, labels, when = [], [], []
    for step, which, label in chosen:
        suffix = "_before_wave" if which == "before_wave" else ""
        u = np.concatenate([simulation[f"ux{suffix}"].values[step],
                            simulation[f"uy{suffix}"].values[step]])
        frames.append(image.render(image.stress(u), rng))
        labels.append(label)
        when.append(float(times[step - 1] if which == "before_wave" and step > 0
                          else times[step]))
    return xr.Dataset(
        {"frame": (("frame", "row", "column"), np.stack(frames),
                   {"long_name": "simulated photoelastic frame (no noise)", "units": "1"}),
         "frame_time": ("frame", np.array(when), {"units": "s",
                                                  "long_name": "time of the state shown"}),
         "frame_label": ("frame", np.array(labels, dtype=str))})
