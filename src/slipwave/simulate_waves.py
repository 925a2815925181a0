"""The simulate-waves stage: a filmed test simulated quasi-dynamically, its waves with a speed.

The simulate stage's solver is quasi-static: its slips have no duration and its waves no
speed. Here the test's slab, normal load and drive are run through the quasi-dynamic
contact (:func:`slipwave.solver.quasi_dynamic.simulate_quasi_dynamic`) under a
rate-and-state law, on the test's clock (the drive starts when the normal loading ends).
The run is then filmed at the video's frame rate by the virtual bench's camera and its
waves tracked on the film as the video's are (:func:`film_kymograph`,
:func:`slipwave.video.track_waves`): those are what the compare stage sets beside the
video's (:func:`slipwave.compare.compare_waves`), measured alike. The run's slip-rate
fronts (:func:`slipwave.solver.fronts.front_waves`) are kept beside them: on slow fronts
the two measures differ by a factor of two (docs, the bench page).

What it leaves out, as the solver does: the actuator's machine spring (the flat's travel
is prescribed at the test's speed) and the slab's inertia beyond radiation damping; and
the test's own camera (the film is the virtual bench's: its fringe value, blur and noise).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr
from threadpoolctl import threadpool_limits

from slipwave.defaults import BAND_MM
from slipwave.photoelastic import Camera, Photoelastic
from slipwave.setup import TestSetup
from slipwave.solver.fronts import front_waves
from slipwave.solver.quasi_dynamic import (
    Drive,
    contact_displacements,
    record_times,
    simulate_quasi_dynamic,
    slab_body,
)
from slipwave.solver.rate_state import RateState
from slipwave.solver.slab import Slab
from slipwave.video.frame import Frame
from slipwave.video.kymograph import Geometry, kymograph
from slipwave.video.waves import MIN_EXTENT, track_waves

UM_PER_M = 1e6

ONE_BLAS_THREAD = 1
"""The BLAS threads a run and its film use, whatever the caller's (Snakemake sets a job's
to its threads): a product's sums then run in one order, and a run, whose stick-slip cycle
is chaotic, is the same run in a workflow's job, a fit's worker or a shell (on the default
campaign's hl050, the log median speed's change at twice the mesh read 0.657 on one
thread and 0.592 on two)."""
FILM_CHUNK = 64
"""Frames whose stresses are computed together (:meth:`Photoelastic.stresses`)."""


def rate_state_law(settings: Mapping[str, Any]) -> RateState:
    """The config's rate-and-state law (the ``simulate_waves`` section), in the solver's units.

    Parameters
    ----------
    settings
        ``a``, ``b``, ``dc_um`` (um), ``mu0`` and ``v0_um_s`` (um/s).

    Returns
    -------
    RateState
        The aging law with those parameters.

    Examples
    --------
    >>> rate_state_law({"a": 0.01, "b": 0.015, "dc_um": 2.0, "mu0": 0.9, "v0_um_s": 1.0}).dc
    2e-06
    """
    return RateState(a=float(settings["a"]), b=float(settings["b"]),
                     dc=float(settings["dc_um"]) / UM_PER_M, mu0=float(settings["mu0"]),
                     v0=float(settings["v0_um_s"]) / UM_PER_M)


def law_text(law: RateState) -> str:
    """The law as a reader writes it, in the config's units.

    Parameters
    ----------
    law
        An aging law of one state (:func:`rate_state_law`'s).

    Returns
    -------
    str
        Its a, b, D_c, mu0 and v0.

    Examples
    --------
    >>> law_text(rate_state_law({"a": 0.01, "b": 0.015, "dc_um": 2.0, "mu0": 0.9,
    ...                          "v0_um_s": 1.0}))
    'aging law, a 0.01, b 0.015, D_c 2 um, mu0 0.9, v0 1 um/s'
    """
    return (f"{law.evolution} law, a {law.a:g}, b {law.b:g}, D_c {law.dc * UM_PER_M:g} um, "
            f"mu0 {law.mu0:g}, v0 {law.v0 * UM_PER_M:g} um/s")


def on_test_clock(run: xr.Dataset, loading: float) -> xr.Dataset:
    """A quasi-dynamic run's times moved onto its test's clock.

    The run's clock starts with the drive; the test's, with the normal loading, which
    takes ``loading`` seconds.

    Parameters
    ----------
    run
        From :func:`~slipwave.solver.quasi_dynamic.simulate_quasi_dynamic`.
    loading
        The test's loading time, s.

    Returns
    -------
    xarray.Dataset
        The run, its ``time``, ``field_time`` and ``crossing_time`` shifted, and its
        ``loading_time`` attribute set.

    Examples
    --------
    >>> run = xr.Dataset(coords={"time": [0.0, 1.0], "field_time": [0.0]})
    >>> run["crossing_time"] = ("crossing", [0.5])
    >>> moved = on_test_clock(run, 10.0)
    >>> moved["time"].values.tolist(), float(moved["crossing_time"][0])
    ([10.0, 11.0], 10.5)
    """
    run = run.assign_coords(time=run["time"] + loading, field_time=run["field_time"] + loading)
    run["crossing_time"] = run["crossing_time"] + loading
    for name in ("time", "field_time"):
        run[name].attrs.update(units="s", long_name="time on the test's clock")
    run.attrs["loading_time"] = loading
    return run


@dataclass(frozen=True)
class WavesRun:
    """A test run quasi-dynamically, filmed, and its waves measured two ways.

    Attributes
    ----------
    run
        The run (:func:`~slipwave.solver.quasi_dynamic.simulate_quasi_dynamic`'s dataset,
        on the test's clock, its fields at the field rate, without the displacements).
    fronts
        Its slip-rate fronts (:func:`~slipwave.solver.fronts.front_waves`, at least the
        video's smallest extent): each node's arrival where its slip rate passes the
        front speed.
    film
        The kymograph of the run filmed as the bench's camera films
        (:func:`film_kymograph`).
    waves
        The film's waves (:func:`slipwave.video.track_waves`): what the compare stage
        sets beside the video's, measured as the video's are.
    """

    run: xr.Dataset
    fronts: pd.DataFrame
    film: xr.Dataset
    waves: pd.DataFrame


def film_kymograph(run: xr.Dataset, slab: Slab, *, band_mm: tuple[float, float],
                   seed: int = 0) -> xr.Dataset:
    """The kymograph of a run filmed by the virtual bench's camera at its field times.

    Each field record's displacements are imaged as the bench's camera images a slab
    (:class:`slipwave.photoelastic.Photoelastic` with the default
    :class:`~slipwave.photoelastic.Camera`, its blur and sensor noise, only the pixels
    the band needs) and read as the video's frames are
    (:func:`slipwave.video.kymograph`), so that :func:`slipwave.video.track_waves` finds
    the run's waves as it finds the video's.

    Parameters
    ----------
    run
        A quasi-dynamic run with ``ux``, ``uy`` over ``field_time`` (the frames' times).
    slab
        The slab it ran.
    band_mm
        The kymograph's band, mm above the interface (the video's).
    seed
        The camera noise's seed.

    Returns
    -------
    xarray.Dataset
        The kymograph, its time the run's ``field_time``.
    """
    camera = Camera()
    photo = Photoelastic(slab, camera, below=band_mm[1] + 1.0)
    geometry = Geometry(interface_row=photo.interface_row, left=photo.left_column,
                        right=photo.left_column + photo.scale * slab.length,
                        length=slab.length)
    rng = np.random.default_rng([seed, 99])
    displacements = contact_displacements(run)
    times = run["field_time"].values

    def frames() -> Iterator[Frame]:
        for first in range(0, len(times), FILM_CHUNK):  # the stresses a chunk at a time
            chunk = photo.render_frames(photo.stresses(displacements[first : first + FILM_CHUNK]),
                                        rng)
            for k, image in enumerate(chunk, start=first):
                yield Frame(k, float(times[k]), image)

    film = kymograph(frames(), geometry, band_mm)
    film.attrs["source"] = "the quasi-dynamic run, filmed by the virtual bench's camera"
    return film


def simulate_waves(setup: TestSetup, law: RateState, *, elements: int, field_rate: float,
                   sample_rate: float, frame_rate: float,
                   band_mm: tuple[float, float] = BAND_MM) -> WavesRun:
    """A test run quasi-dynamically, filmed at the video's frame rate: its waves.

    Parameters
    ----------
    setup
        The test's configuration (its slab, normal load, speed, duration, loading time).
    law
        The interface's law.
    elements
        Elements along the contact.
    field_rate
        Records of the nodes' slip rate, state and stresses per second, kept in the run.
    sample_rate
        Records of the loads and sensors per second.
    frame_rate
        The film's frames per second (the test's video's).
    band_mm
        The kymograph's band, mm above the interface (the video's).

    Returns
    -------
    WavesRun
        The run, its slip-rate fronts, its film and the film's waves, on the test's clock.

    Examples
    --------
    >>> from slipwave.setup import Setting
    >>> values = {"length_mm": 80.0, "height_mm": 40.0, "width_mm": 50.0,
    ...           "youngs_modulus_mpa": 7.0, "poisson_ratio": 0.48, "normal_load_n": 76.0,
    ...           "speed_mm_s": 0.048, "machine_stiffness_n_mm": 40.0, "duration_s": 20.0,
    ...           "loading_time_s": 10.0}
    >>> setup = TestSetup("demo", {k: Setting(v, "example") for k, v in values.items()},
    ...                   "frame")
    >>> law = rate_state_law({"a": 0.01, "b": 0.015, "dc_um": 2.0, "mu0": 0.9,
    ...                       "v0_um_s": 1.0})
    >>> result = simulate_waves(setup, law, elements=40, field_rate=10.0, sample_rate=10.0,
    ...                         frame_rate=5.0)
    >>> float(result.run["time"][0]), result.film.sizes["time"], len(result.waves)
    (10.0, 51, 0)
    """
    loading = setup["loading_time_s"]
    driven = setup["duration_s"] - loading
    kept = record_times(driven, field_rate)
    filmed = record_times(driven, frame_rate)
    slab = setup.slab(elements)
    with threadpool_limits(limits=ONE_BLAS_THREAD):
        run = simulate_quasi_dynamic(
            slab_body(slab), law,
            Drive(normal_load=setup["normal_load_n"], drive_speed=setup["speed_mm_s"],
                  normal_control="force"),
            duration=driven, sample_rate=sample_rate, field_times=np.union1d(kept, filmed))
        film = film_kymograph(run.sel(field_time=filmed), slab, band_mm=band_mm)
    fronts = front_waves(run, min_extent=MIN_EXTENT)
    waves = track_waves(film)
    for table in (fronts, waves):
        table[["t_start", "t_end"]] += loading
    film = film.assign_coords(time=film["time"] + loading)
    film["time"].attrs.update(units="s", long_name="time on the test's clock")
    run = on_test_clock(run.sel(field_time=kept).drop_vars(["ux", "uy"]), loading)
    run.attrs["law_text"] = law_text(law)
    film.attrs.update(loading_time=loading, law_text=law_text(law), frame_rate=frame_rate)
    return WavesRun(run, fronts, film, waves)
