"""Sliding waves in a kymograph, camera and card clocks, and waves paired with load events.

A wave shows as a front of fast change crossing the band above the interface:
:func:`track_waves` finds the frames where the band changes much more than it
does while the contact sticks, follows the front (where the change is
strongest) frame by frame and fits its speed. :func:`align_clocks` maps camera
time to acquisition time; :func:`fuse` gives each load event its wave.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import xarray as xr
from scipy import ndimage, stats

WAVE_COLUMNS = ("t_start", "t_end", "frames", "x_start", "x_end", "x_min", "x_max",
                "direction", "speed", "extent", "kind")
"""Columns of :func:`track_waves`."""


def change(kymo: xr.Dataset) -> xr.DataArray:
    """How much the band changed since the previous frame, at each frame and position.

    The kymograph's ``motion`` (mean absolute change of the band's pixels),
    smoothed over 3 pixels along the band; the first frame has none (0).
    """
    smooth = ndimage.uniform_filter1d(kymo["motion"].values.astype(float), 3, axis=1,
                                      mode="nearest")
    smooth[0] = 0.0
    return xr.DataArray(smooth, coords=kymo["motion"].coords, dims=("time", "x"),
                        name="change", attrs={"units": "1",
                                              "long_name": "change of the band since the "
                                                           "previous frame (full scale)"})


def track_waves(
    kymo: xr.Dataset,
    *,
    threshold: float | None = None,
    min_columns: int = 3,
    max_gap: int = 1,
    min_extent: float = 0.25,
    max_duration: float = 2.0,
    gross_extent: float = 0.95,
) -> pd.DataFrame:
    """Sliding waves of a kymograph: one row per wave.

    Parameters
    ----------
    kymo
        From :func:`~slipwave.video.kymograph` (``length`` is taken from its
        geometry attributes).
    threshold
        Change (full scale) above which a pixel of the band is active;
        ``None``: 4 times the largest change of a typical frame (the stick
        phases' own level).
    min_columns
        A frame takes part in a wave when at least this many pixels are active.
    max_gap
        Quiet frames allowed inside one wave.
    min_extent
        Smallest part of the contact length a wave must sweep (local changes at
        an edge are not waves).
    max_duration
        Longest wave (s): a longer change is the normal loading or sliding.
    gross_extent
        A wave sweeping at least this part of the contact is ``gross``.

    Returns
    -------
    pandas.DataFrame
        ``t_start`` (camera time: half a frame before the first changed
        frame), ``t_end`` (the last), ``frames``; ``x_start, x_end`` (the
        front, mm, at the first and last frames); ``x_min, x_max`` (the swept
        range); ``direction`` (``right_to_left`` / ``left_to_right``);
        ``speed`` (mm/s, a Theil-Sen fit of the front against time, NaN on a
        single frame); ``extent`` (swept range over the contact length);
        ``kind`` (``gross`` or ``partial``).
    """
    moved = change(kymo).values
    time = kymo["time"].values.astype(float)
    x = kymo["x"].values.astype(float)
    length = float(kymo.attrs.get("geometry_length", np.ptp(x)))
    # the stick phases' own level: the largest change of a typical (quiet) frame
    level = float(np.median(moved[1:].max(axis=1))) if moved.shape[0] > 1 else 0.0
    limit = 4.0 * level if threshold is None else float(threshold)
    active = moved > limit
    busy = active.sum(axis=1) >= min_columns
    busy[0] = False
    frames = np.flatnonzero(busy)
    period = float(np.median(np.diff(time))) if time.size > 1 else 0.0
    rows = []
    if frames.size:
        breaks = np.flatnonzero(np.diff(frames) > max_gap + 1)
        for group in np.split(frames, breaks + 1):
            span = np.arange(group[0], group[-1] + 1)
            span = span[busy[span]]
            front = np.array([_front(x, moved[k], active[k]) for k in span])
            swept = x[active[span].any(axis=0)]
            low, high = float(swept.min()), float(swept.max())
            if high - low < min_extent * length or np.ptp(time[span]) > max_duration:
                continue  # a local change at an edge, or not a wave (loading, sliding)
            slope = _front_speed(x, time[span], moved[span], active[span])
            way = front[-1] - front[0] if span.size > 1 else 0.0
            direction = "right_to_left" if (slope < 0 if np.isfinite(slope) else way < 0) \
                else "left_to_right"
            extent = (high - low) / length
            rows.append((time[span[0]] - 0.5 * period, time[span[-1]], int(span.size),
                         float(front[0]), float(front[-1]), low, high, direction,
                         abs(slope), extent, "gross" if extent >= gross_extent else "partial"))
    table = pd.DataFrame(rows, columns=list(WAVE_COLUMNS))
    table.attrs.update(threshold=limit, frame_period=period, length=length)
    return table


def _front(x: np.ndarray, moved: np.ndarray, active: np.ndarray) -> float:
    """Where the front is in one frame: the middle of the longest run of active pixels."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], active.astype(np.int8), [0]])))
    starts, stops = edges[0::2], edges[1::2]
    if starts.size == 0:
        return float(x[np.argmax(moved)])
    longest = int(np.argmax(stops - starts))
    # the middle of the run, not a weighted centre: fringes crowd on one side
    return float(0.5 * (x[starts[longest]] + x[stops[longest] - 1]))


def _front_speed(x: np.ndarray, time: np.ndarray, moved: np.ndarray,
                 active: np.ndarray) -> float:
    """Front velocity (mm/s, signed): positions against their arrival times.

    A position's arrival time is the change-weighted mean of the wave's frame
    times there (between frames, not on them); positions that changed only in
    the first or last frame (all at once as the wave set off or stopped) are
    left out. Theil-Sen: robust to the odd misplaced column.
    """
    if time.size < 2:
        return np.nan
    weights = np.where(active, moved, 0.0)
    total = weights.sum(axis=0)
    seen = total > 0
    arrival = (weights[:, seen] * time[:, None]).sum(axis=0) / total[seen]
    inner = (arrival > time[0] + 1e-9) & (arrival < time[-1] - 1e-9)
    if inner.sum() >= 3 and time.size >= 4:
        positions, arrival = x[seen][inner], arrival[inner]
    else:
        positions = x[seen]
    if np.ptp(arrival) == 0:
        return np.nan
    # position against time: the slope is the velocity
    return float(stats.theilslopes(positions, arrival)[0])


@dataclass(frozen=True)
class ClockFit:
    """Acquisition time = ``offset + rate * camera time``; how it was found and how well."""

    offset: float
    rate: float
    residual: float
    method: str
    pairs: int

    def acquisition_time(self, camera_time: np.ndarray | float) -> np.ndarray:
        """The acquisition-card time of camera times."""
        return self.offset + self.rate * np.asarray(camera_time, dtype=float)


def sync_offset(kymo: xr.Dataset, sync_time: float) -> float | None:
    """Clock offset from the sync LED lit at acquisition time ``sync_time``, if it shows.

    The first lit frame comes at most one frame after the LED lit up: the
    offset is taken half a frame before it. ``None`` when no frame is lit.
    """
    level = kymo["sync"].values.astype(float)
    lit = level > 0.5 * (level.max() + np.median(level))
    if level.max() - np.median(level) < 0.2 or not lit.any():
        return None
    time = kymo["time"].values.astype(float)
    period = float(np.median(np.diff(time)))
    return float(sync_time - time[np.argmax(lit)] + 0.5 * period)


def correlation_offset(kymo: xr.Dataset, recording: xr.Dataset, *,
                       max_offset: float = 60.0) -> float:
    """Clock offset that best lines up the video's activity with the fall rate of T.

    Cross-correlates the band's total change per frame with ``max(-dT/dt, 0)``
    sampled on the frames, over offsets up to ``max_offset`` (s) either way.
    """
    time = kymo["time"].values.astype(float)
    period = float(np.median(np.diff(time)))
    activity = change(kymo).values.sum(axis=1)
    activity = activity - activity.mean()
    card = recording["time"].values.astype(float)
    falling = np.maximum(-np.gradient(recording["T"].values.astype(float), card), 0.0)
    lags = np.arange(-max_offset, max_offset + period, period)
    grid = time[0] + np.arange(time.size) * period
    best, score = 0.0, -np.inf
    for lag in lags:
        sampled = np.interp(grid + lag, card, falling, left=0.0, right=0.0)
        value = float(activity @ (sampled - sampled.mean()))
        if value > score:
            best, score = float(lag), value
    return best


def align_clocks(
    waves: pd.DataFrame,
    kymo: xr.Dataset,
    recording: xr.Dataset,
    events: pd.DataFrame,
    *,
    sync_time: float | None = None,
    tolerance: float = 0.3,
) -> ClockFit:
    """Offset and rate between the camera's and the acquisition card's clocks.

    A first offset comes from the sync LED (``sync_time``, by default the
    recording's ``sync_time_s`` attribute) or, without one, from
    :func:`correlation_offset`. Then every wave whose start falls within
    ``tolerance`` (s) of a load event's onset is paired with it and a straight
    line (acquisition = offset + rate x camera) is fitted to the pairs
    (Theil-Sen: a wrong pair does not tilt it); the residual is the robust
    standard deviation (1.4826 MAD) of its misfit (wave starts are known to a
    frame).
    """
    if sync_time is None and "sync_time_s" in recording.attrs:
        sync_time = float(recording.attrs["sync_time_s"])
    first = sync_offset(kymo, sync_time) if sync_time is not None else None
    method = "sync LED"
    if first is None:
        first, method = correlation_offset(kymo, recording), "cross-correlation"
    camera = waves["t_start"].to_numpy(dtype=float)
    onsets = events["t_start"].to_numpy(dtype=float) if len(events) else np.array([])
    fit = ClockFit(first, 1.0, np.nan, method, 0)
    for _ in range(2):  # pair, fit, pair again with the better clock
        if camera.size == 0 or onsets.size == 0:
            return fit
        mapped = fit.acquisition_time(camera)
        nearest = np.abs(mapped[:, None] - onsets[None, :]).argmin(axis=1)
        close = np.abs(mapped - onsets[nearest]) <= tolerance
        if close.sum() < 3:
            return fit
        paired = onsets[nearest[close]]
        rate = float(stats.theilslopes(paired, camera[close])[0])
        offset = float(np.median(paired - rate * camera[close]))
        misfit = onsets[nearest[close]] - (offset + rate * camera[close])
        spread = 1.4826 * float(np.median(np.abs(misfit - np.median(misfit))))
        fit = ClockFit(float(offset), float(rate), spread,
                       f"{method}, then {int(close.sum())} wave/event pairs",
                       int(close.sum()))
    return fit


def fuse(events: pd.DataFrame, waves: pd.DataFrame, clock: ClockFit, *,
         tolerance: float = 0.3) -> pd.DataFrame:
    """Each load event with its wave; waves without an event and events without one kept.

    Waves are put on the card's clock, then each event takes the nearest wave
    starting within ``tolerance`` (s) of its onset (each wave once). Columns
    ``wave_*`` describe the wave; ``video_kind`` is its kind from the swept
    extent and ``kind_agrees`` compares it with the event's; ``source`` says
    ``both``, ``load`` (no wave seen) or ``video`` (a wave without a T drop).
    """
    starts = clock.acquisition_time(waves["t_start"].to_numpy(dtype=float))
    taken = np.zeros(len(waves), dtype=bool)
    chosen = np.full(len(events), -1)
    onsets = events["t_start"].to_numpy(dtype=float)
    for k in np.argsort(onsets):
        gap = np.abs(starts - onsets[k])
        gap[taken] = np.inf
        if gap.size and gap.min() <= tolerance:
            chosen[k] = int(np.argmin(gap))
            taken[chosen[k]] = True
    described = waves[list(WAVE_COLUMNS)].assign(
        t_start=starts, t_end=clock.acquisition_time(waves["t_end"].to_numpy(dtype=float)))
    columns = {f"wave_{c}": c for c in WAVE_COLUMNS}
    fused = events.reset_index(drop=True).copy()
    for name, column in columns.items():
        values = described[column].to_numpy()
        fused[name] = [values[i] if i >= 0 else None for i in chosen]
    fused["source"] = np.where(chosen >= 0, "both", "load")
    alone = described[~taken].rename(columns={c: name for name, c in columns.items()})
    alone = alone.assign(kind="none", t_start=alone["wave_t_start"], source="video")
    fused = pd.concat([fused, alone], ignore_index=True).sort_values("t_start",
                                                                      ignore_index=True)
    video_kind = fused["wave_kind"].map({"gross": "gross_slip", "partial": "partial_slip"})
    fused["video_kind"] = video_kind
    fused["kind_agrees"] = (fused["kind"] == video_kind).where(fused["source"] == "both")
    return fused

