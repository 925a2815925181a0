"""The sliding waves of a quasi-dynamic simulation, from its fronts' crossings.

A node slips while its slip rate is above the run's front speed
(:func:`slipwave.solver.quasi_dynamic.simulate_quasi_dynamic` records each
crossing of it); a wave is a connected patch of slip in space and time: the slip
intervals of neighbouring nodes that overlap in time. Each wave is described in the
columns of the video's waves table (:data:`slipwave.io.tables.WAVE_COLUMNS`), so that
the two compare column by column: where it started (the first node to slip), which
way it ran (towards the farther of its two ends), how far, and how fast (the slope of
position against arrival time on that side, Theil-Sen as the video's).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr
from scipy import stats

from slipwave.io.tables import WAVE_COLUMNS
from slipwave.solver.contact import OPEN, SLIP, STICK
from slipwave.solver.zones import node_conditions

GROSS_EXTENT = 0.95
"""A wave that slips every node in contact when it starts, or this share of the contact
length, is a gross slip (the video's ``gross_extent``)."""


def field_conditions(ds: xr.Dataset, *, slip_speed: float | None = None) -> np.ndarray:
    """Each node's condition at each field record, as the quasi-static solver's zones.

    Parameters
    ----------
    ds
        A quasi-dynamic simulation.
    slip_speed
        The slip rate (mm/s) above which a node slips; the run's front speed by default.
        Under slow loading a slip zone's tip slips far slower than the drive: a
        thousandth of the drive's speed tells it from the creep of a stuck node, which
        rate-and-state friction never stops.

    Returns
    -------
    numpy.ndarray
        (field_time, x) codes of :func:`slipwave.solver.zones.node_conditions`: open,
        stick, slipping towards -x or +x relative to the flat.
    """
    limit = float(ds.attrs["front_speed"]) if slip_speed is None else slip_speed
    speed = ds["slip_rate"].values
    state = np.where(ds["contact"].values < 0.5, OPEN,
                     np.where(np.abs(speed) > limit, SLIP, STICK))
    return node_conditions(state, np.sign(speed))


def slip_intervals(ds: xr.Dataset) -> pd.DataFrame:
    """Each node's stretches of slip: from a rising crossing to the next falling one.

    Parameters
    ----------
    ds
        A quasi-dynamic simulation (its ``crossing_*`` variables and ``x``).

    Returns
    -------
    pandas.DataFrame
        ``node`` (index along ``x``), ``start`` and ``end`` (s; the record's end for a
        node still slipping there), sorted by node then start.
    """
    x = ds["x"].values
    nodes = np.searchsorted(x, ds["crossing_x"].values)
    times = ds["crossing_time"].values
    rising = ds["crossing_rising"].values.astype(bool)
    last = float(ds["time"].values[-1])
    rows = []
    for node in np.unique(nodes):
        mine = np.flatnonzero(nodes == node)
        mine = mine[np.argsort(times[mine], kind="stable")]
        start = None
        for k in mine:
            if rising[k] and start is None:
                start = times[k]
            elif not rising[k] and start is not None:
                rows.append((int(node), float(start), float(times[k])))
                start = None
        if start is not None:
            rows.append((int(node), float(start), last))
    return pd.DataFrame(rows, columns=["node", "start", "end"])


def _patches(intervals: pd.DataFrame) -> np.ndarray:
    """A label per interval: those of neighbouring nodes that overlap share one."""
    parent = np.arange(len(intervals))

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    nodes = intervals["node"].to_numpy()
    by_node = {int(node): np.flatnonzero(nodes == node) for node in np.unique(nodes)}
    start, end = intervals["start"].to_numpy(), intervals["end"].to_numpy()
    for node, mine in by_node.items():
        theirs = by_node.get(node + 1)
        if theirs is None:
            continue
        # both lists are sorted by start: sweep them together
        i = j = 0
        while i < mine.size and j < theirs.size:
            a, b = mine[i], theirs[j]
            if start[a] <= end[b] and start[b] <= end[a]:
                parent[root(a)] = root(b)
            if end[a] < end[b]:
                i += 1
            else:
                j += 1
    return np.array([root(k) for k in range(len(intervals))])


def _speed(positions: np.ndarray, arrivals: np.ndarray) -> float:
    """|d position / d arrival| by Theil-Sen, mm/s (NaN with fewer than 3 nodes)."""
    if positions.size < 3 or np.ptp(arrivals) == 0:
        return float("nan")
    return float(abs(stats.theilslopes(positions, arrivals)[0]))


def front_waves(ds: xr.Dataset, *, min_extent: float = 0.0,
                gross_extent: float = GROSS_EXTENT) -> pd.DataFrame:
    """The simulation's waves, one row each, in the video's waves table's columns.

    Parameters
    ----------
    ds
        A quasi-dynamic simulation.
    min_extent
        The smallest share of the contact length a wave must sweep to be kept (the
        video keeps a quarter and up: pass its ``MIN_EXTENT`` to compare like with like).
    gross_extent
        The share of the contact length from which a wave is a gross slip.

    Returns
    -------
    pandas.DataFrame
        :data:`~slipwave.io.tables.WAVE_COLUMNS`: ``t_start``, ``t_end`` (s), ``frames``
        (empty: a simulation has no frames), ``x_start`` (where it started), ``x_end``
        (the end it ran to), ``x_min``, ``x_max`` (mm), ``direction``
        (``left_to_right``, ``right_to_left``, or ``unresolved`` for one node),
        ``speed`` (mm/s, on the side it ran to), ``extent`` (share of the contact
        length) and ``kind`` (``gross`` or ``partial``).
    """
    intervals = slip_intervals(ds)
    x = ds["x"].values
    length = float(np.ptp(x))
    contact = ds["contact"].values
    field_time = ds["field_time"].values
    rows = []
    if len(intervals):
        labels = _patches(intervals)
        for label in np.unique(labels):
            patch = intervals[labels == label]
            first = patch.groupby("node")["start"].min()
            nodes, arrivals = first.index.to_numpy(), first.to_numpy()
            origin = int(nodes[np.argmin(arrivals)])
            low, high = float(x[nodes.min()]), float(x[nodes.max()])
            extent = (high - low) / length
            if extent < min_extent:
                continue
            left = x[origin] - low
            right = high - x[origin]
            side = nodes >= origin if right >= left else nodes <= origin
            end = high if right >= left else low
            direction = ("unresolved" if nodes.size == 1 else
                         "left_to_right" if right >= left else "right_to_left")
            t_start = float(arrivals.min())
            # the nodes on the flat when it started: all slipped makes it a gross slip
            record = max(int(np.searchsorted(field_time, t_start, side="right")) - 1, 0)
            closed = np.flatnonzero(contact[record] > 0.5)
            gross = extent >= gross_extent or bool(np.isin(closed, nodes).all())
            rows.append((t_start, float(patch["end"].max()), pd.NA, float(x[origin]), end,
                         low, high, direction, _speed(x[nodes[side]], arrivals[side]),
                         extent, "gross" if gross else "partial"))
    table = pd.DataFrame(rows, columns=list(WAVE_COLUMNS))
    return table.sort_values("t_start", ignore_index=True)
