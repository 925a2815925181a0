"""The fit stage: a test's friction law, fitted on its slip events through the solver.

A law's parameters are found by weighted least squares on event features: T/|N|
before and after each gross slip, the first slips' times, the gross slips' recurrence,
the numbers of gross and partial slips (:func:`feature_residuals`), with the law's own
cycle of slips as a scatter the fit cannot remove (:data:`SEQUENCE_SIGMA`). Each
evaluation runs the solver along the test's own load path
(:meth:`slipwave.setup.TestSetup.load_path`), so a fit costs tens of simulations;
they are cached by parameters within a fit, and the slab's condensation and normal
approach are computed once (:class:`~slipwave.solver.SolverCache`). The measured and
the simulated recordings go through the same detection, with the campaign's settings
(:class:`~slipwave.events.DetectionSettings`). The search is derivative-free
(a scan, then Nelder-Mead): the features are piecewise smooth in the parameters (a
partial slip more or less changes the history), which finite-difference Jacobians do
not survive. 95 % intervals join the Gauss-Newton covariance of the residuals' secant
slopes (two runs per parameter, a few partial slips apart), with the load cells'
calibration range added in quadrature to each coefficient's, and the region where the
misfit rises by less than 3.84, both scaled by the reduced misfit when the law does not
reach the noise; laws are compared by Akaike's criterion (AIC).

The fitted coefficients depend on the mesh they were fitted with (``elements``): the
contact's corner concentrates the stress, so T/|N| at a gross slip for a given fs
changes with the element size (see the documentation's methods).

Examples
--------
>>> law_of("slip-weakening", {"fs": 1.0, "fd": 0.6, "dc": 0.2})
SlipWeakening(fs=1.0, fd=0.6, fs_final=None, runin_slips=0, dc=0.2)
"""

from __future__ import annotations

import time as clock
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from itertools import pairwise
from os import PathLike
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr
from scipy.optimize import minimize

from slipwave.compare import recurrence
from slipwave.defaults import (
    FIT_ELEMENTS,
    FIT_MAX_EVALUATIONS,
    FIT_MESH_CHECK,
    LOAD_CALIBRATION,
)
from slipwave.errors import SlipwaveError
from slipwave.events.detect import DEFAULT_DETECTION, DetectionSettings, detect_events
from slipwave.setup import GEOMETRY, TestSetup
from slipwave.solver import Coulomb, SlipWeakening, SolverCache
from slipwave.solver.signals import clean_signals, step_times
from slipwave.validation import read_json, setup_value_problem

LAWS: dict[str, tuple[str, ...]] = {
    "coulomb": ("fs", "fd"),
    "run-in": ("fs", "fd", "fs_final", "runin_slips"),
    "slip-weakening": ("fs", "fd", "dc"),
}
"""The friction laws a test is fitted with, and their parameters."""

UNITS = {"fs": "1", "fd": "1", "fs_final": "1", "runin_slips": "gross slips", "dc": "mm"}

BOUNDS = {"fs": (0.05, 3.0), "fd": (0.02, 2.5), "fs_final": (0.05, 3.0),
          "runin_slips": (1.0, 12.0), "dc": (0.002, 5.0)}
"""Search bounds of each parameter."""

ZONE_ELEMENTS = 3.0
"""Elements a slip-weakening law's process zone spans at least, so that the law's
features do not depend on the mesh (Day et al. 2005 ask 3 or more of a rupture
simulation's cohesive zone; the mesh study, docs "Mesh convergence", found Dc 0.02 mm
converged from 2.9 elements across its zone, not at 1.4). A shorter Dc is raised to it:
on the fit's mesh it could not be told from that one."""

RATIO_SIGMA = 0.005
"""Uncertainty given to a T/|N| at a slip: the card's noise over a few samples and the
onset's sampling."""
TIME_SIGMA_S = 1.0
"""Uncertainty given to a gross slip's time, s."""
SEQUENCE_SIGMA = 0.015
"""Uncertainty of the law's own making on T/|N| before slips. Under fs > fd the
cascade settles into cycles whose peak T/|N| depends on which partial slips came
before, and that changes by whole slips as the coefficients move, the same for every
gross slip of a run. No parameter then reproduces a test's sequence slip for slip, and
the fit must not take a lucky sequence for the truth: a shift common to the gross
slips' T/|N| before is a nuisance of this standard deviation, and the first slip's
T/|N| is uncertain by as much. T/|N| after a gross slip has no such scatter (it is
fd)."""
SLIP_SIGMA = 0.01
"""Uncertainty of the law's own making on each paired gross slip's T/|N| before, on top
of :data:`SEQUENCE_SIGMA`'s offset common to them all: which partial slips came before
a gross slip changes its own peak too. Without it, a law that misses the whole
sequence but shifts it as one (a shift the offset absorbs) could beat the truth on a
test's first slips alone."""
COUNT_SIGMA = 0.25
"""Relative uncertainty of the numbers of slips and of the gross slips' recurrence.
For partial slips, several small slips of the model may fall in one detected drop and
the smallest hide in the noise; for gross slips, the cycle the law settles in (see
:data:`SEQUENCE_SIGMA`), whose number of slips jumps as the coefficients move."""
PARTIAL_DROP_SIGMA = 0.2
"""Relative uncertainty of the law's own making on the partial slips' median drop, on
top of the measured median's standard error (:func:`median_error`): which partial
slips merge into one detected drop, and how many there are, changes with the
sequence."""
PAIRED_GROSS = 5
"""The first gross slips, whose T/|N| before is fitted one by one (a run-in's rise);
the later ones by their quartiles, as T/|N| after all of them: paired in order they
would turn one slip more or less in the cycle into a misfit of every later pair,
whereas their spread (slips that stop short of fd under slip-weakening) is kept."""
ROUGHNESS_STEP = 0.002
"""How far, relative, the estimate's friction coefficients are moved together, down and
up, to read the misfit's roughness where it is best: less than the load cells tell
apart (their calibration, a scale of every T/|N|, is a nuisance of the misfit already).
Under fs > fd the cycle a law settles in changes with coefficients this close, and
with it the misfit (by orders of magnitude; ``benchmarks/RESULTS.md``). A search that
tries some hundred laws therefore ends on the luckiest of many equally plausible
cycles, and its misfit understates the law's mismatch; its neighbours' misfits do not,
and they scale the intervals (:func:`fit_law`)."""
REJECTED_AIC = 10.0
"""A law whose AIC exceeds the best one's by more is rejected (Burnham & Anderson: no
support)."""


@dataclass(frozen=True)
class SlipFeatures:
    """What a fit compares: gross slips one by one, partial slips by their number.

    Attributes
    ----------
    gross
        One row per gross slip: ``t_start`` (s), ``ratio_before``, ``ratio_after``,
        ``drop`` (N).
    partial_slips
        Partial slips at least ``min_drop`` large.
    min_drop
        The smallest drop counted, N.
    duration
        The recording's length, s.
    sample_rate
        The card's sampling rate, Hz.
    first_time, first_ratio
        Start and T/|N| before the first slip of any kind (NaN: no slip). It comes
        before any visible slip has redistributed the load, so its T/|N| rises
        steadily with fs (by about 1.2 per unit of fs on 80 elements), and it is what
        carries fs most directly: at gross slips T/|N| rises and falls with fs as the
        partial slips before them change.
    partial_drops
        The partial slips' T drops, N (empty: not known).

    """

    gross: pd.DataFrame
    partial_slips: int
    min_drop: float
    duration: float
    sample_rate: float
    first_time: float = float("nan")
    first_ratio: float = float("nan")
    partial_drops: np.ndarray = field(default_factory=lambda: np.zeros(0))


_GROSS_COLUMNS = ("t_start", "ratio_before", "ratio_after", "drop")

WAVE_SPEED_MM_S = 200.0
"""How fast a simulated slip crosses its extent in the simulated recording (the
quasi-static solver has no time): it sets a drop's duration, as the virtual bench's."""


ALIKE_EDGE_RATIO = 0.9
"""A partial slip whose DG/DD ratio is this fraction of the gross slips' median or more
moves the edges as they do: :func:`split_edge_ratios` leaves it out, since a threshold
between it and the gross slips would call most measured gross slips partial on a short
slab, whose gross slips' ratios lie close together."""


def edge_threshold(simulation: xr.Dataset, *, edge_reference: str = "frame") -> float:
    """The DG/DD jump ratio that tells this test's gross slips from its partial ones.

    Read off the simulation's own slips: halfway (geometric mean) between the typical
    (median) ratio of its gross slips and the largest ratio, below that, of a partial
    slip whose far-edge jump shows (a tenth of the gross slips' median jump or more);
    half the median if no partial slip moves the far edge. The median, not the
    smallest gross ratio: the first gross slips start from the normal loading's
    stress state, not a stick-slip cycle's, and move the far edge less; in a law fitted
    coarsely the first can come down among the partial slips, and a threshold at the
    smallest would call the measured partial slips gross. (A partial
    slip that stops just short of the far edge moves it as a gross slip does: it cannot
    be told by the edges, and is left out.) Jumps are along +x, in the frame the edge
    sensors read against: ``flat`` subtracts the flat's jump (the sensors then see the
    slip).

    Parameters
    ----------
    simulation
        From :func:`slipwave.solver.simulate` along the test's load path.
    edge_reference
        ``frame`` or ``flat`` (:data:`slipwave.setup.EDGE_REFERENCES`).

    Returns
    -------
    float
        The ratio (``--gross-edge-ratio`` of ``slipwave detect``).

    Raises
    ------
    SlipwaveError
        If the simulation has no gross slip to read it from.

    """
    wave = simulation["wave"].values
    tangential = simulation["phase"].values == "tangential"
    flat = simulation["DT"].values - simulation["DT_before_wave"].values
    jumps = {}
    for channel in ("DG", "DD"):
        jump = simulation[channel].values - simulation[f"{channel}_before_wave"].values
        jumps[channel] = jump - flat if edge_reference == "flat" else jump
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = jumps["DG"] / jumps["DD"]
    slips = tangential & np.isin(wave, ["gross", "partial"]) & np.isfinite(ratio)
    return split_edge_ratios(ratio[slips], jumps["DG"][slips], wave[slips] == "gross")


def split_edge_ratios(ratio: np.ndarray, far_jump: np.ndarray, gross: np.ndarray) -> float:
    """The DG/DD ratio between a set of slips known to be gross or partial.

    Halfway (geometric mean) between the gross slips' median ratio and the largest ratio,
    below that median, of a partial slip whose far-edge jump shows (a tenth of the gross
    slips' median or more); half the median if there is none (see
    :func:`edge_threshold` for why the median). A partial slip within
    :data:`ALIKE_EDGE_RATIO` of the median moves the edges as a gross slip does and is
    left out: no threshold tells it.

    Parameters
    ----------
    ratio
        DG/DD jump ratio of each slip, along +x.
    far_jump
        The far (left) edge's jump of each slip, mm.
    gross
        Which slips are gross.

    Returns
    -------
    float
        The threshold.

    Raises
    ------
    SlipwaveError
        If no slip is gross.

    Examples
    --------
    The partial slip at 0.9 barely moves the far edge and is left out: the threshold
    lies between 0.5 and the gross slips' median, 1.9.

    >>> ratio = split_edge_ratios(np.array([2.0, 1.8, 0.5, 0.9]),
    ...                           np.array([1.0, 1.0, 0.3, 0.01]),
    ...                           np.array([True, True, False, False]))
    >>> round(ratio, 3)
    0.975

    A partial slip at 1.85, as close to the gross slips as they are to each other, is
    left out too.

    >>> ratio = split_edge_ratios(np.array([2.0, 1.8, 0.5, 1.85]),
    ...                           np.array([1.0, 1.0, 0.3, 0.5]),
    ...                           np.array([True, True, False, False]))
    >>> round(ratio, 3)
    0.975
    """
    ratio = np.asarray(ratio, dtype=float)
    far_jump = np.abs(np.asarray(far_jump, dtype=float))
    gross = np.asarray(gross, dtype=bool) & np.isfinite(ratio)
    if not gross.any():
        raise SlipwaveError("the simulation has no gross slip to set the edge threshold by")
    typical = float(np.median(ratio[gross]))
    shows = 0.1 * np.median(far_jump[gross])
    partial = ~gross & (far_jump >= shows) & np.isfinite(ratio)
    below = ratio[partial][ratio[partial] < ALIKE_EDGE_RATIO * typical]
    if not below.size or below.max() <= 0:
        return 0.5 * typical
    return float(np.sqrt(typical * below.max()))


def detected_edge_threshold(simulation: xr.Dataset, setup: TestSetup, *, min_drop: float,
                            sample_rate: float,
                            detection: DetectionSettings = DEFAULT_DETECTION) -> float:
    """The edge threshold read off a simulation's slips as detection sees them.

    The simulation goes through the measurement's detection
    (:func:`simulated_events`); each detected event is gross when one of the
    solver's gross slips falls in it, and :func:`split_edge_ratios` sets the
    threshold between the two. Read this way, not per load step
    (:func:`edge_threshold`), because detection measures each edge's jump over the
    whole event, partial slips that follow each other within it included, and the
    threshold must lie between the measured partial and gross slips as detection reads
    them.

    Parameters
    ----------
    simulation
        From :func:`slipwave.solver.simulate` along the test's load path.
    setup
        The test's setup.
    min_drop
        The measurement's smallest drop, N.
    sample_rate
        The card's sampling rate, Hz.
    detection
        The detection's settings (the measurement's).

    Returns
    -------
    float
        The ratio.

    Raises
    ------
    SlipwaveError
        If no detected event holds a gross slip.

    """
    events = simulated_events(simulation, setup, min_drop=min_drop, sample_rate=sample_rate,
                              detection=detection)
    times = step_times(simulation, speed=setup["speed_mm_s"],
                       loading_time=setup["loading_time_s"])
    slips = (simulation["phase"].values == "tangential") & (
        simulation["wave"].values == "gross")
    onsets = times[slips]
    slack = 2.0 / sample_rate
    starts = events["t_start"].to_numpy(dtype=float)
    ends = events["t_end"].to_numpy(dtype=float)
    gross = np.array([bool(((onsets >= start - slack) & (onsets <= end + slack)).any())
                      for start, end in zip(starts, ends, strict=True)], dtype=bool)
    return split_edge_ratios(events["edge_ratio"].to_numpy(dtype=float),
                             events["DG_jump"].to_numpy(dtype=float), gross)


def slip_features(events: pd.DataFrame, *, gross_edge_ratio: float, min_drop: float,
                  duration: float, sample_rate: float) -> SlipFeatures:
    """Features of detected events, gross slips told by their edge jumps.

    A drop is a gross slip when the far edge's jump is significant (at least the
    detection's ``DG_min_jump``, from ``events.attrs``; any, without it) and its ratio
    to the near edge's is at least ``gross_edge_ratio`` (as
    :func:`~slipwave.events.classify_events` decides).

    Parameters
    ----------
    events
        From :func:`~slipwave.events.detect_events`.
    gross_edge_ratio
        The test's threshold (:func:`edge_threshold`).
    min_drop, duration, sample_rate
        As in :class:`SlipFeatures`.

    Returns
    -------
    SlipFeatures
        The gross slips and the number of partial ones.

    """
    if events.empty:
        return SlipFeatures(pd.DataFrame(columns=list(_GROSS_COLUMNS)), 0, min_drop, duration,
                            sample_rate)
    significant = np.abs(events["DG_jump"].to_numpy(dtype=float)) >= events.attrs.get(
        "DG_min_jump", 0.0)
    gross = significant & (events["edge_ratio"].to_numpy(dtype=float) >= gross_edge_ratio)
    first = int(np.argmin(events["t_start"].to_numpy(dtype=float)))
    return SlipFeatures(events.loc[gross, list(_GROSS_COLUMNS)].reset_index(drop=True),
                        int((~gross).sum()), min_drop, duration, sample_rate,
                        float(events["t_start"].iloc[first]),
                        float(events["ratio_before"].iloc[first]),
                        events.loc[~gross, "drop"].to_numpy(dtype=float))


def measured_events(recording: xr.Dataset, *,
                    detection: DetectionSettings = DEFAULT_DETECTION) -> pd.DataFrame:
    """A recording's events for a fit: every T drop with its loads and edge jumps.

    Parameters
    ----------
    recording
        From :func:`slipwave.io.read_acquisition`.
    detection
        The detection's settings (the detect stage's).

    Returns
    -------
    pandas.DataFrame
        :func:`~slipwave.events.detect_events`'s table (its ``kind`` is not used: the
        fit classifies with the simulation's threshold).

    Raises
    ------
    SlipwaveError
        If the recording has no slip, no N (T/|N| unknown) or no DG/DD.

    """
    events = detect_events(recording, **detection.keywords())
    test_id = recording.attrs.get("test_id", "?")
    if events.empty:
        raise SlipwaveError(f"test {test_id!r}: no slip detected in "
                            f"{recording.attrs.get('source', 'the recording')} (T never drops "
                            "by more than the detection's threshold): no friction law can be "
                            "fitted on stick alone")
    if events["ratio_before"].isna().all():
        raise SlipwaveError(f"test {test_id!r}: no N channel: the fit compares T/|N| at each "
                            "slip, and a nominal normal_load_n cannot stand in for the N that "
                            "moves with every slip; a recording with N is needed")
    if events["DG_jump"].isna().all() or events["DD_jump"].isna().all():
        raise SlipwaveError(f"test {test_id!r}: no DG and DD channels: gross slips cannot be "
                            "told from partial ones, nothing to fit")
    time = recording["time"].values
    events.attrs["duration"] = float(time[-1] - time[0])
    events.attrs["sample_rate"] = float(1.0 / np.median(np.diff(time)))
    return events


def simulated_events(simulation: xr.Dataset, setup: TestSetup, *, min_drop: float,
                     sample_rate: float,
                     detection: DetectionSettings = DEFAULT_DETECTION) -> pd.DataFrame:
    """A simulation's events, detected as the measurement's are.

    The simulation becomes a noise-free recording sampled like the test
    (:func:`slipwave.solver.signals.clean_signals`, its edges in the test's edge
    reference) and goes through the same detection, so that what detection does to a
    slip (a trough read as the reloading starts, a peak between samples) is on both
    sides of the comparison.

    Parameters
    ----------
    simulation
        From :func:`slipwave.solver.simulate` along the test's load path.
    setup
        The test's setup (speed, normal loading time, duration, edge reference).
    min_drop
        The measurement's smallest drop, N.
    sample_rate
        The card's sampling rate, Hz.
    detection
        The detection's settings (the measurement's; a simulated recording's edges
        read along +x).

    Returns
    -------
    pandas.DataFrame
        As :func:`~slipwave.events.detect_events`.

    """
    recording = simulated_recording(simulation, setup, sample_rate=sample_rate)
    recording.attrs["test_id"] = setup.test_id
    return detect_events(recording, **detection.keywords(min_drop=min_drop,
                                                          edge_convention="x_axis"))


def simulated_recording(simulation: xr.Dataset, setup: TestSetup, *,
                        sample_rate: float) -> xr.Dataset:
    """A simulation as the test's card records it, noise-free.

    Parameters
    ----------
    simulation, setup, sample_rate
        As in :func:`simulated_events`.

    Returns
    -------
    xarray.Dataset
        T, N, DG, DD, DT against time (:func:`slipwave.solver.signals.clean_signals`),
        the edges read against the flat when the test's sensors are.

    """
    recording = clean_signals(simulation, speed=setup["speed_mm_s"],
                              loading_time=setup["loading_time_s"],
                              duration=setup["duration_s"], sample_rate=sample_rate,
                              wave_speed=WAVE_SPEED_MM_S)
    if setup.edge_reference == "flat":  # the sensors read the edges against the flat
        for channel in ("DG", "DD"):
            recording[channel] = recording[channel] - recording["DT"]
    return recording


def feature_residuals(simulated: SlipFeatures, measured: SlipFeatures, *,
                      calibration_error: float = 0.0) -> np.ndarray:
    """Weighted differences simulated - measured, one per feature.

    T/|N| before each of the first :data:`PAIRED_GROSS` measured gross slips, paired
    in order, and the quartiles over the later ones; the quartiles of T/|N| after every
    gross slip (a gross slip or quartile the simulation lacks counts as T/|N| 0.1
    away); the time of the first gross slip (missing: the recording's end) and the
    gross slips' median recurrence; the numbers of gross and of partial slips; where
    the measurement has at least three partial slips with known drops, their median
    drop (uncertain by its standard error and :data:`PARTIAL_DROP_SIGMA` in
    quadrature; 0 where the simulation has none, whose number already counts); and,
    where the measurement has a slip, T/|N| before the first slip of any kind and its
    time (missing: as a missing gross slip). Each T/|N| is uncertain by
    :data:`RATIO_SIGMA`, a paired one by :data:`SLIP_SIGMA` too, in quadrature;
    those before the gross slips also share an offset b, a nuisance of standard
    deviation :data:`SEQUENCE_SIGMA` (the cycle the law settles in), profiled out in
    closed form, its prior b / sd a residual; the first slip's T/|N| is uncertain by
    :data:`RATIO_SIGMA` and :data:`SEQUENCE_SIGMA` in quadrature. A time is uncertain by
    :data:`TIME_SIGMA_S` and half the measured recurrence in quadrature; the counts
    and the recurrence by :data:`COUNT_SIGMA` of the measured value (at least 1 gross
    slip, 3 partial ones, :data:`TIME_SIGMA_S`). Later gross slips are not timed one
    by one: a cycle a little longer shifts every later slip, and they would count the
    same difference many times.

    With ``calibration_error``, the load cells' calibration is a nuisance too: every
    simulated T/|N| is scaled by (1 + c), c of standard deviation
    sqrt(2) ``calibration_error`` (the T and N cells), profiled out with b; its
    prior c / sd is the last residual. A scale error common to every T/|N| then moves
    the coefficients as far as the data allow, and the intervals widen by as much,
    whatever the sensitivity of T/|N| to each parameter.

    Parameters
    ----------
    simulated, measured
        From :func:`slip_features`.
    calibration_error
        Relative calibration uncertainty of each load cell; 0: none.

    Returns
    -------
    numpy.ndarray
        The residuals, each in units of its uncertainty.

    Examples
    --------
    >>> gross = pd.DataFrame({"t_start": [10.0], "ratio_before": [0.7],
    ...                       "ratio_after": [0.6], "drop": [8.0]})
    >>> one = SlipFeatures(gross, 2, 0.3, 60.0, 100.0)
    >>> feature_residuals(one, one).tolist()
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    >>> first = SlipFeatures(gross, 2, 0.3, 60.0, 100.0, first_time=4.0, first_ratio=0.5)
    >>> later = SlipFeatures(gross, 2, 0.3, 60.0, 100.0, first_time=5.0, first_ratio=0.52)
    >>> feature_residuals(later, first).round(3).tolist()  # T/|N| 0.02 and 1 s later
    [0.0, 0.0, 0.0, 0.0, 1.265, 0.0, 1.0, 0.0, 0.0, 0.0]

    A gross slip 0.01 higher is the slip's own scatter and the cycle's offset: it
    costs about 0.3, not 4.

    >>> higher = SlipFeatures(gross.assign(ratio_before=[0.71]), 2, 0.3, 60.0, 100.0)
    >>> round(float(np.sum(feature_residuals(higher, one) ** 2)), 2)
    0.29
    """
    m, s = measured.gross, simulated.gross
    paired = min(PAIRED_GROSS, len(m))
    later = len(m) > paired  # the measurement has gross slips beyond the paired ones
    measured_before = m["ratio_before"].to_numpy(dtype=float)
    simulated_before = s["ratio_before"].to_numpy(dtype=float)
    measured_ratios = [
        np.concatenate([measured_before[:paired], _quartiles(measured_before[paired:])]),
        _quartiles(m["ratio_after"].to_numpy(dtype=float))]
    simulated_ratios = [
        np.concatenate([simulated_before[:paired],
                        _quartiles(simulated_before[paired:]) if later else []]),
        _quartiles(s["ratio_after"].to_numpy(dtype=float)) if len(m) else np.zeros(0)]
    simulated_times = [s["t_start"].to_numpy(dtype=float)[: min(1, len(m))]]
    measured_times = [m["t_start"].to_numpy(dtype=float)[:1]]
    if np.isfinite(measured.first_ratio):
        found = np.isfinite(simulated.first_ratio)
        simulated_ratios.append(np.array([simulated.first_ratio] if found else []))
        measured_ratios.append(np.array([measured.first_ratio]))
        simulated_times.append(np.array([simulated.first_time] if found else []))
        measured_times.append(np.array([measured.first_time]))
    ratios, offsets, t = [], [], []
    for simulated_ratio, measured_ratio in zip(simulated_ratios, measured_ratios, strict=True):
        n = simulated_ratio.size
        # simulated T/|N| (0 where unpaired) and simulated - measured (a missing slip: 0.1)
        ratios.append(np.pad(simulated_ratio, (0, measured_ratio.size - n)))
        offsets.append(np.concatenate([simulated_ratio - measured_ratio[:n],
                                       np.full(measured_ratio.size - n, 0.1)]))
    for simulated_time, measured_time in zip(simulated_times, measured_times, strict=True):
        n = simulated_time.size
        t.append(np.concatenate([simulated_time - measured_time[:n],
                                 measured.duration - measured_time[n:]]))
    measured_recurrence = recurrence(measured.gross)
    counts = [(len(s) - len(measured.gross)) / max(1.0, COUNT_SIGMA * len(measured.gross)),
              (simulated.partial_slips - measured.partial_slips)
              / max(3.0, COUNT_SIGMA * measured.partial_slips)]
    if np.isfinite(measured_recurrence):
        simulated_recurrence = recurrence(s)
        if not np.isfinite(simulated_recurrence):
            simulated_recurrence = measured.duration
        counts.append((simulated_recurrence - measured_recurrence)
                      / max(TIME_SIGMA_S, COUNT_SIGMA * measured_recurrence))
    if measured.partial_drops.size >= 3:
        median = float(np.median(measured.partial_drops))
        sigma_drop = median * np.hypot(median_error(measured.partial_drops) / median,
                                       PARTIAL_DROP_SIGMA)
        counts.append((float(np.median(simulated.partial_drops)) - median) / sigma_drop
                      if simulated.partial_drops.size else 0.0)
    # whitened: the first slip's T/|N| has the cycle's scatter on its own
    sigma = np.concatenate([np.full(r.size, RATIO_SIGMA if which < 2 else
                                    np.hypot(RATIO_SIGMA, SEQUENCE_SIGMA))
                            for which, r in enumerate(measured_ratios)])
    sigma[:paired] = np.hypot(RATIO_SIGMA, SLIP_SIGMA)
    a = np.concatenate(ratios).astype(float) / sigma
    d = np.concatenate(offsets).astype(float) / sigma
    # the cycle's offset b moves the paired T/|N| before gross slips; c scales them all
    e = np.zeros_like(d)
    e[: simulated_ratios[0].size] = 1.0 / sigma[: simulated_ratios[0].size]
    shares = [(e, SEQUENCE_SIGMA)]
    if calibration_error > 0:
        shares.append((a, np.sqrt(2.0) * calibration_error))
    columns = np.column_stack([column for column, _ in shares])
    spreads = np.array([spread for _, spread in shares])
    nuisance = np.linalg.solve(columns.T @ columns + np.diag(spreads**-2.0), -columns.T @ d)
    d = d + columns @ nuisance
    prior = nuisance / spreads
    timing = np.hypot(TIME_SIGMA_S, measured_recurrence / 2.0
                      if np.isfinite(measured_recurrence) else 0.0)
    return np.concatenate([d, np.concatenate(t) / timing, counts, prior])


def median_error(values: np.ndarray) -> float:
    """The standard error of a sample's median, from its interquartile range.

    sqrt(pi / 2) sigma / sqrt(n), the normal sample's, with sigma read off the
    interquartile range (IQR / 1.349), which the long tail of slip sizes does not pull.

    Parameters
    ----------
    values
        The sample (at least two values).

    Returns
    -------
    float
        The median's standard error, in the values' units.

    Examples
    --------
    >>> round(median_error(np.array([1.0, 2.0, 3.0, 4.0, 5.0, 100.0])), 3)
    0.948
    """
    q1, q3 = np.quantile(values, [0.25, 0.75])
    return float(np.sqrt(np.pi / 2.0) * (q3 - q1) / 1.349 / np.sqrt(values.size))


def _quartiles(values: np.ndarray) -> np.ndarray:
    """The quartiles (25, 50 and 75 %); none of none."""
    return np.quantile(values, [0.25, 0.5, 0.75]) if values.size else np.zeros(0)


def law_of(name: str, params: Mapping[str, float]) -> Coulomb:
    """The solver's friction law of a fitted law's name and parameters.

    Parameters
    ----------
    name
        One of :data:`LAWS`.
    params
        Its parameters.

    Returns
    -------
    Coulomb
        :class:`~slipwave.solver.Coulomb` (with run-in) or
        :class:`~slipwave.solver.SlipWeakening`.

    """
    if name == "coulomb":
        return Coulomb(fs=params["fs"], fd=params["fd"])
    if name == "run-in":
        return Coulomb(fs=params["fs"], fd=params["fd"], fs_final=params["fs_final"],
                       runin_slips=params["runin_slips"])  # type: ignore[arg-type]
    if name == "slip-weakening":
        return SlipWeakening(fs=params["fs"], fd=params["fd"], dc=params["dc"])
    raise SlipwaveError(f"unknown friction law {name!r}; known: {', '.join(LAWS)}")


@dataclass
class LawFit:
    """One law fitted to one test.

    Attributes
    ----------
    law
        Its name (:data:`LAWS`).
    values, low, high
        Each parameter's estimate and 95 % interval.
    misfit
        The weighted sum of squared residuals at the estimate (chi-square).
    features
        How many residuals.
    aic
        misfit + 2 k, k the number of parameters.
    evaluations
        Simulations run.
    seconds
        Time the fit took.
    interval_method
        ``secant`` (the Gauss-Newton covariance of the residuals' secant slopes,
        joined with :func:`misfit_intervals`' region), or ``curvature``, ``axes``,
        ``evaluations`` (:func:`misfit_intervals`) when a secant could not be run.
    edge_threshold
        The gross/partial edge-jump ratio of the simulation at the estimate.
    nearby_misfit
        The misfits with the estimate's friction coefficients :data:`ROUGHNESS_STEP`
        lower and higher: how rough the misfit is where it is best (inf: the solver
        could not follow that law).

    """

    law: str
    values: dict[str, float]
    low: dict[str, float]
    high: dict[str, float]
    misfit: float
    features: int
    aic: float
    evaluations: int
    seconds: float
    interval_method: str
    edge_threshold: float
    nearby_misfit: tuple[float, float] = (float("nan"), float("nan"))
    history: list[tuple[tuple[float, ...], float]] = field(default_factory=list, repr=False)
    features_by_parameters: dict[tuple[float, ...], SlipFeatures] = field(
        default_factory=dict, repr=False)

    def to_dict(self) -> dict[str, Any]:
        """The fit in plain types (no history).

        Returns
        -------
        dict
            ``law``, ``parameters`` (value, low, high, units), ``misfit``, ``features``,
            ``aic``, ``evaluations``, ``seconds``, ``interval_method``,
            ``edge_threshold``, ``misfit_nearby`` (:attr:`nearby_misfit`; null for inf).

        """
        return {"law": self.law,
                "parameters": {name: {"value": round(self.values[name], 6),
                                      "low": round(self.low[name], 6),
                                      "high": round(self.high[name], 6),
                                      "units": UNITS[name]} for name in self.values},
                "misfit": round(self.misfit, 4), "features": self.features,
                "aic": round(self.aic, 4), "evaluations": self.evaluations,
                "seconds": round(self.seconds, 2), "interval_method": self.interval_method,
                "edge_threshold": round(self.edge_threshold, 4),
                "misfit_nearby": [round(value, 4) if np.isfinite(value) else None
                                  for value in self.nearby_misfit]}


class LawObjective:
    """The misfit of one law on one test, its simulations cached by parameters.

    Gross slips are told from partial ones by one edge threshold for the whole fit
    (``threshold``), so that every law is judged on the same measured features.

    Parameters
    ----------
    setup, measured, law, elements, threshold, calibration_error, detection
        As in :func:`fit_law`.
    cache
        The solver's cache, shared by the law's simulations.

    Attributes
    ----------
    measured
        The measured features (:class:`SlipFeatures`).
    features
        The simulated features by (clipped) parameters.
    cache
        The misfit by (clipped) parameters.
    history
        Every (parameters, misfit) evaluated, in order.
    """

    def __init__(self, setup: TestSetup, measured: pd.DataFrame, law: str, elements: int,
                 threshold: float, calibration_error: float, detection: DetectionSettings,
                 cache: SolverCache):
        self.setup, self.law, self.elements = setup, law, elements
        self.detection, self.solver_cache = detection, cache
        self.calibration_error = calibration_error
        self.names = LAWS[law]
        self.sizes = {"min_drop": float(measured.attrs.get("min_drop", 0.0)),
                      "duration": float(measured.attrs["duration"]),
                      "sample_rate": float(measured.attrs["sample_rate"])}
        self.threshold = threshold
        self.measured = slip_features(measured, gross_edge_ratio=threshold, **self.sizes)
        self.history: list[tuple[tuple[float, ...], float]] = []
        self.features: dict[tuple[float, ...], SlipFeatures] = {}
        self.cache: dict[tuple[float, ...], float] = {}

    def clip(self, theta: Sequence[float]) -> tuple[float, ...]:
        """The parameters within their bounds and the law's order (fd below fs).

        Parameters
        ----------
        theta
            The law's parameters, in :data:`LAWS`' order.

        Returns
        -------
        tuple of float
            Clipped and rounded to 1e-6: the key of :attr:`cache`.

        """
        values = dict(zip(self.names, (float(v) for v in theta), strict=True))
        for name, (low, high) in BOUNDS.items():
            if name in values:
                values[name] = min(max(values[name], low), high)
        # the law's own order: fd <= fs (and <= fs_final)
        values["fd"] = min(values["fd"], values["fs"] - 1e-3)
        if "fs_final" in values:
            values["fs_final"] = max(values["fs_final"], values["fd"] + 1e-3)
        if "dc" in values:  # a process zone the mesh resolves (ZONE_ELEMENTS)
            values["dc"] = max(values["dc"], self.shortest_dc(values["fs"], values["fd"]))
        return tuple(round(values[name], 6) for name in self.names)

    def shortest_dc(self, fs: float, fd: float) -> float:
        """The shortest Dc whose process zone spans :data:`ZONE_ELEMENTS` of the mesh.

        Parameters
        ----------
        fs, fd
            The law's coefficients (the zone shortens as fs - fd grows).

        Returns
        -------
        float
            Dc, mm.

        """
        spacing = self.setup["length_mm"] / self.elements
        unit = self.setup.process_zone(SlipWeakening(fs=fs, fd=fd, dc=1.0))
        return ZONE_ELEMENTS * spacing / unit

    def simulated(self, theta: tuple[float, ...]) -> SlipFeatures:
        """The features of the law's simulation at ``theta``.

        Parameters
        ----------
        theta
            Clipped parameters (:meth:`clip`).

        Returns
        -------
        SlipFeatures
            Its slips, detected as the measurement's.

        """
        params = dict(zip(self.names, theta, strict=True))
        simulation = self.setup.simulate(law_of(self.law, params), self.elements,
                                         cache=self.solver_cache)
        events = simulated_events(simulation, self.setup, min_drop=self.sizes["min_drop"],
                                  sample_rate=self.sizes["sample_rate"],
                                  detection=self.detection)
        return slip_features(events, gross_edge_ratio=self.threshold, **self.sizes)

    def __call__(self, theta: Sequence[float]) -> float:
        """The misfit at ``theta`` (inf where the solver cannot follow the law).

        Parameters
        ----------
        theta
            The law's parameters, in :data:`LAWS`' order (clipped first).

        Returns
        -------
        float
            The sum of the squared residuals (:func:`feature_residuals`).

        """
        key = self.clip(theta)
        if key not in self.cache:
            try:
                features = self.simulated(key)
            except SlipwaveError:
                misfit = np.inf  # a law the solver cannot follow: not a candidate
            else:
                self.features[key] = features
                misfit = float(np.sum(feature_residuals(
                    features, self.measured, calibration_error=self.calibration_error) ** 2))
            self.cache[key] = misfit
            self.history.append((key, misfit))
        return self.cache[key]


def law_misfit(setup: TestSetup, measured: pd.DataFrame, law: str,
               params: Mapping[str, float], *, threshold: float,
               elements: int = FIT_ELEMENTS,
               calibration_error: float = LOAD_CALIBRATION,
               detection: DetectionSettings = DEFAULT_DETECTION,
               cache: SolverCache | None = None) -> float:
    """The misfit the fit gives one law's parameters on one test (one simulation).

    To tell, where a fit misses a known truth, a search that stopped short (the truth's
    misfit below the fit's) from features the truth does not reproduce (above).

    Parameters
    ----------
    setup, measured, law, threshold, elements, calibration_error, detection, cache
        As for :func:`fit_law`.
    params
        The law's parameters by name (:data:`LAWS`).

    Returns
    -------
    float
        The sum of the squared residuals (:func:`feature_residuals`); inf where the
        solver cannot follow the law.

    """
    objective = LawObjective(setup, measured, law, elements, threshold, calibration_error,
                           detection, cache or SolverCache())
    return objective(tuple(float(params[name]) for name in LAWS[law]))


def _fd_start(measured: pd.DataFrame) -> float:
    """T/|N| after the largest quarter of the drops: the dynamic coefficient's start."""
    largest = measured["drop"] >= measured["drop"].quantile(0.75)
    return float(np.clip(measured.loc[largest, "ratio_after"].median(), *BOUNDS["fd"]))


def _closest(scan: Mapping[tuple[float, ...], SlipFeatures], target: float,
             which: slice) -> float:
    """The scanned fs whose simulated T/|N| before the chosen gross slips is nearest."""
    best, distance = float("nan"), np.inf
    for theta, features in scan.items():
        ratios = features.gross["ratio_before"].to_numpy()[which]
        if ratios.size and abs(np.median(ratios) - target) < distance:
            best, distance = theta[0], abs(np.median(ratios) - target)
    return best


def _first_slip_fs(runs: Mapping[tuple[float, ...], SlipFeatures], target: float) -> float:
    """The fs whose T/|N| before the first slip is ``target``, between Coulomb runs.

    Interpolated between two runs next to each other in fs (fs first in their
    parameters) whose T/|N| rises across the target: it rises steadily with fs, but
    only where fs is well above fd (closer, the first cascades stay too small to be
    seen and the first visible slip is a later one). With several such pairs, the one
    of highest fs; NaN with none.

    Examples
    --------
    >>> def run(fs, first):
    ...     return (fs, 0.6), SlipFeatures(pd.DataFrame(), 0, 0.3, 90.0, 100.0,
    ...                                    first_time=50.0, first_ratio=first)
    >>> runs = dict([run(0.62, 0.56), run(0.72, 0.52), run(0.82, 0.51), run(0.92, 0.63)])
    >>> round(_first_slip_fs(runs, 0.58), 4)  # not between 0.62 and 0.72, where it falls
    0.8783
    """
    found = float("nan")
    if not np.isfinite(target):
        return found
    points = sorted((theta[0], features.first_ratio) for theta, features in runs.items()
                    if np.isfinite(features.first_ratio))
    for (fs_low, low), (fs_high, high) in pairwise(points):
        if low <= target <= high and high > low:
            found = fs_low + (fs_high - fs_low) * (target - low) / (high - low)
    return found


def _starts(law: str, objective: LawObjective, measured: pd.DataFrame,
            previous: Mapping[str, LawFit], scan: Mapping[tuple[float, ...], SlipFeatures]
            ) -> Sequence[tuple[float, ...]]:
    """Starting points of a law's search.

    Coulomb: a scan of fs at the measured T/|N| after the largest drops (T/|N| at
    gross slips is not monotonic in fs, since the partial slips before it change with
    fs: a scan finds the right valley, a gradient does not); :func:`fit_law` then adds
    the fs the first slip gives. Run-in: fs from the first slip (before any gross
    slip, the run-in has not begun) read off the Coulomb runs, fs_final from the
    scanned Coulomb run whose gross slips match the measured later ones, and around
    the number of slips until the measured T/|N| settles (without a first slip, a scan
    of fs below fs_final). Slip-weakening: Coulomb's fd with a few Dc, each with the fs
    that puts its first slip at the test's (:func:`first_slip_match`). A law fitted
    without Coulomb before it starts from the same scan of fs, as its Coulomb limit (no
    run-in, Dc 0.03 mm).
    """
    fd = _fd_start(measured)
    scanned = [fd + excess for excess in np.arange(0.05, 0.81, 0.1)]
    coulomb = previous.get("coulomb")
    if law == "coulomb":
        return [(fs, fd) for fs in scanned]
    if coulomb is None:
        if law == "run-in":
            return [(fs, fd, fs, 1.0) for fs in scanned]
        return [(fs, fd, 0.03) for fs in scanned]
    fs, fd = coulomb.values["fs"], coulomb.values["fd"]
    if law == "run-in":
        ratios = objective.measured.gross["ratio_before"].to_numpy()
        if ratios.size < 2:
            return [(fs, fd, fs, 1.0)]
        later = slice(ratios.size // 2, None)
        # the later gross slips settle at fs_final: the scanned Coulomb run that matches
        # them, or Coulomb's optimum; fs, the first slips' coefficient, is scanned below
        final = _closest(scan, float(np.median(ratios[later])), later) if scan else fs
        final = fs if not np.isfinite(final) else final
        settled = np.abs(ratios - np.median(ratios[later])) <= 0.01
        runin = float(np.clip(np.argmax(settled), 1, 8))
        first = _first_slip_fs(scan, objective.measured.first_ratio)
        if np.isfinite(first):
            return [(first, fd, float(max(final, first)), float(slips))
                    for slips in {max(1.0, runin - 1.0), runin, runin + 1.0}] + [
                (fs, fd, fs, 1.0)]
        firsts = np.arange(fd + 0.05, max(final, fd + 0.06), 0.05)
        return [(float(first), fd, float(max(final, first)), runin) for first in firsts] + [
            (fs, fd, fs, 1.0)]
    # Coulomb's fs reads a weakening law's high, the more so the longer Dc: a slip that
    # weakens over Dc sheds its load gradually and is seen later, at a higher T/|N|
    # (Coulomb's fs was 4 %, 7 %, 17 % and 32 % above the truth in four slip-weakening
    # tests of Dc 0.05-0.2 mm). Each Dc therefore starts from the fs that puts its
    # first slip where the test's was; 0.01 mm, nearly Coulomb, from Coulomb's fs.
    return [(fs, fd, 0.01)] + [first_slip_match(objective, (fs, fd, dc))
                               for dc in (0.03, 0.1, 0.3)]


FIRST_SLIP_SLOPE = 1.2
"""How T/|N| before a test's first slip rises with fs (about 1.2 per unit on 80
elements, :class:`SlipFeatures`): the first step of :func:`first_slip_match`."""

FIRST_SLIP_REACH = 0.2
"""The largest move of fs in one step of :func:`first_slip_match` (Coulomb's fs read
a weakening law's 0.04-0.28 high in four tests: two steps cover it)."""


def first_slip_match(objective: LawObjective, theta: tuple[float, ...], *,
                     steps: int = 2) -> tuple[float, ...]:
    """The parameters, fs moved by secant steps, whose first slip comes at the test's.

    The first slip's T/|N| (:attr:`SlipFeatures.first_ratio`) is matched, since it is
    what carries fs most directly. The first step takes :data:`FIRST_SLIP_SLOPE`, the
    next the secant of the runs so far. It stops where the first slip does not follow
    fs (a secant below a quarter of that slope: a law whose first slip is a gross one,
    say, that no fs brings down to a measured partial slip's), where the match asks
    for fs at or below fd, and each step moves fs by at most :data:`FIRST_SLIP_REACH`.
    Returns the run of lowest misfit among those tried (``theta`` itself without a
    measured or simulated first slip).

    Parameters
    ----------
    objective
        The law's misfit on the test (what it reads: :meth:`LawObjective.clip`, its
        call, ``measured``, ``features`` and ``cache``).
    theta
        The start: fs first, then the law's other parameters.
    steps
        Secant steps at most.

    Returns
    -------
    tuple of float
        The parameters tried of lowest misfit.

    """
    target = objective.measured.first_ratio
    tried = [objective.clip(theta)]
    objective(tried[0])
    points: list[tuple[float, float]] = []
    for _ in range(steps):
        features = objective.features.get(tried[-1])
        if features is None or not (np.isfinite(target) and np.isfinite(features.first_ratio)):
            break
        points.append((tried[-1][0], features.first_ratio))
        slope = FIRST_SLIP_SLOPE
        if len(points) > 1:
            (fs_a, ratio_a), (fs_b, ratio_b) = points[-2:]
            slope = (ratio_b - ratio_a) / (fs_b - fs_a) if fs_b != fs_a else 0.0
            if slope < FIRST_SLIP_SLOPE / 4:
                break
        move = float(np.clip((target - points[-1][1]) / slope, -FIRST_SLIP_REACH,
                             FIRST_SLIP_REACH))
        fs = points[-1][0] + move
        if fs <= tried[-1][1]:
            break
        step = objective.clip((fs, *tried[-1][1:]))
        if step in objective.cache:
            break
        objective(step)
        tried.append(step)
    return min(tried, key=objective)


COEFFICIENTS = ("fs", "fd", "fs_final")
"""Parameters that are friction coefficients (scaled by a load-cell calibration error)."""

_SIMPLEX = {"fs": 0.02, "fd": 0.005, "fs_final": 0.03, "runin_slips": 1.0, "dc": 0.03}


def fit_law(setup: TestSetup, measured: pd.DataFrame, law: str, *,
            threshold: float, elements: int = FIT_ELEMENTS,
            max_evaluations: int = FIT_MAX_EVALUATIONS,
            previous: Mapping[str, LawFit] | None = None,
            scan: Mapping[tuple[float, ...], SlipFeatures] | None = None,
            calibration_error: float = LOAD_CALIBRATION,
            detection: DetectionSettings = DEFAULT_DETECTION,
            cache: SolverCache | None = None,
            starts: Sequence[tuple[float, ...]] | None = None) -> LawFit:
    """Fit one friction law to one test.

    Parameters
    ----------
    setup
        The test's configuration (:func:`slipwave.setup.read_test_setup`).
    measured
        Its events (:func:`measured_events`).
    law
        One of :data:`LAWS`.
    threshold
        The edge-jump ratio that tells gross slips (:func:`edge_threshold`).
    elements
        Elements along the contact in every simulation.
    max_evaluations
        Simulations of the Nelder-Mead search (the starting points add a few).
    previous
        Laws already fitted: the richer laws start around Coulomb's optimum.
    scan
        Coulomb's simulated features by parameters, for the run-in's start.
    calibration_error
        Relative calibration uncertainty of each load cell (:data:`LOAD_CALIBRATION`).
    detection
        The detection's settings, for the simulated recordings.
    cache
        The solver's cache (the slab's condensation and normal approach); ``None``: the
        fit's own.
    starts
        Where the search starts (the law's parameters in :data:`LAWS` order), in place
        of the law's own starting scan: a local search from a known fit.

    Returns
    -------
    LawFit
        Estimates, 95 % intervals, misfit and AIC.

    Raises
    ------
    SlipwaveError
        If no simulation of the law could be run.

    """
    began = clock.perf_counter()
    objective = LawObjective(setup, measured, law, elements, threshold, calibration_error,
                           detection, cache or SolverCache())
    local = starts is not None
    points = ([objective.clip(theta) for theta in starts] if starts is not None
              else _starts(law, objective, measured, previous or {}, scan or {}))
    best = min(points, key=objective)
    if law == "coulomb" and not local:
        # the scan's runs give fs by the first slip's T/|N|, finer than the scan's step
        first = _first_slip_fs(objective.features, objective.measured.first_ratio)
        if np.isfinite(first):
            best = min([best, objective.clip((first, best[1]))], key=objective)
    if law == "run-in" and not local:
        # fs_final alone along a line: the later gross slips' valley is narrow, and the
        # simplex, moving four parameters at once, steps over it
        k = LAWS[law].index("fs_final")
        line = [(*best[:k], best[k] + offset, *best[k + 1:])
                for offset in (-0.1, -0.075, -0.05, -0.025, 0.025, 0.05, 0.075, 0.1)]
        best = min([best, *(objective.clip(theta) for theta in line)], key=objective)
    scale = np.array([_SIMPLEX[name] for name in LAWS[law]])
    simplex = np.vstack([best, best + np.diag(scale)])
    minimize(objective, np.asarray(best), method="Nelder-Mead",
             options={"initial_simplex": simplex, "maxfev": max_evaluations,
                      "xatol": 1e-3, "fatol": 0.5})
    finite = [(theta, misfit) for theta, misfit in objective.history if np.isfinite(misfit)]
    if not finite:
        raise SlipwaveError(f"test {setup.test_id!r}: the solver followed no {law} law tried")
    theta, misfit = min(finite, key=lambda item: item[1])
    # The residuals on both sides of the optimum along each parameter, a secant's width
    # apart: the misfit is rough at the scale of one partial slip more or less, so the
    # sensitivity that matters is the trend across several, not the local curvature.
    # Without the load cells' calibration: it is an error of its own, added below.
    names = LAWS[law]
    centre = np.asarray(theta)
    secant = 2.0 * scale
    jacobian = []
    for k in range(len(theta)):
        ends = [objective.clip(centre + sign * secant[k] * np.eye(len(theta))[k])
                for sign in (-1.0, 1.0)]
        for end in ends:
            objective(end)
        if all(end in objective.features for end in ends) and ends[0][k] != ends[1][k]:
            below, above = (feature_residuals(objective.features[end], objective.measured)
                            for end in ends)
            jacobian.append((above - below) / (ends[1][k] - ends[0][k]))
        else:
            jacobian.append(None)
    theta, nearby = _nearby(objective)
    misfit = objective.cache[theta]
    history = [(point, value) for point, value in objective.history if np.isfinite(value)]
    # the features a law is judged on: the residuals of the measurement against itself
    features = feature_residuals(objective.measured, objective.measured).size
    # the law's mismatch: its neighbours' misfit, not the luckiest cycle's (ROUGHNESS_STEP)
    followed = [value for value in nearby if np.isfinite(value)]
    mismatch = max(misfit, float(np.mean(followed))) if followed else misfit
    low, high, method = misfit_intervals(history, theta, misfit, features, mismatch=mismatch)
    # A scale error common to both load cells multiplies every T/|N|, hence every
    # coefficient, alike: its 95 % range, independent of the fit's own error.
    calibration = np.array([abs(value) * 1.96 * np.sqrt(2.0) * calibration_error
                            if name in COEFFICIENTS else 0.0
                            for name, value in zip(names, theta, strict=True)])
    half = calibration
    if all(column is not None for column in jacobian):
        matrix = np.column_stack(jacobian)
        reduced = max(1.0, mismatch / max(1, features - len(theta)))
        try:
            covariance = np.linalg.inv(matrix.T @ matrix) * reduced
        except np.linalg.LinAlgError:
            covariance = None
        if covariance is not None and np.all(np.diag(covariance) > 0):
            half = np.hypot(1.96 * np.sqrt(np.diag(covariance)), calibration)
            method = "secant"
    low = [min(a, t - h) for a, t, h in zip(low, theta, half, strict=True)]
    high = [max(b, t + h) for b, t, h in zip(high, theta, half, strict=True)]
    for k, name in enumerate(names):
        bounds = BOUNDS[name]
        low[k], high[k] = max(low[k], bounds[0]), min(high[k], bounds[1])
        if name == "dc":  # no shorter Dc is told apart on this mesh (ZONE_ELEMENTS)
            values = dict(zip(names, theta, strict=True))
            low[k] = max(low[k], objective.shortest_dc(values["fs"], values["fd"]))
    fit = LawFit(law, dict(zip(names, theta, strict=True)), dict(zip(names, low, strict=True)),
                 dict(zip(names, high, strict=True)), misfit, features,
                 misfit + 2 * len(names), len(objective.history),
                 clock.perf_counter() - began, method, threshold, nearby, history)
    fit.features_by_parameters = objective.features
    return fit


def _nearby(objective: LawObjective) -> tuple[tuple[float, ...], tuple[float, float]]:
    """The best law tried, and its misfits with its coefficients moved apart.

    The friction coefficients move together by :data:`ROUGHNESS_STEP`, down and up. A
    neighbour that scores better does not replace the best: at this scale the misfit's
    differences are the cycle's luck, not information.
    """
    theta = min(objective.cache, key=objective.cache.__getitem__)
    low, high = (objective(tuple(
        value * (1.0 + sign * ROUGHNESS_STEP) if name in COEFFICIENTS else value
        for name, value in zip(objective.names, theta, strict=True)))
        for sign in (-1.0, 1.0))
    return theta, (float(low), float(high))


def probe_threshold(setup: TestSetup, measured: pd.DataFrame, *,
                    elements: int = FIT_ELEMENTS,
                    detection: DetectionSettings = DEFAULT_DETECTION,
                    cache: SolverCache | None = None) -> float:
    """The test's edge threshold from one Coulomb run at plausible coefficients.

    What separates a gross slip's edge jumps from a partial slip's is the slab's shape
    (how the far edge follows); one simulation at fd from the largest drops and fs 0.3
    above sets it for the whole fit.

    Parameters
    ----------
    setup, measured, elements, detection, cache
        As in :func:`fit_law`.

    Returns
    -------
    float
        :func:`detected_edge_threshold` of that run.

    """
    fd = _fd_start(measured)
    simulation = setup.simulate(Coulomb(fs=fd + 0.3, fd=fd), elements, cache=cache)
    return detected_edge_threshold(simulation, setup,
                                   min_drop=float(measured.attrs.get("min_drop", 0.0)),
                                   sample_rate=float(measured.attrs["sample_rate"]),
                                   detection=detection)


def misfit_intervals(history: list[tuple[tuple[float, ...], float]],
                     best: tuple[float, ...], misfit: float, features: int, *,
                     mismatch: float | None = None) -> tuple[list[float], list[float], str]:
    """95 % intervals of the parameters: the misfit's curvature, and where it rises.

    Two estimates, and each interval covers both. (1) A quadratic in the parameters
    fitted (least squares) to the evaluations whose misfit lies within 10 of the best:
    its Hessian H gives the covariance 2 H^-1 ("curvature"); where H is not positive
    definite, each parameter's parabola through the optimum and its two axis
    neighbours ("axes"). (2) The likelihood-ratio region: the range of the evaluated
    values whose misfit lies within 3.84 of the best, interpolated out to the nearest
    evaluation beyond ("evaluations"). Both scale by the reduced misfit when that
    exceeds 1 (the law misses by more than the noise): ``mismatch`` (the law's typical
    misfit, see :data:`ROUGHNESS_STEP`; by default the best one) per degree of freedom.
    The misfit is rough at the scale of one partial slip more or less, so a curvature
    can be steeper than the rise it predicts; the union keeps the interval honest.

    Parameters
    ----------
    history
        Every (parameters, misfit) evaluated.
    best
        The optimum's parameters.
    misfit
        The optimum's misfit.
    features
        How many features the misfit sums.
    mismatch
        The law's typical misfit; ``None``: ``misfit``.

    Returns
    -------
    tuple
        The lower and upper bounds, one per parameter, and how the curvature was read
        (``curvature``, ``axes`` or ``evaluations``).

    """
    points = np.array([theta for theta, _ in history])
    values = np.array([value for _, value in history])
    p = points.shape[1]
    reduced = max(1.0, (misfit if mismatch is None else mismatch) / max(1, features - p))
    centre = np.asarray(best)
    span = np.maximum(np.ptp(points, axis=0), 1e-9)
    rise = 3.84 * reduced
    # (2) the likelihood-ratio region along each parameter
    low, high = [], []
    for j in range(p):
        order = np.argsort(points[:, j])
        theta, excess = points[order, j], values[order] - misfit
        inside = np.flatnonzero(excess <= rise)
        first, last = inside.min(), inside.max()
        lo, hi = theta[first], theta[last]
        if first > 0 and excess[first - 1] > excess[first]:
            lo = np.interp(rise, [excess[first], excess[first - 1]],
                           [theta[first], theta[first - 1]])
        if last + 1 < theta.size and excess[last + 1] > excess[last]:
            hi = np.interp(rise, [excess[last], excess[last + 1]], [theta[last], theta[last + 1]])
        low.append(float(min(lo, centre[j])))
        high.append(float(max(hi, centre[j])))
    # (1) the curvature
    half = np.full(p, np.nan)
    method = "evaluations"
    near = values <= misfit + 10.0 * reduced
    if near.sum() >= 2 + p + p * (p + 1) // 2:
        d = (points[near] - centre) / span
        columns = [np.ones(d.shape[0])] + [d[:, i] for i in range(p)]
        pairs = [(i, j) for i in range(p) for j in range(i, p)]
        columns += [d[:, i] * d[:, j] * (0.5 if i == j else 1.0) for i, j in pairs]
        coefficients, *_ = np.linalg.lstsq(np.column_stack(columns), values[near], rcond=None)
        hessian = np.zeros((p, p))
        for (i, j), c in zip(pairs, coefficients[1 + p:], strict=True):
            hessian[i, j] = hessian[j, i] = c
        if np.all(np.linalg.eigvalsh(hessian) > 0):
            half = 1.96 * np.sqrt(np.diag(2.0 * np.linalg.inv(hessian) * reduced)) * span
            method = "curvature"
    if method != "curvature":
        for j in range(p):
            others = np.all(np.isclose(np.delete(points, j, axis=1), np.delete(centre, j)),
                            axis=1)
            offsets = points[others, j] - centre[j]
            below, above = offsets < 0, offsets > 0
            if not (below.any() and above.any()):
                continue
            k0 = np.flatnonzero(below)[np.argmax(offsets[below])]
            k1 = np.flatnonzero(above)[np.argmin(offsets[above])]
            h0, h1 = -offsets[k0], offsets[k1]
            m0, m1 = values[others][k0] - misfit, values[others][k1] - misfit
            curvature = 2.0 * (m0 / h0 + m1 / h1) / (h0 + h1)  # the second derivative
            if curvature > 0:
                half[j] = 1.96 * np.sqrt(2.0 * reduced / curvature)
                method = "axes"
    for j in range(p):
        if np.isfinite(half[j]):
            low[j] = min(low[j], centre[j] - half[j])
            high[j] = max(high[j], centre[j] + half[j])
    return low, high, method


def mesh_check(setup: TestSetup, measured: pd.DataFrame, fit: LawFit, *, elements: int,
               max_evaluations: int = FIT_MAX_EVALUATIONS,
               calibration_error: float = LOAD_CALIBRATION,
               detection: DetectionSettings = DEFAULT_DETECTION,
               cache: SolverCache | None = None) -> dict[str, Any]:
    """The law refitted on a finer mesh: how much its parameters still follow the mesh.

    A local search at ``elements`` (twice the fit's, in :func:`fit_test`) from the
    fit's estimate, the gross slips told by the fit's own edge threshold, so that the
    same measured features are matched. A law with a length scale (slip-weakening's Dc)
    converges once its process zone spans a few elements; Coulomb's law with fs > fd
    and run-in have none, and their coefficients are the mesh-dependent limit (docs:
    "Mesh convergence").

    Parameters
    ----------
    setup, measured
        As in :func:`fit_law`.
    fit
        The law fitted on the fit's own mesh.
    elements
        The finer mesh.
    max_evaluations, calibration_error, detection, cache
        As in :func:`fit_law`.

    Returns
    -------
    dict
        ``elements``, ``law``, ``parameters`` (value, low, high, units at ``elements``),
        ``change`` (each parameter's relative change from the fit's estimate), ``misfit``,
        ``evaluations``, ``seconds`` and ``process_zone_mm`` (the law's process zone at
        the fit's estimate, :meth:`~slipwave.setup.TestSetup.process_zone`; null for a
        law without a length).

    """
    finer = fit_law(setup, measured, fit.law, threshold=fit.edge_threshold,
                    elements=elements, max_evaluations=max_evaluations,
                    calibration_error=calibration_error, detection=detection, cache=cache,
                    starts=[tuple(fit.values.values())])
    entry = finer.to_dict()
    zone = setup.process_zone(law_of(fit.law, fit.values))
    return {"elements": elements, "law": fit.law, "parameters": entry["parameters"],
            "change": {name: round((finer.values[name] - value) / value, 6)
                       for name, value in fit.values.items()},
            "misfit": entry["misfit"], "evaluations": entry["evaluations"],
            "seconds": entry["seconds"],
            "process_zone_mm": round(zone, 4) if zone > 0 else None}


def fit_test(setup: TestSetup, measured: pd.DataFrame, *, laws: Sequence[str] = tuple(LAWS),
             elements: int = FIT_ELEMENTS, max_evaluations: int = FIT_MAX_EVALUATIONS,
             calibration_error: float = LOAD_CALIBRATION,
             detection: DetectionSettings = DEFAULT_DETECTION,
             cache: SolverCache | None = None,
             check_mesh: bool = FIT_MESH_CHECK) -> dict[str, Any]:
    """Fit every law to a test and choose by AIC.

    Parameters
    ----------
    setup, measured
        As in :func:`fit_law`.
    laws
        The laws to fit (Coulomb first: the others start from it).
    elements, max_evaluations, calibration_error, detection
        As in :func:`fit_law`.
    cache
        The solver's cache, shared by every law's simulations; ``None``: the fit's own.
    check_mesh
        Refit the chosen law at twice ``elements`` (:func:`mesh_check`).

    Returns
    -------
    dict
        ``test_id``, ``setup`` (every value with its source), ``elements``,
        ``detection`` (:meth:`~slipwave.events.DetectionSettings.to_dict`),
        ``measured`` (gross and partial slip counts), ``laws`` (each
        :meth:`LawFit.to_dict` with ``delta_aic`` and ``rejected``), ``chosen`` (the
        lowest AIC), ``parameters`` (the chosen law's values) and ``mesh_check``
        (:func:`mesh_check` at twice the mesh, or null).

    """
    unknown = [law for law in laws if law not in LAWS]
    if unknown:
        raise SlipwaveError(f"unknown friction law(s) {unknown}; known: {', '.join(LAWS)}")
    ordered = sorted(laws, key=list(LAWS).index)
    fits: dict[str, LawFit] = {}
    cache = cache or SolverCache()
    threshold = probe_threshold(setup, measured, elements=elements, detection=detection,
                                cache=cache)
    for law in ordered:
        scan = fits["coulomb"].features_by_parameters if "coulomb" in fits else None
        fits[law] = fit_law(setup, measured, law, threshold=threshold, elements=elements,
                            max_evaluations=max_evaluations, previous=fits, scan=scan,
                            calibration_error=calibration_error, detection=detection,
                            cache=cache)
    best = min(fits.values(), key=lambda fit: fit.aic)
    finer = mesh_check(setup, measured, best, elements=2 * elements,
                       max_evaluations=max_evaluations, calibration_error=calibration_error,
                       detection=detection, cache=cache) if check_mesh else None
    laws_out = {}
    for law, fit in fits.items():
        entry = fit.to_dict()
        entry["delta_aic"] = round(fit.aic - best.aic, 4)
        entry["rejected"] = bool(fit.aic - best.aic > REJECTED_AIC)
        laws_out[law] = entry
    return {"test_id": setup.test_id, "setup": setup.to_dict(), "elements": elements,
            "detection": detection.to_dict(), "load_calibration": calibration_error,
            "measured": {"slips": len(measured),
                         "gross_slips": len(slip_features(
                             measured, gross_edge_ratio=threshold, min_drop=0.0,
                             duration=0.0, sample_rate=0.0).gross),
                         "min_drop_n": round(float(measured.attrs.get("min_drop", 0.0)), 6)},
            "edge_threshold": round(threshold, 4),
            "laws": laws_out, "chosen": best.law,
            "parameters": {name: round(value, 6) for name, value in best.values.items()},
            "mesh_check": finer}


def chosen_law(fit: Mapping[str, Any]) -> Coulomb:
    """The solver's law of a fit's chosen law (``fit.json`` as a mapping).

    Parameters
    ----------
    fit
        From :func:`fit_test` (or its JSON).

    Returns
    -------
    Coulomb
        The law.

    """
    return law_of(fit["chosen"], fit["parameters"])


def read_fit(path: str | PathLike[str]) -> dict[str, Any]:
    """A ``fit.json``, checked, with an error naming the file and the key when it is not one.

    The file is held to ``slipwave/schemas/fit.schema.json``, and what a schema cannot
    say is checked too: the chosen law is one of the fitted laws, its parameters are
    that law's and make a law the solver takes, and the setup is a slab's.

    Parameters
    ----------
    path
        The file.

    Returns
    -------
    dict
        Its content (:func:`fit_test`).

    Raises
    ------
    SlipwaveError
        ``<path>: <key>: <what is wrong>`` (or the line and column of broken JSON).

    """
    fit = read_json(path, "fit")
    chosen = fit["chosen"]
    if chosen not in fit["laws"]:
        raise SlipwaveError(f"{path}: chosen: {chosen!r} is not one of the fitted laws "
                            f"{sorted(fit['laws'])}")
    names = set(LAWS[chosen])
    for where, values in [("parameters", fit["parameters"]),
                          (f"laws.{chosen}.parameters", fit["laws"][chosen]["parameters"])]:
        if set(values) != names:
            raise SlipwaveError(f"{path}: {where}: {sorted(values)} are not the parameters of "
                                f"the {chosen} law, {sorted(names)}")
    try:
        law_of(chosen, fit["parameters"])
        setup = TestSetup.from_dict(fit["setup"])
        for key in GEOMETRY:
            problem = setup_value_problem(key, setup[key])
            if problem is not None:
                raise SlipwaveError(f"setup.{key}.value: {problem}")
        setup.slab(int(fit["elements"]))
    except SlipwaveError as err:
        raise SlipwaveError(f"{path}: {err}") from err
    return dict(fit)
