"""The waves stage: sliding waves tracked in a kymograph.

A wave shows as a front of fast change crossing the band above the interface:
:func:`track_waves` finds the frames where the band changes much more than it
does while the contact sticks, gives every position the time the change reached
it (:func:`arrivals`), follows the front from where it started for as long as
the arrivals go on in time (:func:`sweep`) and fits its speed.
Clock alignment is :mod:`slipwave.video.clock`, pairing with load events
:mod:`slipwave.video.fuse`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr
from scipy import ndimage, stats

from slipwave.io.tables import WAVE_COLUMNS

SMOOTHING = 3
"""Pixels along the band over which :func:`change` averages."""


MIN_EXTENT = 0.25
"""Smallest part of the contact length a wave must sweep to be tracked (:func:`track_waves`)."""


def change(kymo: xr.Dataset) -> xr.DataArray:
    """How much the band changed since the previous frame, at each frame and position.

    The kymograph's ``motion`` (mean absolute change of the band's pixels),
    smoothed over 3 pixels along the band; the first frame has none (0).

    Parameters
    ----------
    kymo
        From :func:`~slipwave.video.kymograph`.

    Returns
    -------
    xarray.DataArray
        (time, x), in units of the full grey scale.

    """
    smooth = ndimage.uniform_filter1d(kymo["motion"].values.astype(float), SMOOTHING, axis=1,
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
    max_gap: int = 2,
    min_extent: float = MIN_EXTENT,
    max_duration: float = 2.0,
    gross_extent: float = 0.95,
    min_frames: int = 3,
    floor: float = 0.8,
    max_hole: float = 10.0,
    edge: float = 2.0,
) -> pd.DataFrame:
    """Sliding waves of a kymograph: one row per wave.

    Frames where the band changes much more than while the contact sticks are
    grouped into waves. In each wave every position gets an arrival time (when
    its change peaked); the front starts where the change came first and the
    wave swept the positions reached from there with arrivals that do not go
    back in time. Beyond the tip of a partial slip the slab changes too (its
    stress redistributes), but all through the wave, not after the front: those
    positions arrive early and end the sweep (see :func:`sweep`).

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
        Quiet frames allowed inside one wave (a fading front).
    min_extent
        Smallest part of the contact length a wave must sweep (local changes at
        an edge are not waves).
    max_duration
        Longest wave (s): a longer change is the normal loading or sliding.
    gross_extent
        A wave sweeping at least this part of the contact is ``gross``; so is
        one whose front ran out at the far end of the contact (within
        ``edge``), however far it started from the other end (the contact
        opens at the trailing edge before it slides, so a gross slip does not
        sweep the whole length).
    min_frames
        A front must be seen in at least this many frames (arrivals spread over
        ``min_frames - 1`` frame periods) for its direction, speed and extent
        to be measured; a faster change is ``unresolved``.
    floor
        A position changed in the wave when its change rose above its own
        sticking level by ``floor`` times the typical frame's largest change.
    max_hole
        Longest stretch (mm) without change inside a front (where the fringe
        order is the same before and after, the intensity does not change).
    edge
        How close (mm) to the contact's end a front must run out to have gone
        through: the width of a front on the images, so a partial slip that
        stops closer than this to the edge is seen as gross.

    Returns
    -------
    pandas.DataFrame
        ``t_start`` (camera time: half a frame before the first changed
        frame), ``t_end`` (the last), ``frames``; ``x_start, x_end`` (mm, where
        the front started and where it stopped); ``x_min, x_max`` (the swept
        range); ``direction`` (``right_to_left``, ``left_to_right`` or
        ``unresolved``); ``speed`` (mm/s, Theil-Sen fit of position against
        arrival time, NaN when unresolved); ``extent`` (swept range over the
        contact length; for an unresolved wave, the changed range, an upper
        bound); ``kind`` (``gross``, ``partial`` or ``unresolved``).

    Examples
    --------
    A front crossing 60 of 80 positions (1 mm apart) from the right, four
    positions a frame; its extent runs between the centres of its end pixels
    (59 mm):

    >>> frames, columns = 40, 80
    >>> motion = np.full((frames, columns), 0.002)
    >>> for k in range(15):
    ...     motion[10 + k, 76 - 4 * k : 80 - 4 * k] = 0.2
    >>> kymo = xr.Dataset({"motion": (("time", "x"), motion)},
    ...                   coords={"time": 0.04 * np.arange(frames),
    ...                           "x": np.arange(columns) - 39.5},
    ...                   attrs={"geometry_length": 80.0})
    >>> wave = track_waves(kymo).iloc[0]
    >>> wave["direction"], round(wave["speed"]), round(float(wave["extent"]), 2), wave["kind"]
    ('right_to_left', 100, 0.74, 'partial')
    """
    moved = change(kymo).values
    time = kymo["time"].values.astype(float)
    x = kymo["x"].values.astype(float)
    length = float(kymo.attrs.get("geometry_length", np.ptp(x)))
    rows = []
    period = float(np.median(np.diff(time))) if time.size > 1 else 0.0
    # the stick phases' own level: the largest change of a typical (quiet) frame
    level = float(np.median(moved[1:].max(axis=1))) if moved.shape[0] > 1 else 0.0
    limit = 4.0 * level if threshold is None else float(threshold)
    busy = (moved > limit).sum(axis=1) >= min_columns
    busy[0] = False
    frames = np.flatnonzero(busy)
    if frames.size:
        # each position's own level while the contact sticks (waves are a few % of frames)
        quiet = np.percentile(moved[1:], 90, axis=0)
        pitch = float(np.median(np.abs(np.diff(x))))
        breaks = np.flatnonzero(np.diff(frames) > max_gap + 1)
        for group in np.split(frames, breaks + 1):
            if time[group[-1]] - time[group[0]] > max_duration:
                continue  # not a wave: the normal loading, or sliding
            window = np.arange(max(group[0] - 1, 1), min(group[-1] + 2 + max_gap, time.size))
            excess = np.maximum(moved[window] - quiet, 0.0)
            # 2 mm arriving too early in a row (half a front's width on the bench's
            # images) end the front; a lone early position does not
            found = sweep(excess, floor=floor * level,
                          hole=round(max_hole / pitch), stop=round(2.0 / pitch))
            if found is None:
                continue
            origin, end, arrival = found
            # the change was smoothed over SMOOTHING positions: it leaks half of that
            # past each end of the front, unless the end is the contact's
            origin, end = (_unleak(origin, end, x.size), _unleak(end, origin, x.size))
            low, high = sorted((x[origin], x[end]))
            extent = (high - low) / length
            if extent < min_extent:
                continue
            inside = np.isfinite(arrival)
            inside[: min(origin, end)] = False
            inside[max(origin, end) + 1 :] = False
            # how many frame periods the front took (5th to 95th percentile of the
            # arrivals: a lone position at the edge does not make a front)
            spread = float(np.subtract(*np.percentile(arrival[inside], [95, 5]))) \
                if inside.any() else 0.0
            if spread >= min_frames - 1:
                seconds = np.interp(arrival[inside], np.arange(window.size), time[window])
                speed = _front_speed(x[inside], seconds)
                direction = "right_to_left" if x[end] < x[origin] else "left_to_right"
                through = abs(x[end]) >= length / 2 - edge and (x[end] - x[origin]) * x[end] > 0
                kind = "gross" if extent >= gross_extent or through else "partial"
            else:
                speed, direction, kind = np.nan, "unresolved", "unresolved"
            rows.append((time[group[0]] - 0.5 * period, time[group[-1]], int(group.size),
                         float(x[origin]), float(x[end]), float(low), float(high), direction,
                         speed, extent, kind))
    table = pd.DataFrame(rows, columns=list(WAVE_COLUMNS))
    table.attrs.update(threshold=limit, frame_period=period, length=length)
    return table


def _unleak(tip: int, other: int, size: int) -> int:
    """Move one end of a front (position index) in by the smoothing's leak."""
    leak = SMOOTHING // 2
    if tip in (0, size - 1) or abs(tip - other) <= 2 * leak:
        return tip
    return tip + leak if other > tip else tip - leak


def arrivals(excess: np.ndarray, floor: float) -> np.ndarray:
    """When each position changed in a wave (frame index, between frames), NaN if it did not.

    ``excess`` (frames, positions) is the change above each position's
    sticking level. A position changed when its largest excess exceeds
    ``floor``; its arrival is the excess-weighted mean of the frames where the
    excess is at least half its largest (low, slow changes before or after do
    not move it).

    Parameters
    ----------
    excess
        (frames, positions) change above each position's sticking level.
    floor
        Least excess that counts as a change.

    Returns
    -------
    numpy.ndarray
        (positions,) frame indices, NaN where nothing changed.

    """
    peak = excess.max(axis=0)
    strong = np.where(excess >= 0.5 * peak, excess, 0.0)
    total = strong.sum(axis=0)
    arrival = (strong * np.arange(excess.shape[0])[:, None]).sum(axis=0) / np.where(
        total > 0, total, 1.0)
    return np.where(peak > floor, arrival, np.nan)


def sweep(excess: np.ndarray, *, floor: float, hole: int, stop: int,
          tolerance: float = 1.0) -> tuple[int, int, np.ndarray] | None:
    """Where a wave's front started and where it stopped (position indices).

    The front starts at the earliest arrival (:func:`arrivals`, median of 5
    neighbours). From there it is followed each way while arrivals do not fall
    more than ``tolerance`` frames below the latest one reached, over holes of
    at most ``hole`` positions without change, until more than ``stop``
    positions in a row arrive too early; the way it goes is the one where
    arrivals grow most (a front runs one way; the slab's relaxation around it
    comes all through the wave). Behind the start, positions arriving within
    ``tolerance`` of the start are swept too (the front's own width).

    Returns ``(start, end, arrivals)``, or ``None`` when fewer than 3 positions
    changed.

    Parameters
    ----------
    excess
        As in :func:`arrivals`.
    floor
        As in :func:`arrivals`.
    hole
        Positions without a change the front may cross.
    stop
        Positions from the start beyond which an early arrival ends the sweep.
    tolerance
        Frames an arrival may come before its neighbour's and still follow it.

    Returns
    -------
    tuple or None
        (start, stop, arrival times), or ``None`` without a front.

    """
    arrival = arrivals(excess, floor)
    changed = np.flatnonzero(np.isfinite(arrival))
    if changed.size < 3:
        return None
    smooth = ndimage.median_filter(arrival[changed], 5, mode="nearest")
    origin = int(changed[np.argmin(smooth)])
    ahead = {way: _follow(arrival, origin, way, hole, stop, tolerance) for way in (-1, 1)}
    way = max(ahead, key=lambda w: (ahead[w][1], abs(ahead[w][0] - origin)))
    end = ahead[way][0]
    behind = _follow(arrival, origin, -way, hole, stop, tolerance, ahead=False)[0]
    return behind, end, arrival


def _follow(arrival: np.ndarray, origin: int, way: int, hole: int, stop: int,
            tolerance: float, *, ahead: bool = True) -> tuple[int, float]:
    """Last position reached from ``origin`` going ``way``, and the latest arrival there.

    Ahead of the start a position must not arrive more than ``tolerance``
    before the latest arrival so far; behind it, not more than ``tolerance``
    after the start.
    """
    latest = first = arrival[origin]
    last, quiet, early = origin, 0, 0
    k = origin + way
    while 0 <= k < arrival.size:
        if not np.isfinite(arrival[k]):
            quiet += 1
            if quiet > hole:
                break
        else:
            quiet = 0
            fits = arrival[k] >= latest - tolerance if ahead else arrival[k] <= first + tolerance
            if fits:
                early, last = 0, k
                latest = max(latest, arrival[k])
            else:
                early += 1
                if early > stop:
                    break
        k += way
    return last, float(latest - first)


def _front_speed(positions: np.ndarray, arrival: np.ndarray) -> float:
    """Front speed (mm/s): slope of positions against their arrival times (s).

    Positions that arrived with the first or last of them (the change there came
    all at once as the wave set off or stopped) are left out when enough
    remain. Theil-Sen: robust to the odd misplaced position.
    """
    inner = (arrival > arrival.min() + 1e-9) & (arrival < arrival.max() - 1e-9)
    if inner.sum() >= 3:
        positions, arrival = positions[inner], arrival[inner]
    if np.ptp(arrival) == 0:
        return np.nan
    return float(abs(stats.theilslopes(positions, arrival)[0]))
