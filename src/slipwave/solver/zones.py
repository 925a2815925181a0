"""Zones of the interface followed from step to step: the history a behaviour is read from.

At each load step the contact nodes are open, sticking or slipping, and a slipping
node slips one way or the other relative to the flat. A *zone* is a run of
neighbouring nodes in one of four conditions: ``open``, ``stick``, ``slip_back``
(the slab slips towards -x relative to the flat, the way the flat's drag to +x makes
it slip) and ``slip_forward`` (towards +x: at the right edge, the outward slip of the
normal loading unloading). Runs shorter than a physical size (``min_size`` mm, about
two elements) decide nothing: they are absorbed by their neighbours, so a single
node flickering at a corner does not make a zone.

:func:`track_zones` follows the zones from step to step (a zone continues the zone of
the previous step of the same condition it overlaps most; several merging keep the
largest's identity) and :func:`zone_events` lists what happened: zones appearing
(at the left edge, the right edge or inside), merging and vanishing, with where
they were.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeAlias, cast

import numpy as np
import pandas as pd

from slipwave.solver.contact import OPEN, SLIP, STICK

CONDITIONS = ("open", "stick", "slip_back", "slip_forward")
"""Zone conditions, in the order of their codes in :func:`node_conditions`."""


def node_conditions(state: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """The condition code of each node (index into :data:`CONDITIONS`).

    Parameters
    ----------
    state
        Contact states (0 open, 1 stick, 2 slip), any shape.
    direction
        Sign of each node's slip increment relative to the flat, same shape.

    Returns
    -------
    numpy.ndarray
        int8 codes: 0 open, 1 stick, 2 slipping towards -x, 3 slipping towards +x.

    Examples
    --------
    >>> node_conditions(np.array([0, 1, 2, 2]), np.array([0, 0, -1, 1])).tolist()
    [0, 1, 2, 3]
    """
    codes = np.where(state == OPEN, 0, 1).astype(np.int8)
    slipping = state == SLIP
    codes[slipping & (direction >= 0)] = 3
    codes[slipping & (direction < 0)] = 2
    codes[state == STICK] = 1
    return codes


def zone_runs(codes: np.ndarray, spacing: float, min_size: float) -> list[tuple[int, int, int]]:
    """Runs of equal condition along the contact, the runs shorter than ``min_size`` absorbed.

    The shortest run under the size is given to the longer of its neighbours (or
    its only one), again and again until every run is at least ``min_size`` long
    or the contact holds a single run.

    Parameters
    ----------
    codes
        Condition codes of the nodes, left to right (:func:`node_conditions`).
    spacing
        Distance between nodes, mm.
    min_size
        Shortest zone that counts, mm.

    Returns
    -------
    list of tuple
        (code, first node, last node) per run, left to right.

    Examples
    --------
    A one-node slip at the corner does not count, a six-node one does:

    >>> zone_runs(np.array([2, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2]), 0.5, 1.0)
    [(1, 0, 5), (2, 6, 11)]
    """
    change = np.flatnonzero(codes[1:] != codes[:-1]) + 1
    starts = np.concatenate([[0], change]).tolist()
    ends = np.concatenate([change - 1, [codes.size - 1]]).tolist()
    runs = [[int(codes[a]), a, b] for a, b in zip(starts, ends, strict=True)]
    while len(runs) > 1:
        lengths = [(b - a + 1) * spacing for _, a, b in runs]
        k = min(range(len(runs)), key=lengths.__getitem__)  # the first shortest
        if lengths[k] >= min_size:
            break
        neighbours = [j for j in (k - 1, k + 1) if 0 <= j < len(runs)]
        into = max(neighbours, key=lambda j: lengths[j])
        runs[into][1] = min(runs[into][1], runs[k][1])
        runs[into][2] = max(runs[into][2], runs[k][2])
        del runs[k]
        merged: list[list[int]] = []  # neighbours of one condition become one run
        for run in runs:
            if merged and merged[-1][0] == run[0]:
                merged[-1][2] = run[2]
            else:
                merged.append(run)
        runs = merged
    return [(code, a, b) for code, a, b in runs]


if TYPE_CHECKING:
    # a zone at a step: (step, identity, condition code, first node, last node,
    # identities of the previous step's zones it absorbed)
    Zone: TypeAlias = tuple[int, int, int, int, int, tuple[int, ...]]


def follow_zones(codes: np.ndarray, spacing: float, min_size: float) -> list[Zone]:
    """Every zone at every step, with an identity kept from step to step (plain tuples).

    A zone continues the zone of the previous step of the same condition that it
    overlaps most; the others it overlaps are absorbed (a merge). A zone split in
    two keeps its identity in its larger part.

    Parameters
    ----------
    codes
        (steps, nodes) condition codes (:func:`node_conditions`).
    spacing
        Distance between nodes, mm.
    min_size
        Shortest zone that counts, mm (:func:`zone_runs`).

    Returns
    -------
    list of tuple
        One tuple per zone, step by step, left to right: (step, identity, condition
        code, first node, last node, identities of the previous step's zones it
        absorbed).

    Examples
    --------
    >>> codes = np.array([[1] * 8, [1] * 6 + [2] * 2, [1] * 3 + [2] * 5])
    >>> [z for z in follow_zones(codes, 1.0, 1.5) if z[2] == 2]
    [(1, 1, 2, 6, 7, ()), (2, 1, 2, 3, 7, ())]
    """
    out: list[Zone] = []
    previous: list[tuple[int, int, int, int]] = []  # (zone, code, first, last)
    next_zone = 0
    for step, line in enumerate(codes):
        current: list[tuple[int, int, int, int]] = []
        absorbed_by: list[tuple[int, ...]] = []
        for code, first, last in zone_runs(line, spacing, min_size):
            overlap = sorted(((min(last, b) - max(first, a) + 1, zone)
                              for zone, c, a, b in previous
                              if c == code and a <= last and b >= first), reverse=True)
            if overlap:
                zone, absorbed = overlap[0][1], tuple(z for _, z in overlap[1:])
            else:
                zone, next_zone, absorbed = next_zone, next_zone + 1, ()
            current.append((zone, code, first, last))
            absorbed_by.append(absorbed)
        seen: dict[int, int] = {}
        for k, (zone, _, first, last) in enumerate(current):
            if zone in seen:  # a split: the smaller part is a new zone
                other = seen[zone]
                keep, give = ((other, k) if current[other][3] - current[other][2]
                              >= last - first else (k, other))
                _, c, a, b = current[give]
                current[give] = (next_zone, c, a, b)
                seen[zone] = keep
                next_zone += 1
            else:
                seen[zone] = k
        out.extend((step, zone, code, first, last, absorbed)
                   for (zone, code, first, last), absorbed in zip(current, absorbed_by,
                                                                  strict=True))
        previous = current
    return out


def track_zones(codes: np.ndarray, x: np.ndarray, *, min_size: float) -> pd.DataFrame:
    """Every zone at every step, with an identity kept from step to step, as a table.

    Parameters
    ----------
    codes
        (steps, nodes) condition codes (:func:`node_conditions`).
    x
        Node positions, mm, left to right, evenly spaced.
    min_size
        Shortest zone that counts, mm (:func:`zone_runs`).

    Returns
    -------
    pandas.DataFrame
        One row per zone and step: ``step``, ``zone`` (identity), ``condition``,
        ``first``, ``last`` (nodes), ``x_left``, ``x_right`` (mm), ``merged``
        (identities of the zones of the previous step it absorbed, space
        separated). See :func:`follow_zones`.

    Examples
    --------
    A slip zone entering from the right edge and growing to the left keeps its identity:

    >>> codes = np.array([[1] * 8, [1] * 6 + [2] * 2, [1] * 3 + [2] * 5])
    >>> zones = track_zones(codes, np.arange(8.0), min_size=1.5)
    >>> zones[zones["condition"] == "slip_back"][["step", "zone", "first"]].values.tolist()
    [[1, 1, 6], [2, 1, 3]]
    """
    spacing = float(x[1] - x[0]) if x.size > 1 else 1.0
    rows = [{"step": step, "zone": zone, "condition": CONDITIONS[code], "first": first,
             "last": last, "x_left": float(x[first]), "x_right": float(x[last]),
             "merged": " ".join(str(z) for z in absorbed)}
            for step, zone, code, first, last, absorbed in follow_zones(codes, spacing,
                                                                         min_size)]
    return pd.DataFrame(rows, columns=["step", "zone", "condition", "first", "last", "x_left",
                                       "x_right", "merged"])


def zone_events(zones: pd.DataFrame) -> pd.DataFrame:
    """What happened to the zones: appear (where), merge, vanish, one event per row.

    Parameters
    ----------
    zones
        From :func:`track_zones`.

    Returns
    -------
    pandas.DataFrame
        ``step``, ``event`` (``appear``, ``merge``, ``vanish``), ``zone``,
        ``condition``, ``where`` (``left_edge``, ``right_edge``, ``interior``,
        ``whole``: where the zone touches the contact's ends, the part of the
        interface not open at that step), ``x_left``, ``x_right``. Zones present
        at the first step are listed as appearing there.

    Examples
    --------
    A slip zone appears beside the open right edge, then the contact sticks again:

    >>> codes = np.array([[1] * 8, [1] * 4 + [2] * 2 + [0] * 2, [1] * 6 + [0] * 2])
    >>> events = zone_events(track_zones(codes, np.arange(8.0), min_size=1.5))
    >>> events[["step", "event", "condition", "where"]].values.tolist()[1:3]
    [[1, 'appear', 'slip_back', 'right_edge'], [1, 'appear', 'open', 'right_edge']]
    >>> events[["step", "event", "condition"]].values.tolist()[-1]
    [2, 'vanish', 'slip_back']
    """
    rows = []
    last_seen: dict[int, tuple[pd.Series, str]] = {}
    for key, group in zones.groupby("step", sort=True):
        step = int(cast(int, key))
        contact = group[group["condition"] != "open"]
        ends = ((int(contact["first"].min()), int(contact["last"].max())) if len(contact)
                else (int(group["first"].min()), int(group["last"].max())))
        present = set(group["zone"])
        absorbed_now = {int(z) for m in group["merged"] for z in str(m).split(" ") if z}
        for _, zone in group.iterrows():
            where = _where(zone, ends)
            if int(cast(int, zone["zone"])) not in last_seen:
                rows.append(_event(step, "appear", zone, where))
            for absorbed in filter(None, str(zone["merged"]).split(" ")):
                rows.append(_event(step, "merge", *last_seen[int(absorbed)]))
        for identity, (zone, where) in list(last_seen.items()):
            if identity not in present and identity not in absorbed_now:
                rows.append(_event(step, "vanish", zone, where))
            if identity not in present:
                del last_seen[identity]
        for _, zone in group.iterrows():
            last_seen[int(cast(int, zone["zone"]))] = (zone, _where(zone, ends))
    return pd.DataFrame(rows, columns=["step", "event", "zone", "condition", "where", "x_left",
                                       "x_right"])


def _where(zone: pd.Series, ends: tuple[int, int]) -> str:
    first, last = (int(cast(int, zone[key])) for key in ("first", "last"))
    left, right = first <= ends[0], last >= ends[1]
    return ("whole" if left and right else "left_edge" if left else "right_edge" if right
            else "interior")


def _event(step: int, event: str, zone: pd.Series, where: str) -> dict[str, object]:
    return {"step": step, "event": event, "zone": int(cast(int, zone["zone"])),
            "condition": zone["condition"], "where": where, "x_left": float(zone["x_left"]),
            "x_right": float(zone["x_right"])}


def zone_sweeps(zones: pd.DataFrame, *, min_size: float) -> pd.DataFrame:
    """How each zone grew over its life: where it started, which way it swept, how far.

    Parameters
    ----------
    zones
        From :func:`track_zones`.
    min_size
        Growth at one end smaller than this (mm) is no growth.

    Returns
    -------
    pandas.DataFrame
        One row per zone: ``zone``, ``condition``, ``first_step``, ``last_step``,
        ``x_left``, ``x_right`` (where it appeared), ``x_min``, ``x_max`` (the
        range it covered), ``sweep`` (``right_to_left``, ``left_to_right``,
        ``both_ways`` or ``none``) and ``swept`` (mm its ends travelled).

    Examples
    --------
    >>> codes = np.array([[1] * 8, [1] * 6 + [2] * 2, [1] * 2 + [2] * 6])
    >>> sweeps = zone_sweeps(track_zones(codes, np.arange(8.0), min_size=1.5), min_size=1.5)
    >>> sweeps[sweeps["condition"] == "slip_back"][["sweep", "swept"]].values.tolist()
    [['right_to_left', 4.0]]
    """
    rows = []
    for zone, life in zones.groupby("zone", sort=True):
        life = life.sort_values("step")
        first = life.iloc[0]
        leftward = float(first["x_left"] - life["x_left"].min())
        rightward = float(life["x_right"].max() - first["x_right"])
        grew_left, grew_right = leftward >= min_size, rightward >= min_size
        sweep = ("both_ways" if grew_left and grew_right else "right_to_left" if grew_left
                 else "left_to_right" if grew_right else "none")
        rows.append({"zone": int(cast(int, zone)), "condition": first["condition"],
                     "first_step": int(first["step"]), "last_step": int(life["step"].max()),
                     "x_left": float(first["x_left"]), "x_right": float(first["x_right"]),
                     "x_min": float(life["x_left"].min()), "x_max": float(life["x_right"].max()),
                     "sweep": sweep, "swept": round(leftward + rightward, 6)})
    return pd.DataFrame(rows, columns=["zone", "condition", "first_step", "last_step", "x_left",
                                       "x_right", "x_min", "x_max", "sweep", "swept"])
