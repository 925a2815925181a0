"""What a fit compares: a test's slips, detected alike in the recording and the simulation.

The measured and the simulated recordings go through the same detection, with the
campaign's settings (:class:`~slipwave.events.DetectionSettings`), and each is summed up
in one vector of :data:`FEATURES` (:func:`feature_vector`): the numbers a synthetic
likelihood compares (:mod:`slipwave.fit.likelihood`). Gross slips are told from partial
ones by one edge threshold per test (:func:`detected_edge_threshold`).

Examples
--------
>>> gross = pd.DataFrame({"t_start": [10.0, 40.0], "ratio_before": [0.7, 0.72],
...                       "ratio_after": [0.6, 0.61], "drop": [8.0, 8.5]})
>>> features = SlipFeatures(gross, 4, 0.3, 60.0, 100.0, first_time=4.0, first_ratio=0.5,
...                         partial_drops=np.array([0.5, 1.0, 2.0, 4.0]))
>>> dict(zip(FEATURES, feature_vector(features).round(3).tolist()))["gross_ratio_before_2"]
0.72
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import xarray as xr

from slipwave.compare import recurrence
from slipwave.errors import SlipwaveError
from slipwave.events.detect import DEFAULT_DETECTION, DetectionSettings, detect_events
from slipwave.setup import TestSetup
from slipwave.solver.signals import clean_signals, step_times


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


def far_edge_moves(events: pd.DataFrame) -> np.ndarray:
    """Which slips move the far edge significantly (the detection's ``DG_min_jump``).

    Parameters
    ----------
    events
        From :func:`~slipwave.events.detect_events`; without ``DG_min_jump`` in its
        ``attrs``, any jump counts.

    Returns
    -------
    numpy.ndarray
        One bool per slip.

    """
    return np.abs(events["DG_jump"].to_numpy(dtype=float)) >= events.attrs.get(
        "DG_min_jump", 0.0)


def gross_by_edges(events: pd.DataFrame, gross_edge_ratio: float) -> np.ndarray:
    """Which slips are gross, told by their edges.

    The far edge moves (:func:`far_edge_moves`) and DG/DD reaches ``gross_edge_ratio``
    (as :func:`~slipwave.events.classify_events` decides).

    Parameters
    ----------
    events
        From :func:`~slipwave.events.detect_events`.
    gross_edge_ratio
        The test's threshold.

    Returns
    -------
    numpy.ndarray
        One bool per slip.

    """
    return far_edge_moves(events) & (
        events["edge_ratio"].to_numpy(dtype=float) >= gross_edge_ratio)


CLEAR_SPLIT = 2.0
"""A measured split between gross and partial slips is clear when the widest gap of
the slips' DG/DD ratios (sorted) is at least this factor."""


def measured_split(events: pd.DataFrame) -> float | None:
    """The DG/DD ratio in the widest gap of a recording's slips, where that gap is clear.

    Only the slips whose far-edge jump is significant (``DG_min_jump`` of
    ``events.attrs``) count; the threshold is the gap's geometric middle. ``None``
    when fewer than two such slips or no gap of :data:`CLEAR_SPLIT` or more.

    Parameters
    ----------
    events
        From :func:`~slipwave.events.detect_events` (``edge_ratio``, ``DG_jump``).

    Returns
    -------
    float or None
        The ratio, or ``None``.

    Examples
    --------
    >>> events = pd.DataFrame({"edge_ratio": [1.2, 1.16, 0.46, 0.3, 0.2],
    ...                        "DG_jump": [0.5, 0.5, 0.1, 0.05, 0.05]})
    >>> round(measured_split(events), 3)
    0.73

    Ratios that spread without a clear gap have no split:

    >>> print(measured_split(events.assign(edge_ratio=[1.2, 0.9, 0.7, 0.5, 0.4])))
    None
    """
    if events.empty:
        return None
    ratio = events["edge_ratio"].to_numpy(dtype=float)
    significant = far_edge_moves(events)
    logs = np.sort(np.log(ratio[significant & np.isfinite(ratio) & (ratio > 0)]))
    if logs.size < 2:
        return None
    gaps = np.diff(logs)
    widest = int(np.argmax(gaps))
    if gaps[widest] < np.log(CLEAR_SPLIT):
        return None
    return float(np.exp(0.5 * (logs[widest] + logs[widest + 1])))


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
    gross = gross_by_edges(events, gross_edge_ratio)
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



FEATURES: dict[str, str] = {
    "first_ratio": "T/|N| before the first slip of any kind",
    "first_time_s": "time of the first slip, s",
    "gross_ratio_before_1": "T/|N| before the first gross slip",
    "gross_ratio_before_2": "T/|N| before the second gross slip",
    "gross_ratio_before_3": "T/|N| before the third gross slip",
    "gross_ratio_before_later": "T/|N| before the later gross slips (median)",
    "gross_ratio_before_spread": "T/|N| before the later gross slips (interquartile range)",
    "gross_ratio_after": "T/|N| after the gross slips (median)",
    "gross_slips_sqrt": "square root of the number of gross slips",
    "partial_slips_sqrt": "square root of the number of partial slips",
    "gross_first_time_s": "time of the first gross slip, s",
    "recurrence_s": "the gross slips' recurrence (median interval), s",
    "partial_drop_log": "natural log of the partial slips' median T drop (N)",
}
"""The summary of a test's slips that a fit compares, in :func:`feature_vector`'s order.

Each is defined whatever the slips, so that every simulation of an ensemble has the
same vector: a gross slip that did not happen carries the T/|N| of the one before it
(the first: the first slip's), a time that did not come is the recording's length, a
partial slip drop that was not seen is the smallest counted. The numbers of slips enter
by their square roots, which steady a count's scatter (a Poisson count's is then 1/2
whatever its mean)."""

GROSS_ONE_BY_ONE = 3
"""The first gross slips, whose T/|N| before is a feature each (a run-in's rise or
fall); the later ones by their median and spread."""


def feature_vector(features: SlipFeatures) -> np.ndarray:
    """A test's slips as the numbers of :data:`FEATURES`.

    Parameters
    ----------
    features
        From :func:`slip_features`.

    Returns
    -------
    numpy.ndarray
        One value per feature, in :data:`FEATURES`' order, all finite.

    Examples
    --------
    No slip at all: the first slip's T/|N| is unknown (NaN), every time the recording's
    length.

    >>> none = SlipFeatures(pd.DataFrame(columns=["t_start", "ratio_before", "ratio_after",
    ...                                           "drop"]), 0, 0.3, 60.0, 100.0)
    >>> feature_vector(none)[[1, 8, 10, 11]].tolist()
    [60.0, 0.0, 60.0, 60.0]
    """
    gross = features.gross
    before = gross["ratio_before"].to_numpy(dtype=float)
    after = gross["ratio_after"].to_numpy(dtype=float)
    first_ratio = features.first_ratio if np.isfinite(features.first_ratio) else 0.0
    first_time = features.first_time if np.isfinite(features.first_time) else features.duration
    one_by_one = []
    carried = first_ratio
    for k in range(GROSS_ONE_BY_ONE):
        carried = float(before[k]) if k < before.size else carried
        one_by_one.append(carried)
    later = before[GROSS_ONE_BY_ONE:]
    if later.size:
        q1, median, q3 = np.quantile(later, [0.25, 0.5, 0.75])
    else:
        q1 = median = q3 = carried
    t_start = gross["t_start"].to_numpy(dtype=float)
    interval = recurrence(gross)
    drops = features.partial_drops
    smallest = max(features.min_drop, 1e-3)
    drop = float(np.median(drops)) if drops.size else smallest
    return np.array([
        first_ratio,
        first_time,
        *one_by_one,
        median,
        q3 - q1,
        float(np.median(after)) if after.size else first_ratio,
        np.sqrt(before.size),
        np.sqrt(features.partial_slips),
        float(t_start[0]) if t_start.size else features.duration,
        interval if np.isfinite(interval) else features.duration,
        np.log(max(drop, smallest)),
    ], dtype=float)


def measurement_error(features: SlipFeatures, *, ratio_error: float,
                      time_error: float) -> np.ndarray:
    """The measured features' own standard errors, in :data:`FEATURES`' order.

    What the recording itself leaves uncertain, on top of what an ensemble of
    simulations spreads: a T/|N| by ``ratio_error`` (the card's noise over a peak, the
    onset's sampling), a time by ``time_error``, a count's square root by 1/2 (a
    Poisson count's), the partial slips' median drop by its standard error
    (:func:`median_error`, relative: the feature is a log), at least ``ratio_error``.

    Parameters
    ----------
    features
        The measured slips (:func:`slip_features`).
    ratio_error
        Standard error of one T/|N|.
    time_error
        Standard error of one time, s.

    Returns
    -------
    numpy.ndarray
        One standard error per feature.

    """
    drops = features.partial_drops
    drop_error = (median_error(drops) / max(float(np.median(drops)), 1e-9)
                  if drops.size >= 3 else 0.0)
    return np.array([ratio_error, time_error, ratio_error, ratio_error, ratio_error,
                     ratio_error, ratio_error, ratio_error, 0.5, 0.5, time_error,
                     time_error, max(drop_error, ratio_error)])
