"""The fit-waves stage: a filmed test's rate-and-state law, from its cycle and its waves.

The quasi-dynamic contact (:func:`slipwave.simulate_waves.simulate_waves`) gives a
rate-and-state law's slips a duration and its waves a speed; here a test's a, b - a,
D_c and mu0 (at v0 1 um/s, the aging law) are inferred from what its card and its video
measure, by a synthetic likelihood (Wood 2010) read from an emulator of the runs'
features (:func:`slipwave.fit.emulator.emulator_search`).

**The statistic.** The test after its first slip and one settling window is cut into
windows of :data:`WINDOW_RECURRENCES` of its slips' median recurrence; each window's
slips (:func:`slipwave.events.detect_events`, the detect stage's settings) give
:data:`CARD_FEATURES`: the median T/|N| before a slip, the median T/|N| drop, the log of
the window's length per slip. The video's waves over the same span give
:data:`WAVE_FEATURES`: the log of the followed waves' median speed. (The share of waves
the camera could follow is not one: it steps between none and all across the prior,
which no smooth emulator reads, and moves with the mesh.)

**The likelihood at a guess.** One quasi-dynamic run of the test's slab, normal load and
drive, long enough for the settling window and :attr:`WavesFitSettings.members` windows
more, recorded as the card records it (noise-free) and filmed as the bench's camera
films (:func:`slipwave.simulate_waves.film_kymograph`), its waves tracked as the video's
(:func:`slipwave.video.track_waves`); its windows are cut as the test's. The card
features' mean has the Gaussian synthetic log-likelihood of the spring-slider fit (the
windows' shrunk covariance times (1/n + 1/K), plus the test's own windows' variance over
n and :data:`CARD_FLOOR` squared); the log median speed adds an independent Gaussian
term by its two standard errors (:data:`slipwave.compare.MEDIAN_ERROR`) and its floor.
Leaving out the card and wave features' correlation is this likelihood's approximation.

What it leaves out: the nuisances of the quasi-static fit's ensemble (the load cells'
calibration, the machine's spring: the quasi-dynamic run prescribes the flat's travel),
and the law's v0 (a change of v0 is a change of mu0).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr
from scipy.stats import multivariate_normal, qmc
from threadpoolctl import threadpool_limits

from slipwave.compare import MEDIAN_ERROR
from slipwave.defaults import BAND_MM, FIT_WAVES_DEFAULTS, FIT_WAVES_TUNABLES
from slipwave.errors import SlipwaveError
from slipwave.events.detect import DEFAULT_DETECTION, DetectionSettings, detect_events
from slipwave.fit.emulator import emulated_posterior, emulator_search
from slipwave.fit.likelihood import shrunk_covariance
from slipwave.fit.search import central_intervals
from slipwave.fit.slider import rate_state_values
from slipwave.setup import TestSetup
from slipwave.simulate_waves import (
    ONE_BLAS_THREAD,
    UM_PER_M,
    film_kymograph,
    on_test_clock,
    rate_state_law,
)
from slipwave.solver.quasi_dynamic import Drive, record_times, simulate_quasi_dynamic, slab_body
from slipwave.solver.rate_state import RateState
from slipwave.solver.signals import quasi_dynamic_signals
from slipwave.validation import read_json
from slipwave.video.waves import track_waves

PARAMETERS = ("a", "b_minus_a", "log10_dc", "mu0")
"""The search's coordinates: a, b - a, log10 of D_c in metres, mu0 at v0 = 1 um/s."""

PRIOR_BOX = np.array([[0.005, 0.02], [0.005, 0.035], [-5.0, -3.7], [0.6, 1.2]])
"""The uniform prior's bounds, one row per parameter. a: polymers' direct effect, 0.005
to 0.02 (PMMA on glass about 0.01, Berthoud et al. 1999); b - a: velocity weakening (the
test slips), up to three and a half times the smallest a; D_c: 10 to 200 um, where this
slab's fronts run slow enough for a 25 frames/s camera to follow some (with D_c of a few
um they run at metres per second, docs: "Laws with slow fronts"); mu0: 0.6 to 1.2, about
the bench's measured T/|N| (0.7-0.9) and the drop's reach either side."""

CARD_FEATURES = ("peak", "drop", "recurrence")
"""A window's card features: median T/|N| before a slip, median T/|N| drop, log of the
window's length per slip (s)."""

WAVE_FEATURES = ("speed",)
"""The video's feature: the log of the followed waves' median speed (mm/s)."""

WINDOW_RECURRENCES = 3.0
"""A window's length, in the test's median recurrences: three slips or so a window."""

CARD_FLOOR = np.array([0.003, 0.003, 0.05])
"""The smallest standard error of each card feature's window mean: the card's T/|N| over
a peak (its noise, 0.003) and a twentieth of a recurrence."""

SPEED_FLOOR = 0.1
"""The smallest standard error of the log median speed: a tenth, the scatter between the
film's and the video's median under the same law (benchmarks/RESULTS.md, quasi-dynamic
tests at the truth's mesh)."""

FASTEST_FOLLOWED = 1000.0
"""The speed (mm/s) a run none of whose waves the camera followed stands at: the contact's
80 mm in the two frame periods a followed front needs at 25 frames/s."""

MIN_WINDOWS = 2
"""Windows a test, and a guess's run, need at least."""

MIN_FOLLOWED = 2
"""Followed waves a median speed needs (fewer: the speed is not compared)."""

ABSENT_FEATURES = np.array([np.nan] * len(CARD_FEATURES) + [np.log(FASTEST_FOLLOWED)])
"""What a run lacking a feature stands at where too few runs have it to emulate it
(:data:`slipwave.fit.emulator.MIN_VALUES`): the speed, at the fastest the frames follow
(as :func:`loglik` reads a run that followed fewer than :data:`MIN_FOLLOWED`)."""


@dataclass(frozen=True)
class FilmedTest:
    """A filmed test as the fit reads it.

    Attributes
    ----------
    setup
        Its configuration (slab, normal load, speed, loading time, duration).
    frame_rate
        Its video's frames per second.
    band_mm
        Its kymograph's band, mm above the interface.
    window
        The windows' length, s.
    settle
        From the drive's start to the first window's, s.
    observed
        The mean of the windows' :data:`CARD_FEATURES`.
    spread
        Their standard deviations over the windows.
    windows
        The number of windows n.
    waves, followed
        The video's waves starting in the windows, and those the camera followed.
    speeds
        The followed waves' speeds, mm/s.
    detection
        The detection's settings (the detect stage's).
    sample_rate
        The card's samples per second.
    min_drop
        The smallest T drop the test's detection counted, N (the simulated card is
        noise-free: its slips are counted from the same size).

    """

    setup: TestSetup
    frame_rate: float
    band_mm: tuple[float, float]
    window: float
    settle: float
    observed: tuple[float, ...]
    spread: tuple[float, ...]
    windows: int
    waves: int
    followed: int
    speeds: tuple[float, ...]
    detection: DetectionSettings = DEFAULT_DETECTION
    sample_rate: float = 100.0
    min_drop: float = 0.0


def card_windows(events: pd.DataFrame, recording: xr.Dataset, start: float, window: float,
                 count: int) -> np.ndarray:
    """Each window's :data:`CARD_FEATURES`, from a test's slips.

    Parameters
    ----------
    events
        ``t_start``, ``ratio_before``, ``ratio_after`` of each slip
        (:func:`slipwave.events.detect_events`).
    recording
        The card's T and N: a window without a slip has its largest T/|N| for peak
        and no drop (a law that slides steadily is so told from one that slips).
    start
        The first window's start, s.
    window
        The windows' length, s.
    count
        The windows.

    Returns
    -------
    numpy.ndarray
        Shape (count, 3).

    Examples
    --------
    >>> slips = pd.DataFrame({"t_start": [1.0, 4.0, 7.0, 11.0], "ratio_before": 0.8,
    ...                       "ratio_after": [0.7, 0.7, 0.72, 0.7]})
    >>> card = xr.Dataset({"T": ("time", [60.0, 68.0, 70.0]), "N": ("time", [-85.0] * 3)},
    ...                   coords={"time": [0.0, 6.0, 13.0]})
    >>> card_windows(slips, card, 0.0, 6.0, 3).round(3).tolist()
    [[0.8, 0.1, 1.099], [0.8, 0.09, 1.099], [0.824, 0.0, 2.485]]
    """
    time = events["t_start"].to_numpy(dtype=float)
    before = events["ratio_before"].to_numpy(dtype=float)
    drop = before - events["ratio_after"].to_numpy(dtype=float)
    card_time = recording["time"].values
    load, normal = recording["T"].values, np.abs(recording["N"].values)
    rows = []
    for k in range(count):
        low, high = start + k * window, start + (k + 1) * window
        inside = (time >= low) & (time < high)
        slips = int(inside.sum())
        span = (card_time >= low) & (card_time < high)
        peak = (float(np.median(before[inside])) if slips
                else float(np.max(load[span] / normal[span])))
        rows.append([peak,
                     float(np.median(drop[inside])) if slips else 0.0,
                     float(np.log(window / max(slips, 0.5)))])
    return np.array(rows)


def _window_plan(events: pd.DataFrame, loading: float, end: float, window: float | None
                 ) -> tuple[float, float, int]:
    """The windows' length, the first one's start and their number for a test's slips."""
    time = np.sort(events["t_start"].to_numpy(dtype=float))
    if time.size < 3:
        raise SlipwaveError(f"{time.size} slips: a cycle needs three at least to be fitted")
    length = (WINDOW_RECURRENCES * float(np.median(np.diff(time))) if window is None
              else float(window))
    start = float(time[0]) + length  # one window after the first slip: its settling
    return length, start - loading, int((end - start) // length)


def filmed_test(setup: TestSetup, recording: xr.Dataset, waves: pd.DataFrame, *,
                frame_rate: float, band_mm: tuple[float, float] = BAND_MM,
                detection: DetectionSettings = DEFAULT_DETECTION,
                window: float | None = None) -> FilmedTest:
    """A test's card and video read as the fit reads them.

    Parameters
    ----------
    setup
        The test's configuration.
    recording
        Its card's recording (:func:`slipwave.io.read_acquisition`).
    waves
        Its video's waves (the waves stage's ``waves.csv``: :func:`slipwave.video.track_waves`'
        columns and ``t_start_card``, the start on the card's clock).
    frame_rate
        The video's frames per second.
    band_mm
        The kymograph's band, mm above the interface.
    detection
        The detection's settings.
    window
        The windows' length, s; ``None``: :data:`WINDOW_RECURRENCES` median recurrences.

    Returns
    -------
    FilmedTest
        Its windows' card features, its waves.

    Raises
    ------
    SlipwaveError
        If the test has fewer than three slips or :data:`MIN_WINDOWS` windows, or no wave.
    """
    events = detect_events(recording, **detection.keywords())
    end = float(recording["time"].values[-1])
    loading = setup["loading_time_s"]
    name = recording.attrs.get("test_id", setup.test_id)
    try:
        length, settle, count = _window_plan(events, loading, end, window)
    except SlipwaveError as err:
        raise SlipwaveError(f"test {name!r}: {err}") from err
    if count < MIN_WINDOWS:
        raise SlipwaveError(f"test {name!r}: {count} windows of {length:.3g} s after the "
                            f"first slip and its settling; the fit needs {MIN_WINDOWS}")
    rows = card_windows(events, recording, settle + loading, length, count)
    start = waves["t_start_card"]
    span = (start >= settle + loading) & (start < settle + loading + count * length)
    seen = waves[span]
    followed = seen[seen["kind"] != "unresolved"]
    if seen.empty:
        raise SlipwaveError(f"test {name!r}: its video found no wave in the windows fitted")
    return FilmedTest(setup, frame_rate, band_mm, length, settle,
                      tuple(np.nanmean(rows, axis=0)), tuple(np.nanstd(rows, axis=0, ddof=1)),
                      count, len(seen), len(followed),
                      tuple(followed["speed"].to_numpy(dtype=float)), detection,
                      float(1.0 / np.median(np.diff(recording["time"].values))),
                      float(events.attrs.get("min_drop", 0.0)))


def law_at(point: np.ndarray) -> RateState:
    """The aging law at a point of :data:`PARAMETERS` (v0 1 um/s).

    Parameters
    ----------
    point
        (a, b - a, log10 D_c in metres, mu0).

    Returns
    -------
    RateState
        The law.

    Examples
    --------
    >>> law = law_at(np.array([0.01, 0.02, -4.5, 0.9]))
    >>> round(law.b, 3), round(law.dc * 1e6, 1)
    (0.03, 31.6)
    """
    a, excess, log_dc, mu0 = (float(value) for value in point)
    return RateState(a=a, b=a + excess, dc=10.0**log_dc, mu0=mu0, v0=1e-6)


def median_point(samples: np.ndarray) -> np.ndarray:
    """The posterior's point handed on: each of :data:`PARAMETERS` at its marginal median.

    Parameters
    ----------
    samples
        Posterior samples, shape (n, 4).

    Returns
    -------
    numpy.ndarray
        (a, b - a, log10 D_c, mu0).

    Examples
    --------
    >>> median_point(np.array([[0.01, 0.02, -4.5, 0.9], [0.012, 0.01, -4.3, 0.8],
    ...                        [0.014, 0.03, -4.1, 1.0]])).tolist()
    [0.012, 0.02, -4.3, 0.9]
    """
    return np.median(samples, axis=0)


@dataclass(frozen=True)
class Simulated:
    """A guess's run, summed up as the test is.

    Attributes
    ----------
    windows
        Its windows' :data:`CARD_FEATURES`, shape (K, 3).
    waves, followed
        The film's waves in the windows, and those the camera followed.
    speeds
        The followed waves' speeds, mm/s.

    """

    windows: np.ndarray
    waves: int
    followed: int
    speeds: np.ndarray


def simulate_guess(test: FilmedTest, law: RateState, *, elements: int, members: int,
                   seed: int = 0) -> Simulated | None:
    """A guess's quasi-dynamic run of the test, filmed, summed up in windows.

    Parameters
    ----------
    test
        The test.
    law
        The guess.
    elements
        Elements along the contact.
    members
        Windows K after the run's first slip and settling.
    seed
        The film's camera noise seed.

    Returns
    -------
    Simulated or None
        None where the run failed. Its windows start one window after its first slip,
        as the test's; where that leaves fewer than ``members`` (a law that slips late,
        or never), at the test's own first window.
    """
    with threadpool_limits(limits=ONE_BLAS_THREAD):
        return _simulated(test, law, elements=elements, members=members, seed=seed)


def _simulated(test: FilmedTest, law: RateState, *, elements: int, members: int, seed: int
               ) -> Simulated | None:
    """:func:`simulate_guess` on the threads it is given."""
    setup = test.setup
    loading = setup["loading_time_s"]
    driven = test.settle + (members + 1) * test.window
    slab = setup.slab(elements)
    filmed = record_times(driven, test.frame_rate)
    try:
        run = simulate_quasi_dynamic(
            slab_body(slab), law,
            Drive(normal_load=setup["normal_load_n"], drive_speed=setup["speed_mm_s"],
                  normal_control="force"),
            duration=driven, sample_rate=test.sample_rate, field_times=filmed)
    except SlipwaveError:
        return None
    run = on_test_clock(run, loading)
    card = quasi_dynamic_signals(run, loading=loading, duration=loading + driven,
                                 sample_rate=test.sample_rate)
    card.attrs["test_id"] = setup.test_id
    events = detect_events(card, **test.detection.keywords(min_drop=test.min_drop,
                                                           edge_convention="x_axis"))
    start = (float(events["t_start"].min()) + test.window if len(events)
             else loading + driven)
    if loading + driven - start < members * test.window:
        start = loading + test.settle
    rows = card_windows(events, card, start, test.window, members)
    if events.empty:  # it slid steadily: nothing to film
        return Simulated(rows, 0, 0, np.zeros(0))
    waves = track_waves(film_kymograph(run, slab, band_mm=test.band_mm, seed=seed))
    seen = waves[(waves["t_start"] >= start)
                 & (waves["t_start"] < start + members * test.window)]
    followed = seen[seen["kind"] != "unresolved"]
    return Simulated(rows, len(seen), len(followed), followed["speed"].to_numpy(dtype=float))


def _median_and_error(speeds: np.ndarray) -> tuple[float, float]:
    """The log median speed and its standard error (from the log speeds' quartiles)."""
    logs = np.log(speeds)
    spread = float(np.subtract(*np.percentile(logs, [75, 25])))
    return float(np.median(logs)), MEDIAN_ERROR * spread / np.sqrt(logs.size)


@dataclass(frozen=True)
class MeshError:
    """The features' error from the guesses' mesh: how far twice as many elements move them.

    Attributes
    ----------
    card
        Each card feature's change (absolute), in :data:`CARD_FEATURES`' order.
    speed
        The log median speed's change (absolute; 0 where either run followed fewer than
        two waves).

    """

    card: np.ndarray
    speed: float


def mesh_error(coarse: Simulated | None, fine: Simulated | None) -> MeshError:
    """The change of the features between a guess's run and the same at twice the mesh.

    Parameters
    ----------
    coarse, fine
        The two runs (:func:`simulate_guess`).

    Returns
    -------
    MeshError
        Zero where either run failed.

    Examples
    --------
    >>> coarse = Simulated(np.array([[0.80, 0.10, 2.5], [0.82, 0.10, 2.5]]), 6, 6,
    ...                    np.array([200.0, 220.0]))
    >>> fine = Simulated(np.array([[0.82, 0.11, 2.5]]), 3, 3, np.array([240.0, 264.0]))
    >>> error = mesh_error(coarse, fine)
    >>> error.card.round(3).tolist(), round(error.speed, 3)
    ([0.01, 0.01, 0.0], 0.182)
    """
    if coarse is None or fine is None:
        return MeshError(np.zeros(len(CARD_FEATURES)), 0.0)
    card = np.abs(np.nanmean(fine.windows, axis=0) - np.nanmean(coarse.windows, axis=0))
    speed = (abs(float(np.median(np.log(fine.speeds)) - np.median(np.log(coarse.speeds))))
             if min(coarse.followed, fine.followed) >= MIN_FOLLOWED else 0.0)
    return MeshError(card, speed)


def root_mean_square(errors: list[MeshError]) -> MeshError:
    """The mesh's error over several guesses: each feature's root mean square change.

    The change varies over the prior (with D_c and b - a); each guess measures it at one
    point.

    Parameters
    ----------
    errors
        The changes measured (:func:`mesh_error`).

    Returns
    -------
    MeshError
        Zero where none was measured.

    Examples
    --------
    >>> errors = [MeshError(np.array([0.001, 0.006, 0.0]), 0.1),
    ...           MeshError(np.array([0.001, 0.002, 0.0]), 0.5)]
    >>> error = root_mean_square(errors)
    >>> error.card.round(4).tolist(), round(error.speed, 3)
    ([0.001, 0.0045, 0.0], 0.361)
    """
    if not errors:
        return MeshError(np.zeros(len(CARD_FEATURES)), 0.0)
    return MeshError(np.sqrt(np.mean([error.card**2 for error in errors], axis=0)),
                     float(np.sqrt(np.mean([error.speed**2 for error in errors]))))


def loglik(test: FilmedTest, simulated: Simulated | None, error: MeshError | None = None
           ) -> float:
    """The test's synthetic log-likelihood given a guess's run.

    Parameters
    ----------
    test
        The test.
    simulated
        The guess's run (:func:`simulate_guess`); None: failed.
    error
        The features' error from the mesh (:func:`mesh_error`), added to their variance;
        None: none.

    Returns
    -------
    float
        The card features' Gaussian synthetic log-likelihood plus the wave features'
        terms; -inf for a failed run or fewer than :data:`MIN_WINDOWS` windows with slips.
    """
    if simulated is None:
        return float("-inf")
    members = simulated.windows
    finite = members[np.all(np.isfinite(members), axis=1)]
    if finite.shape[0] < MIN_WINDOWS:
        return float("-inf")
    covariance = shrunk_covariance(finite) * (1.0 / test.windows + 1.0 / finite.shape[0])
    mesh = error if error is not None else MeshError(np.zeros(len(CARD_FEATURES)), 0.0)
    covariance += np.diag(np.asarray(test.spread) ** 2 / test.windows + CARD_FLOOR**2
                          + mesh.card**2)
    total = float(multivariate_normal.logpdf(np.asarray(test.observed),
                                             mean=finite.mean(axis=0), cov=covariance))
    if test.followed >= MIN_FOLLOWED:
        measured, measured_error = _median_and_error(np.asarray(test.speeds))
        if simulated.followed >= MIN_FOLLOWED:
            median, spread = _median_and_error(simulated.speeds)
        else:  # faster than the frames show: at the fastest speed they follow
            median, spread = np.log(FASTEST_FOLLOWED), measured_error
        variance = measured_error**2 + spread**2 + SPEED_FLOOR**2 + mesh.speed**2
        total += -0.5 * ((measured - median) ** 2 / variance + np.log(2 * np.pi * variance))
    return float(total)


def run_features(simulated: Simulated | None) -> np.ndarray:
    """A run's features as the emulator learns them.

    Parameters
    ----------
    simulated
        The run (:func:`simulate_guess`).

    Returns
    -------
    numpy.ndarray
        The mean of its windows' :data:`CARD_FEATURES` and the log median speed of the
        waves the camera followed (NaN where fewer than :data:`MIN_FOLLOWED`: the
        emulator learns the speed from the runs the camera followed); all NaN where it
        failed or has fewer than :data:`MIN_WINDOWS` windows.

    Examples
    --------
    >>> run = Simulated(np.array([[0.80, 0.10, 2.5], [0.82, 0.10, 2.7]]), 4, 1,
    ...                 np.array([200.0]))
    >>> run_features(run).round(3).tolist()
    [0.81, 0.1, 2.6, nan]
    """
    if simulated is None:
        return np.full(len(CARD_FEATURES) + len(WAVE_FEATURES), np.nan)
    finite = simulated.windows[np.all(np.isfinite(simulated.windows), axis=1)]
    if finite.shape[0] < MIN_WINDOWS:
        return np.full(len(CARD_FEATURES) + len(WAVE_FEATURES), np.nan)
    speed = (float(np.median(np.log(simulated.speeds)))
             if simulated.followed >= MIN_FOLLOWED else np.nan)
    return np.array([*finite.mean(axis=0), speed])


@dataclass(frozen=True)
class RunScatter:
    """What a run's features scatter by, typical over the runs made.

    The emulator's likelihood takes the features' means from the emulator and their
    scatter from here.

    Attributes
    ----------
    card
        The variance of a window's card features (the median over the runs).
    speed
        The standard error of a run's log median speed (the median over the runs
        with :data:`MIN_FOLLOWED` followed waves; None where none had).

    """

    card: np.ndarray
    speed: float | None

    @classmethod
    def of(cls, runs: list[Simulated | None]) -> RunScatter:
        """The typical scatter of runs.

        Parameters
        ----------
        runs
            Runs of :func:`simulate_guess` (None: failed, left out).

        Returns
        -------
        RunScatter
            Over the runs with :data:`MIN_WINDOWS` windows.

        Examples
        --------
        >>> run = Simulated(np.array([[0.80, 0.10, 2.5], [0.82, 0.10, 2.7]]), 4, 2,
        ...                 np.array([200.0, 220.0]))
        >>> scatter = RunScatter.of([run, None])
        >>> scatter.card.round(4).tolist(), round(scatter.speed, 3)
        ([0.0002, 0.0, 0.02], 0.031)
        """
        made = [run for run in runs if run is not None
                and np.all(np.isfinite(run.windows), axis=1).sum() >= MIN_WINDOWS]
        card = np.median([np.var(run.windows[np.all(np.isfinite(run.windows), axis=1)],
                                 axis=0, ddof=1) for run in made], axis=0)
        speeds = [_median_and_error(run.speeds)[1] for run in made
                  if run.followed >= MIN_FOLLOWED]
        return cls(card, float(np.median(speeds)) if speeds else None)


def emulated_loglik(test: FilmedTest, scatter: RunScatter, error: MeshError, members: int
                    ) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """The test's log-likelihood given emulated features (:func:`run_features`' order).

    As :func:`loglik` reads a run, with the card features' covariance diagonal (the
    runs' typical window variance times (1/n + 1/K)) and each feature's emulator
    variance added to its own.

    Parameters
    ----------
    test
        The test.
    scatter
        The runs' typical scatter.
    error
        The features' error from the mesh.
    members
        Windows K of a run.

    Returns
    -------
    callable
        ``(means, variances) -> log-likelihoods``, each argument of shape (n, 4).

    Examples
    --------
    >>> from slipwave.setup import TestSetup
    >>> test = FilmedTest(TestSetup("t", {}, "frame"), 25.0, (0.5, 3.0), 60.0, 60.0,
    ...                   (0.80, 0.10, 2.5), (0.001, 0.001, 0.0), 3, 6, 6,
    ...                   (200.0, 210.0, 190.0, 205.0, 200.0, 195.0))
    >>> scatter = RunScatter(np.array([1e-6, 1e-6, 0.0]), 0.02)
    >>> rate = emulated_loglik(test, scatter, MeshError(np.zeros(3), 0.0), 4)
    >>> near = np.array([[0.80, 0.10, 2.5, np.log(200.0)]])
    >>> off = near + [0.01, 0.0, 0.0, 0.0]
    >>> bool(rate(near, np.zeros((1, 4)))[0] - rate(off, np.zeros((1, 4)))[0] > 3)
    True
    """
    card_variance = (scatter.card * (1.0 / test.windows + 1.0 / members)
                     + np.asarray(test.spread) ** 2 / test.windows + CARD_FLOOR**2
                     + error.card**2)
    observed = np.asarray(test.observed)
    measured = (_median_and_error(np.asarray(test.speeds))
                if test.followed >= MIN_FOLLOWED else None)

    def gaussian(difference: np.ndarray, variance: np.ndarray) -> np.ndarray:
        return -0.5 * (difference**2 / variance + np.log(2 * np.pi * variance))

    def rate(means: np.ndarray, variances: np.ndarray) -> np.ndarray:
        card = len(CARD_FEATURES)
        total = gaussian(means[:, :card] - observed, card_variance + variances[:, :card]
                         ).sum(axis=1)
        if measured is not None:
            spread = scatter.speed if scatter.speed is not None else measured[1]
            variance = (measured[1] ** 2 + spread**2 + SPEED_FLOOR**2 + error.speed**2
                        + variances[:, card])
            total += gaussian(measured[0] - means[:, card], variance)
        return total

    return rate


@dataclass(frozen=True)
class WavesFitSettings:
    """How the fit of a filmed test searches.

    Attributes
    ----------
    elements
        Elements along the contact of each guess's run.
    members
        Windows K of each guess's run.
    design
        Points of the first Latin hypercube, per parameter.
    refinements
        Points drawn from the emulator's posterior, per parameter.
    samples
        Posterior samples kept.
    mesh_checks
        Points of the posterior run again at twice the mesh after the search: its median
        (the law the stage runs) and draws; the mesh's error carried by the posterior,
        sampled again, is then the root mean square of their features' changes and the
        design's best guess's (0: that guess's alone).
    processes
        Worker processes for the guesses' runs.
    seed
        The search's seed (and the films' camera noise's).

    """

    elements: int = FIT_WAVES_DEFAULTS["elements"]
    members: int = FIT_WAVES_DEFAULTS["members"]
    design: int = FIT_WAVES_DEFAULTS["design"]
    refinements: int = FIT_WAVES_DEFAULTS["refinements"]
    samples: int = FIT_WAVES_DEFAULTS["samples"]
    mesh_checks: int = FIT_WAVES_DEFAULTS["mesh_checks"]
    processes: int = 1
    seed: int = FIT_WAVES_DEFAULTS["seed"]


def _simulate_job(job: tuple[FilmedTest, np.ndarray, int, WavesFitSettings]
                  ) -> Simulated | None:
    """:func:`simulate_guess` of one guess at a mesh (a picklable call for the pool)."""
    test, point, elements, settings = job
    return simulate_guess(test, law_at(point), elements=elements, members=settings.members,
                          seed=settings.seed)


def _inside(points: np.ndarray) -> np.ndarray:
    """Whether points lie in the prior's box."""
    points = np.atleast_2d(points)
    return np.all((points >= PRIOR_BOX[:, 0]) & (points <= PRIOR_BOX[:, 1]), axis=1)


def _prior_draws(count: int, rng: np.random.Generator | int) -> np.ndarray:
    """``count`` Latin hypercube points of the prior's box."""
    sampler = qmc.LatinHypercube(d=PRIOR_BOX.shape[0], seed=rng)
    return qmc.scale(sampler.random(count), PRIOR_BOX[:, 0], PRIOR_BOX[:, 1])


@dataclass(frozen=True)
class WavesPosterior:
    """A filmed test's fitted law.

    Attributes
    ----------
    samples
        Posterior samples of :data:`PARAMETERS`.
    points, logliks
        The guesses and their synthetic log-likelihoods.
    mesh_error
        The features' error from the mesh, carried by every likelihood.

    """

    samples: np.ndarray
    points: np.ndarray
    logliks: np.ndarray
    mesh_error: MeshError

    def interval(self, probability: float = 0.95) -> dict[str, tuple[float, float, float]]:
        """Each parameter's median and central interval.

        Parameters
        ----------
        probability
            The interval's probability.

        Returns
        -------
        dict
            ``a``, ``b``, ``b_minus_a``, ``dc_um`` (um), ``mu0``: (median, low, high).
        """
        values = rate_state_values(self.samples)
        values["dc_um"] = UM_PER_M * values.pop("dc")
        return central_intervals(values, probability)

    def law(self) -> RateState:
        """The law the test's waves are simulated with: at the posterior's medians.

        Each of :data:`PARAMETERS` at its marginal median (b is a's median plus b - a's).

        Returns
        -------
        RateState
            The aging law (:func:`law_at`).
        """
        return law_at(median_point(self.samples))

    def to_dict(self) -> dict[str, Any]:
        """The fit as JSON-ready values.

        Returns
        -------
        dict
            ``parameters`` (:meth:`interval`), ``law`` (:meth:`law`: ``a``, ``b``,
            ``dc_um``, ``mu0``, ``v0_um_s``, the ``simulate_waves`` section's keys),
            ``guesses``, ``best`` (the best guess), ``mesh_error`` (``card`` by feature,
            ``speed``).
        """
        finite = np.isfinite(self.logliks)
        best = self.points[finite][int(np.argmax(self.logliks[finite]))]
        law = self.law()
        return {"parameters": {name: dict(zip(("value", "low", "high"), values, strict=True))
                               for name, values in self.interval().items()},
                "law": {"a": law.a, "b": law.b, "dc_um": law.dc * UM_PER_M, "mu0": law.mu0,
                        "v0_um_s": law.v0 * UM_PER_M},
                "guesses": int(self.points.shape[0]),
                "best": dict(zip(PARAMETERS, (float(v) for v in best), strict=True)),
                "mesh_error": {"card": dict(zip(CARD_FEATURES, self.mesh_error.card.tolist(),
                                                strict=True)),
                               "speed": self.mesh_error.speed}}


def fit_filmed_test(test: FilmedTest, settings: WavesFitSettings,
                    progress: Callable[[str], None] | None = None) -> WavesPosterior:
    """The posterior of (a, b - a, log10 D_c, mu0) given a filmed test.

    The features of the guesses' runs (:func:`run_features`) are emulated
    (:func:`slipwave.fit.emulator.emulator_search`), and the posterior is the test's
    likelihood given the emulated features (:func:`emulated_loglik`). After the design's
    runs, the best of them by :func:`loglik` is run again on twice the mesh, and the
    features' change (:func:`mesh_error`) is carried by every likelihood from then on, so
    that an interval does not claim what the guesses' mesh cannot resolve. That change
    varies over the prior; after the search, :attr:`WavesFitSettings.mesh_checks`
    points of the posterior (its median, the law :meth:`WavesPosterior.law` hands on, and
    draws) are run at both meshes, and the posterior is sampled again with the root mean
    square of every change measured.

    Parameters
    ----------
    test
        The test (:func:`filmed_test`).
    settings
        The search's settings.
    progress
        Called with a line after each round of guesses.

    Returns
    -------
    WavesPosterior
        Its samples, guesses (with their :func:`loglik`) and the mesh error carried.

    Raises
    ------
    SlipwaveError
        If too few guesses of the design have a run to emulate.
    """
    say = progress or (lambda _: None)
    runs: list[Simulated | None] = []
    measured: list[MeshError] = []
    with (ProcessPoolExecutor(settings.processes) if settings.processes > 1
          else contextlib.nullcontext()) as pool:

        def simulated(points: np.ndarray, elements: int) -> list[Simulated | None]:
            jobs = [(test, point, elements, settings) for point in points]
            if pool is None:
                return [_simulate_job(job) for job in jobs]
            return list(pool.map(_simulate_job, jobs))

        def simulate(points: np.ndarray) -> np.ndarray:
            made = simulated(points, settings.elements)
            runs.extend(made)
            if not measured:  # the design's best run again on twice the mesh
                first = np.array([loglik(test, run) for run in made])
                if np.isfinite(first).any():
                    best = int(np.nanargmax(np.where(np.isfinite(first), first, np.nan)))
                    fine = simulated(points[best][None, :], 2 * settings.elements)[0]
                    measured.append(mesh_error(made[best], fine))
                    say(f"mesh error at the design's best guess ({settings.elements} "
                        f"against {2 * settings.elements} elements): card "
                        f"{measured[0].card.round(4).tolist()}, log speed "
                        f"{measured[0].speed:.3f}")
            return np.array([run_features(run) for run in made])

        def carried() -> MeshError:
            return root_mean_square(measured)

        def likelihood(means: np.ndarray, variances: np.ndarray) -> np.ndarray:
            # the runs' scatter as made so far (the emulator is refitted after each batch)
            rate = emulated_loglik(test, RunScatter.of(runs), carried(), settings.members)
            return rate(means, variances)

        try:
            samples, points, _, emulator = emulator_search(
                simulate, PRIOR_BOX, _prior_draws, _inside, likelihood,
                design=settings.design, refinements=settings.refinements,
                samples=settings.samples, seed=settings.seed, progress=progress,
                absent=ABSENT_FEATURES)
        except SlipwaveError as err:
            raise SlipwaveError(f"test {test.setup.test_id!r}: {err}") from err
        if settings.mesh_checks:  # the mesh's error where the posterior is, then again
            # the posterior's median first (the law the stage runs: its change is the one a
            # comparison at another mesh meets), then draws
            rng = np.random.default_rng(settings.seed)
            drawn = samples[rng.choice(len(samples), settings.mesh_checks - 1, replace=False)]
            checked = np.vstack([median_point(samples), drawn])
            coarse = simulated(checked, settings.elements)
            fine = simulated(checked, 2 * settings.elements)
            runs.extend(coarse)
            points = np.vstack([points, checked])
            # a failed pair measures nothing (mesh_error's zeros would shrink the mean)
            measured.extend(mesh_error(c, f) for c, f in zip(coarse, fine, strict=True)
                            if c is not None and f is not None)
            error = carried()
            say(f"mesh error over {len(measured)} guesses (root mean square): card "
                f"{error.card.round(4).tolist()}, log speed {error.speed:.3f}")
            samples = emulated_posterior(emulator, points, _inside,
                                         samples=settings.samples, seed=settings.seed)
    error = carried()
    logliks = np.array([loglik(test, run, error) for run in runs])
    return WavesPosterior(samples, points, logliks, error)


def fit_record(test: FilmedTest, posterior: WavesPosterior, settings: WavesFitSettings
               ) -> dict[str, Any]:
    """What ``slipwave fit-waves`` writes of a test's fit (``fit_waves.schema.json``).

    Parameters
    ----------
    test
        The test fitted.
    posterior
        Its fit.
    settings
        The search's settings.

    Returns
    -------
    dict
        :meth:`WavesPosterior.to_dict`, with ``test`` (the windows, their features'
        mean and spread, the waves in them, those followed and their median speed),
        ``settings`` (all but the processes, which change no number) and ``detection``.
        The test's identity is the caller's to stamp.
    """
    speeds = np.asarray(test.speeds, dtype=float)
    return {**posterior.to_dict(),
            "test": {"windows": test.windows, "window_s": test.window,
                     "settle_s": test.settle,
                     "features": dict(zip(CARD_FEATURES, test.observed, strict=True)),
                     "spread": dict(zip(CARD_FEATURES, test.spread, strict=True)),
                     "waves": test.waves, "followed": test.followed,
                     "median_speed_mm_s": float(np.median(speeds)) if speeds.size else None,
                     "frame_rate": test.frame_rate},
            "settings": {name: getattr(settings, name) for name in FIT_WAVES_TUNABLES},
            "detection": test.detection.to_dict()}


def read_waves_fit(path: str | PathLike[str]) -> dict[str, Any]:
    """A ``fit_waves.json``, held to its schema, its law one the solver takes.

    Parameters
    ----------
    path
        The file (``slipwave fit-waves -o``).

    Returns
    -------
    dict
        Its content (:func:`fit_record`).

    Raises
    ------
    SlipwaveError
        ``<path>: <key>: <what is wrong>`` (or the line and column of broken JSON).
    """
    record = read_json(path, "fit_waves")
    try:
        rate_state_law(record["law"])
    except (SlipwaveError, ValueError) as err:
        raise SlipwaveError(f"{path}: law: {err}") from err
    return record
