"""The detect stage: slip events of a friction test, T drops classified by what the edges did.

A gross slip is a wave that crossed the whole contact: the T drop comes with
a jump of DG, the far (left) edge, at least as large as the jump of DD, the
right edge where waves start. A partial slip is a T drop whose DG jump is
missing, smaller than DD's, or of the other sign: the left part of the
contact held.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from slipwave.defaults import (
    EDGE_CONVENTION,
    GROSS_EDGE_RATIO,
    MAX_DURATION_S,
    MAX_SPIKE,
    MIN_FALL_RATE,
    THRESHOLD,
)
from slipwave.errors import SlipwaveError
from slipwave.events.steps import (
    _fill_gaps,
    edge_jumps,
    load_drops,
    noise_level,
    window_median,
)
from slipwave.events.summary import friction_ratio, normal_loading_end, wave_counts

EVENT_COLUMNS = (
    "kind", "i_start", "t_start", "i_end", "t_end", "duration", "T_before", "T_after",
    "N_before", "N_after", "ratio_before", "ratio_after", "drop", "DG_jump", "DD_jump",
    "edge_ratio", "direction",
)
"""Columns of :func:`detect_events`, in order."""

EVENT_UNITS = {
    "i_start": "1", "t_start": "s", "i_end": "1", "t_end": "s", "duration": "s",
    "T_before": "N", "T_after": "N", "N_before": "N", "N_after": "N", "ratio_before": "1",
    "ratio_after": "1", "drop": "N", "DG_jump": "mm", "DD_jump": "mm", "edge_ratio": "1",
}

EVENT_DESCRIPTIONS = {
    "kind": "partial_slip, gross_slip, or unclassified (no DG/DD channel)",
    "i_start": "sample index of the onset (last sample before the T drop)",
    "t_start": "time of the onset",
    "i_end": "sample index where the T drop ends",
    "t_end": "time where the T drop ends",
    "duration": "t_end - t_start",
    "T_before": "tangential load at the onset (fitted, the peak)",
    "T_after": "tangential load at the end (fitted, the trough)",
    "N_before": "compressive normal load |N| just before the onset",
    "N_after": "compressive normal load |N| just after the end",
    "ratio_before": "T/|N| at the onset: the static estimate",
    "ratio_after": "T/|N| at the end: the dynamic estimate",
    "drop": "T_before - T_after",
    "DG_jump": "change of DG across the event (left edge)",
    "DD_jump": "change of DD across the event (right edge)",
    "edge_ratio": "DG_jump / DD_jump (gross slips: at least gross_edge_ratio)",
    "direction": "right_to_left or left_to_right (which edge moved first), or unresolved",
}


def classify_events(
    drops: pd.DataFrame,
    jumps: Mapping[str, pd.DataFrame],
    *,
    gross_edge_ratio: float = GROSS_EDGE_RATIO,
    tolerance: float | None = None,
    resolution: float | None = None,
) -> pd.DataFrame:
    """Partial or gross slip for each T drop, from the edge jumps around it.

    Parameters
    ----------
    drops
        T drops (:func:`~slipwave.events.load_drops`).
    jumps
        ``{"DG": ..., "DD": ...}``: edge jumps (:func:`~slipwave.events.edge_jumps`)
        of the left and right edges, found anywhere or measured at the drops
        (rows whose ``significant`` is false are no jump). Without both, the
        drops are ``unclassified``.
    gross_edge_ratio
        A drop is a gross slip when the left edge jumped, in the same direction
        as the right edge (or alone), by at least this times the right edge's
        jump. About 1 for a low slab (0.9 leaves room for noise); a tall
        slab's gross slips move the left edge more (the events table's
        ``edge_ratio`` column shows the two groups of a test).
    tolerance
        A jump belongs to a drop when it starts within this time (s) of the
        drop's interval; ``None``: the drop's own duration.
    resolution
        Smallest difference of onset times (s) that tells which edge moved
        first; ``None``: a quarter of the drop's duration, at least two sample
        intervals (onsets of small jumps are uncertain by a few samples).

    Returns
    -------
    pandas.DataFrame
        ``drops`` with ``kind``, ``DG_jump``, ``DD_jump`` (the matched jumps,
        significant or not; 0 when none matched), ``edge_ratio`` and
        ``direction`` (from significant jumps only).

    Examples
    --------
    >>> drops = pd.DataFrame({"t_start": [10.0, 20.0], "t_end": [10.3, 20.3]})
    >>> dg = pd.DataFrame({"t_start": [10.0], "t_end": [10.3], "jump": [-0.2]})
    >>> dd = pd.DataFrame({"t_start": [10.0, 20.0], "t_end": [10.3, 20.3],
    ...                    "jump": [-0.14, -0.06]})
    >>> classify_events(drops, {"DG": dg, "DD": dd})["kind"].tolist()
    ['gross_slip', 'partial_slip']
    """
    table = drops.copy()
    interval = drops.attrs.get("sample_interval", 0.0)
    starts = drops["t_start"].to_numpy(dtype=float)
    ends = drops["t_end"].to_numpy(dtype=float)
    if resolution is None:
        resolution_at = np.maximum(0.25 * (ends - starts), 2.0 * interval)
    else:
        resolution_at = np.full(starts.size, float(resolution))
    slack = ends - starts if tolerance is None else np.full(starts.size, float(tolerance))
    moved: dict[str, np.ndarray] = {}
    real: dict[str, np.ndarray] = {}
    onsets: dict[str, np.ndarray] = {}
    for channel in ("DG", "DD"):
        moved[channel] = np.zeros(starts.size)
        real[channel] = np.zeros(starts.size, dtype=bool)
        onsets[channel] = np.full(starts.size, np.nan)
        found = jumps.get(channel)
        if found is None or found.empty:
            continue
        jump_starts = found["t_start"].to_numpy(dtype=float)
        size = found["jump"].to_numpy(dtype=float)
        significant = (found["significant"].to_numpy(dtype=bool) if "significant" in found
                       else np.ones(size.size, dtype=bool))
        for k in range(starts.size):
            near = (jump_starts >= starts[k] - slack[k]) & (jump_starts <= ends[k] + slack[k])
            if near.any():  # the largest: a small precursor (creep) is not the slip
                best = np.flatnonzero(near)[np.argmax(np.abs(size[near]))]
                moved[channel][k] = size[best]
                real[channel][k] = significant[best]
                if significant[best]:
                    onsets[channel][k] = jump_starts[best]
    left, right = moved["DG"], moved["DD"]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(right != 0, left / right, np.where(left != 0, np.inf, np.nan))
    # the left edge jumped, and at least so far the right edge's way (even a step of the
    # right edge below its threshold has a sign); DG alone: gross
    gross = real["DG"] & (ratio >= gross_edge_ratio)
    if "DG" in jumps and "DD" in jumps:
        kind = np.where(gross, "gross_slip", "partial_slip")
    else:  # the rule compares the two edges
        kind = np.full(starts.size, "unclassified")
    lag = onsets["DG"] - onsets["DD"]
    direction = np.where(lag >= resolution_at, "right_to_left",
                         np.where(lag <= -resolution_at, "left_to_right", "unresolved"))
    table["kind"] = kind
    table["DG_jump"] = left
    table["DD_jump"] = right
    table["edge_ratio"] = ratio
    table["direction"] = direction
    return table


EDGE_CONVENTIONS = ("x_axis", "outward")
"""How edge sensors read: both along +x, or each its own edge's outward displacement."""


def edge_convention(time: np.ndarray, load: np.ndarray, left: np.ndarray,
                    drops: pd.DataFrame, *, start: int = 0, agreement: float = 0.8
                    ) -> tuple[str | None, str]:
    """How the left-edge sensor reads, from how it moves while the contact sticks.

    While the flat drags the sticking contact to the right, T rises and the
    slab's faces deflect towards +x: a sensor along +x reads the left edge
    rising with T, an outward-reading one (the paper's bench) falling. Each
    stick ramp between two drops (from ``start``, the end of the normal
    loading) votes when T rose by more than 8 times its noise and DG moved by
    more than 3 times its own.

    Parameters
    ----------
    time
        Sample times, s.
    load
        T.
    left
        DG, as recorded.
    drops
        From :func:`~slipwave.events.load_drops` (``i_start``, ``i_end``).
    start
        First sample of the tangential loading.
    agreement
        Share of the votes that decides.

    Returns
    -------
    tuple
        ``"x_axis"``, ``"outward"`` or ``None`` (the data cannot tell), and the
        evidence in words.

    Examples
    --------
    >>> t = np.arange(3000) * 0.01
    >>> T = 2.0 * (t % 10.0)
    >>> drops = pd.DataFrame({"i_start": [999, 1999], "i_end": [1000, 2000]})
    >>> edge_convention(t, T, -0.01 * T, drops)[0]
    'outward'
    """
    noise_t, noise_dg = noise_level(load), noise_level(left)
    bounds = [start, *np.ravel(np.column_stack([drops["i_start"], drops["i_end"]])).tolist(),
              load.size - 1]
    up = down = 0
    for first, last in zip(bounds[0::2], bounds[1::2], strict=False):
        first, last = int(first), int(last)
        if last - first < 10 or first < start:
            continue
        width = max(2, min(50, (last - first) // 5))
        rise = window_median(load, last - width, last) - window_median(load, first, first + width)
        moved = window_median(left, last - width, last) - window_median(left, first,
                                                                        first + width)
        if rise > 8 * noise_t and abs(moved) > 3 * noise_dg:
            up, down = up + (moved > 0), down + (moved < 0)
    votes = up + down
    evidence = (f"DG rose with T over {up} and fell over {down} of the stick ramps where "
                "both moved")
    if votes and up >= agreement * votes:
        return "x_axis", evidence
    if votes and down >= agreement * votes:
        return "outward", evidence
    return None, evidence


def _usable(recording: xr.Dataset, channel: str) -> bool:
    return channel in recording and bool(np.isfinite(recording[channel].values).any())


def _convention(recording: xr.Dataset, time: np.ndarray, load: np.ndarray, drops: pd.DataFrame,
                given: str, warnings: list[str]) -> tuple[str | None, str]:
    """The edge convention to use and why (``None`` without a DG channel)."""
    if given not in (*EDGE_CONVENTIONS, "auto"):
        raise SlipwaveError(f"edge_convention {given!r}: auto, x_axis or outward")
    if not _usable(recording, "DG"):
        return None, "no DG channel"
    if given != "auto":
        return given, "given"
    left = _fill_gaps(np.asarray(recording["DG"].values, dtype=float))
    found, evidence = edge_convention(time, _fill_gaps(load), left, drops,
                                      start=normal_loading_end(recording))
    if found is None:
        warnings.append(f"the edge sensors' convention cannot be told from the data ({evidence});"
                        " x_axis assumed: set edge_convention (x_axis or outward) for this test")
        return "x_axis", f"assumed: {evidence}"
    return found, f"measured: {evidence}"


@dataclass(frozen=True)
class DetectionSettings:
    """The settings of event detection, as every stage that detects uses them.

    How slips are found: the detect stage reads the measured events with them; the
    fit, the simulate stage and the comparison read the measured and the simulated
    recordings with the same ones, so that a campaign's ``detection`` section reaches
    every stage, and ``fit.json`` records them. Each is :func:`detect_events`'s
    argument of that name. How a slip is classified (``gross_edge_ratio``) is not
    among them: a simulated test reads its own off its simulated slips.

    Attributes
    ----------
    threshold, max_spike, max_duration, min_fall_rate
        As in :func:`~slipwave.events.load_drops`.
    edge_convention
        How the measured edge sensors read (:func:`detect_events`).

    Examples
    --------
    >>> settings = DetectionSettings(threshold=10.0)
    >>> DetectionSettings.from_dict(settings.to_dict()) == settings
    True
    """

    threshold: float = THRESHOLD
    max_spike: int = MAX_SPIKE
    max_duration: float | None = MAX_DURATION_S
    min_fall_rate: float = MIN_FALL_RATE
    edge_convention: str = EDGE_CONVENTION

    def keywords(self, **overrides: Any) -> dict[str, Any]:
        """:func:`detect_events`'s keyword arguments, some replaced.

        Parameters
        ----------
        **overrides
            Settings to replace (e.g. ``edge_convention="x_axis"`` for a simulated
            recording, whose edges read along +x).

        Returns
        -------
        dict
            Setting -> value.

        """
        return {**asdict(self), **overrides}

    def to_dict(self) -> dict[str, Any]:
        """The settings in plain types (``fit.json``'s ``detection``).

        Returns
        -------
        dict
            One entry per attribute.

        """
        return asdict(self)

    @classmethod
    def from_dict(cls, content: Mapping[str, Any]) -> DetectionSettings:
        """The settings of :meth:`to_dict`.

        Parameters
        ----------
        content
            Attribute -> value; a missing one takes its default.

        Returns
        -------
        DetectionSettings
            The settings.

        Raises
        ------
        SlipwaveError
            Naming a key that is not a setting.

        """
        unknown = sorted(set(content) - set(cls.__dataclass_fields__))
        if unknown:
            raise SlipwaveError(f"not detection settings: {', '.join(unknown)}")
        return cls(**content)


DEFAULT_DETECTION = DetectionSettings()
"""Detection with every setting at its default."""


def detect_events(
    recording: xr.Dataset,
    *,
    min_drop: float | None = None,
    min_jump: float | None = None,
    threshold: float = THRESHOLD,
    max_spike: int = MAX_SPIKE,
    max_duration: float | None = MAX_DURATION_S,
    min_fall_rate: float = MIN_FALL_RATE,
    gross_edge_ratio: float = GROSS_EDGE_RATIO,
    edge_convention: str = EDGE_CONVENTION,
) -> pd.DataFrame:
    """Slip events of a recording: T drops, classified, with loads and edge jumps.

    Parameters
    ----------
    recording
        A Dataset from :func:`slipwave.io.read_acquisition` (T and N at
        least; DG and DD to tell partial from gross slips).
    min_drop, min_jump
        Smallest T drop (N) and edge jump (mm); ``None``: ``threshold`` times
        each channel's noise level.
    threshold, max_spike, max_duration, min_fall_rate
        As in :func:`~slipwave.events.load_drops`.
    gross_edge_ratio
        As in :func:`classify_events`.
    edge_convention
        How the edge sensors read (:data:`EDGE_CONVENTIONS`), or ``"auto"``:
        found from the stick ramps (:func:`edge_convention`; when the data
        cannot tell, ``x_axis`` with a warning). An ``outward`` left sensor is
        turned to +x before the edges are compared, so ``DG_jump`` and
        ``edge_ratio`` are always along +x.

    Returns
    -------
    pandas.DataFrame
        One row per event with the columns of :data:`EVENT_COLUMNS` (see
        :data:`EVENT_DESCRIPTIONS`). ``DG_jump`` and ``DD_jump`` are measured
        across every event (:func:`~slipwave.events.edge_jumps` with ``at``),
        significant or not. ``attrs`` holds
        ``warnings`` (one per line), the noise levels and thresholds.

    Raises
    ------
    SlipwaveError
        If T is missing or has no finite value (without N, the loads and
        ratios that need it are NaN, with a warning).

    Examples
    --------
    >>> from slipwave.bench.sawtooth import SawtoothBench, sawtooth_recording
    >>> events = detect_events(sawtooth_recording(SawtoothBench(), seed=0))
    >>> events["kind"].value_counts().to_dict()
    {'gross_slip': 12, 'partial_slip': 8}
    """
    source = recording.attrs.get("source", "the recording")
    if not _usable(recording, "T"):
        raise SlipwaveError(f"{source}: channel T is missing or has no finite value")
    time = np.asarray(recording["time"].values, dtype=float)
    load = np.asarray(recording["T"].values, dtype=float)
    drops = load_drops(time, load, min_drop=min_drop, threshold=threshold,
                       max_spike=max_spike, max_duration=max_duration,
                       min_fall_rate=min_fall_rate)
    if len(drops) == 0:
        _check_direction(source, time, load)
    warnings: list[str] = []
    convention, evidence = _convention(recording, time, load, drops, edge_convention, warnings)
    jumps: dict[str, pd.DataFrame] = {}
    for channel in ("DG", "DD"):
        if _usable(recording, channel):
            values = np.asarray(recording[channel].values, dtype=float)
            if channel == "DG" and convention == "outward":
                values = -values  # along +x, as the rule compares them
            jumps[channel] = edge_jumps(time, values, at=drops, min_jump=min_jump,
                                        threshold=threshold, max_spike=max_spike)
    missing = [channel for channel in ("DG", "DD") if channel not in jumps]
    if missing:
        warnings.append(f"no usable {' or '.join(missing)} channel: events are T drops, "
                        "not classified into partial and gross slips")
    events = classify_events(drops, {} if missing else jumps,
                             gross_edge_ratio=gross_edge_ratio)
    if _usable(recording, "N"):
        normal = np.abs(np.asarray(recording["N"].values, dtype=float))
    else:  # a force-only record: no normal load, so no T/|N| either
        warnings.append("no usable N channel: T/|N| and the normal loading are unknown")
        normal = np.full(time.size, np.nan)
    starts = events["i_start"].to_numpy(dtype=np.int64)
    ends = events["i_end"].to_numpy(dtype=np.int64)
    # levels over windows as long as the event (at least 5 samples), clear of it
    width = np.maximum(ends - starts, 5)
    n_before = np.array([window_median(normal, s - w, s + 1)
                         for s, w in zip(starts, width, strict=True)])
    n_after = np.array([window_median(normal, e, e + w) for e, w in zip(ends, width, strict=True)])
    result = pd.DataFrame({
        "kind": events["kind"],
        "i_start": starts,
        "t_start": events["t_start"],
        "i_end": ends,
        "t_end": events["t_end"],
        "duration": events["duration"],
        "T_before": events["peak"],
        "T_after": events["trough"],
        "N_before": n_before,
        "N_after": n_after,
        "ratio_before": events["peak"] / n_before,
        "ratio_after": events["trough"] / n_after,
        "drop": events["drop"],
        "DG_jump": np.nan,
        "DD_jump": np.nan,
        "edge_ratio": np.nan,
        "direction": events["direction"],
    }, columns=list(EVENT_COLUMNS))
    for channel, found in jumps.items():
        result[f"{channel}_jump"] = found["jump"].to_numpy()
    with np.errstate(divide="ignore", invalid="ignore"):
        result["edge_ratio"] = result["DG_jump"] / result["DD_jump"]
    result.attrs.update(
        warnings="\n".join(warnings),
        edge_convention=convention or "",
        edge_convention_evidence=evidence,
        T_noise=drops.attrs.get("noise", np.nan),
        min_drop=drops.attrs.get("min_size", np.nan),
        sample_interval=drops.attrs.get("sample_interval", np.nan),
        **{f"{c}_noise": j.attrs.get("noise", np.nan) for c, j in jumps.items()},
        **{f"{c}_min_jump": j.attrs.get("min_size", np.nan) for c, j in jumps.items()},
    )
    return result


def _check_direction(source: object, time: np.ndarray, load: np.ndarray) -> None:
    """Refuse a test loaded along -x: T falls from its start where it should rise."""
    finite = np.isfinite(load)
    if finite.sum() < 10:
        return
    values = load[finite]
    start = float(np.median(values[: max(5, values.size // 100)]))
    low, high = np.percentile(values - start, [1, 99])
    if -low > 3.0 * max(high, 0.0) and -low > 0.0:
        at = float(time[finite][int(np.argmin(values))])
        raise SlipwaveError(
            f"{source}: T falls from {start:.3g} N to {start + low:.3g} N (lowest at t = "
            f"{at:.4g} s) and no drop of T is found: the test was loaded along -x; slipwave "
            "reads T positive along the drive (+x) and its slips as drops of T; record T "
            "along +x, or negate T, DG, DD and DT in a copy of the file")


def events_dataset(events: pd.DataFrame, phase: xr.DataArray) -> xr.Dataset:
    """Events (along ``event``), phases (along ``time``) and friction ratios in one Dataset.

    Columns become variables with CF ``units`` and ``long_name``; the
    detection's noise levels, thresholds and warnings become attributes. This
    is what ``events.nc`` holds; :func:`events_table` reads the events back.

    Parameters
    ----------
    events
        From :func:`detect_events`.
    phase
        From :func:`~slipwave.events.summary.segment_phases`.

    Returns
    -------
    xarray.Dataset
        Events, phases, friction ratios (:func:`~slipwave.events.summary.friction_ratio`)
        and the wave counts as attributes.

    """
    data = {}
    for column in EVENT_COLUMNS:
        attrs = {"long_name": EVENT_DESCRIPTIONS[column]}
        if column in EVENT_UNITS:
            attrs["units"] = EVENT_UNITS[column]
        values = events[column].to_numpy()
        data[column] = ("event", values.astype(str) if values.dtype == object else values, attrs)
    ratio = friction_ratio(events).rename({"time": "slip_time"})
    dataset = xr.Dataset(data, coords={"event": np.arange(len(events))})
    dataset = xr.merge([dataset, phase.to_dataset(), ratio], combine_attrs="override")
    attrs = {str(k): v for k, v in events.attrs.items() if k != "warnings"}
    dataset.attrs = {**attrs, "warnings": events.attrs.get("warnings", ""),
                     **wave_counts(events), "product": "events"}
    return dataset


def events_table(dataset: xr.Dataset) -> pd.DataFrame:
    """The events of an :func:`events_dataset` Dataset (``events.nc``) as a table.

    The inverse of :func:`events_dataset` for the events: the one place a
    stored events file becomes the DataFrame :func:`detect_events` returns.

    Parameters
    ----------
    dataset
        From :func:`events_dataset` (or read back from ``events.nc``).

    Returns
    -------
    pandas.DataFrame
        One row per event, the columns of :data:`EVENT_COLUMNS`; ``attrs``
        are the dataset's (noise levels, thresholds, ``warnings``, counts).

    Examples
    --------
    >>> from slipwave.bench.sawtooth import SawtoothBench, sawtooth_recording
    >>> from slipwave.events.summary import segment_phases
    >>> recording = sawtooth_recording(SawtoothBench(), seed=0)
    >>> events = detect_events(recording)
    >>> stored = events_dataset(events, segment_phases(recording, events))
    >>> events_table(stored).equals(events)
    True
    """
    table = dataset[list(EVENT_COLUMNS)].to_dataframe().reset_index(drop=True)
    table.attrs = dict(dataset.attrs)
    return table
