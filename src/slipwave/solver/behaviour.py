"""The behaviour of the interface: the succession of events a simulation went through.

The paper (Zeghloul, Dubourg & Villechaise, 1994) sorts its 1572 cases by "the
succession of events (sliding, sticking and opening)" at the interface, and names
two of its behaviours:

- **ZD**: a slip zone sweeping the interface from the right edge to the left;
- **ZG**: a slip zone starting mid-interface and sweeping it to the right;

and marks **L** the cases whose first opening appears at the right edge.

:func:`describe_behaviour` reads the succession from the zone history
(:mod:`slipwave.solver.zones`) of the tangential loading, up to gross sliding:

- openings (an open zone appearing where the contact was closed after the normal
  loading: at the right edge, the left edge or inside);
- slip zones driven by the tangential load, i.e. the slab slipping towards -x
  relative to the flat, which drags it to +x. Each has an origin (``right edge``,
  ``left edge``, ``inside``, or ``left edge, continuing the normal loading's slip``
  when it is the edge zone the normal loading left, going on in the same
  direction), a sweep (which way it grew: ``right-to-left``, ``left-to-right``,
  ``both ways`` when neither side grew twice as far as the other, or ``in place``)
  and how far (mm) until it merged, re-stuck or the contact slid;
- merges of slip zones and re-sticking (a slip zone vanishing before gross
  sliding);
- the end: ``gross sliding`` or ``jammed`` (see :func:`~slipwave.solver.simulate`).

The outward slip at the right edge as the tangential load unloads it (the slab
slipping towards +x there, the way the normal loading made it slip) is not driven
by T: it is listed among the events (``unloading slip``) but does not enter the
succession. Zones shorter than ``min_size`` (mm) decide nothing.

Two cases have the same behaviour when their successions are equal; the succession
carries no number (positions, loads and sweep lengths are in :attr:`Behaviour.events`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from slipwave.defaults import MIN_ZONE_MM
from slipwave.solver.zones import CONDITIONS, follow_zones, node_conditions

BEHAVIOUR_VARIABLES = ("phase", "wave", "T", "N", "state", "slip_direction")
"""The variables of a simulation that :func:`describe_behaviour` reads (``simulate``'s
``variables``)."""

MIN_SWEEP_FRACTION = 0.05
"""A slip zone enters the succession once it has covered this fraction of the contact."""

_DOMINANT = 2.0  # a sweep has a direction when one side grew this many times the other

ZD = "ZD"
ZG = "ZG"
PAPER_SWEEP_FRACTION = 0.25
"""The least part of the contact a ZD or ZG slip zone sweeps before gross sliding."""


@dataclass(frozen=True)
class Behaviour:
    """What happened at the interface, as a succession of events.

    Attributes
    ----------
    sequence
        The succession, one phrase per event, e.g. ``("opening right", "slip zone from
        right edge sweeps right-to-left", "gross sliding")``; no numbers in it.
    events
        Every event, with its step, T (N), T/N, where (mm) and, for slip zones,
        the sweep in mm; the unloading slip at an edge is here too.
    first_opening
        Where the first opening appeared (``"right"``, ``"left"``, ``"inside"``) or
        ``None``.
    first_opening_x
        Its position (mm, the zone's centre when it appeared), NaN if none.
    first_slip
        Origin of the first slip zone driven by T, or ``None``.
    first_slip_x
        Its position (mm), NaN if none.
    main_slip
        Origin and sweep of the slip zone that led to gross sliding (the largest
        slip zone at the last step before it), or ``None``.
    main_swept
        How far that zone swept before it merged or the contact slid, as a
        fraction of the contact length (0 if none).
    end
        ``"gross sliding"``, ``"jammed"`` or ``"not reached"``.
    ratio_at_gross
        T/N at the first gross sliding, ``None`` if it was not reached.

    """

    sequence: tuple[str, ...]
    events: tuple[dict[str, Any], ...] = field(repr=False)
    first_opening: str | None
    first_opening_x: float
    first_slip: str | None
    first_slip_x: float
    main_slip: tuple[str, str] | None
    main_swept: float
    end: str
    ratio_at_gross: float | None

    @property
    def text(self) -> str:
        """The succession as one line.

        Returns
        -------
        str
            The phrases joined by arrows.

        """
        return " -> ".join(self.sequence)

    @property
    def paper_name(self) -> str | None:
        """``"ZD"`` or ``"ZG"`` when the behaviour is one the paper names.

        ZD: the slip zone that leads to gross sliding came from the right edge and
        swept right to left; ZG: it started inside and swept to the right; either way
        over at least :data:`PAPER_SWEEP_FRACTION` of the contact ("sweeping
        through the interface", the paper says).

        Returns
        -------
        str or None
            The paper's name, or ``None``.

        """
        if self.main_swept < PAPER_SWEEP_FRACTION:
            return None
        if self.main_slip == ("right edge", "right-to-left"):
            return ZD
        if self.main_slip == ("inside", "left-to-right"):
            return ZG
        return None

    @property
    def opens_right_first(self) -> bool:
        """The paper's mark L: the first opening appears at the right edge.

        Returns
        -------
        bool
            Whether the first opening is at the right edge.

        """
        return self.first_opening == "right"

    def to_dict(self) -> dict[str, Any]:
        """Everything, in plain types (for JSON or a netCDF attribute).

        Returns
        -------
        dict
            Fields of the behaviour, plus ``text``, ``paper_name`` and ``L``.

        """
        return {
            "sequence": list(self.sequence), "text": self.text, "paper_name": self.paper_name,
            "L": self.opens_right_first, "first_opening": self.first_opening,
            "first_opening_x": _plain(self.first_opening_x), "first_slip": self.first_slip,
            "first_slip_x": _plain(self.first_slip_x),
            "main_slip": None if self.main_slip is None else list(self.main_slip),
            "main_swept": round(self.main_swept, 6),
            "end": self.end, "ratio_at_gross": self.ratio_at_gross,
            "events": [{k: _plain(v) for k, v in event.items()} for event in self.events],
        }

    def to_json(self) -> str:
        """:meth:`to_dict` as JSON.

        Returns
        -------
        str
            The JSON text.

        """
        return json.dumps(self.to_dict())


def _plain(value: Any) -> Any:
    if isinstance(value, float | np.floating):
        return None if not np.isfinite(value) else round(float(value), 6)
    if isinstance(value, np.integer):
        return int(value)
    return value


def describe_behaviour(ds: xr.Dataset, *, min_size: float = MIN_ZONE_MM,
                       min_sweep: float | None = None) -> Behaviour:
    """The succession of events of a :func:`~slipwave.solver.simulate` result.

    Parameters
    ----------
    ds
        From :func:`~slipwave.solver.simulate`.
    min_size
        Shortest zone that counts, mm.
    min_sweep
        Largest extent (mm) a slip zone must reach to enter the succession; by
        default :data:`MIN_SWEEP_FRACTION` of the contact length.

    Returns
    -------
    Behaviour
        The succession, its events and the paper's names.

    Examples
    --------
    Frictionless normal loading, H/L 0.5, f = 1 under a constant normal load: the
    contact opens at the right edge, the slip zone beside it sweeps the contact from
    right to left (the paper's ZD):

    >>> from slipwave.solver import Slab, Coulomb, LoadPath, simulate
    >>> ds = simulate(Slab(elements=80), Coulomb(fs=1.0),
    ...               LoadPath(normal_control="force", normal_friction=False))
    >>> behaviour = describe_behaviour(ds)
    >>> behaviour.text
    'opening right -> slip zone from right edge sweeps right-to-left -> gross sliding'
    >>> behaviour.paper_name, behaviour.opens_right_first
    ('ZD', True)

    """
    # the arrays read from the variables: ds[name] would make a DataArray of each
    values = {name: ds.variables[name].values for name in ("x", *BEHAVIOUR_VARIABLES)}
    x, phase, wave = values["x"], values["phase"], values["wave"]
    T, N = values["T"], values["N"]
    normal_end = int(np.flatnonzero(phase == "normal")[-1])
    tangential = np.flatnonzero(phase == "tangential")
    gross = tangential[wave[tangential] == "gross"]
    if gross.size:
        end, last = "gross sliding", int(gross[0])
    else:
        end = ("jammed" if str(ds.attrs.get("gross_sliding", "")).startswith("jammed")
               else "not reached")
        last = int(tangential[-1]) + 1 if tangential.size else normal_end + 1
    # The zone history from the end of the normal loading to the step before gross
    # sliding (at gross sliding every contact node slips: one zone, nothing to read).
    window = np.arange(normal_end, last)
    codes = node_conditions(values["state"][window], values["slip_direction"][window])
    if not _approach_had_friction(ds):
        # A frictionless approach leaves every node sliding freely: the tangential
        # loading starts from a clean interface, friction engaging everywhere.
        codes[0] = np.where(codes[0] == _OPEN, _OPEN, _STICK)
    spacing = float(x[1] - x[0])
    # A zone dates from when half the decisive size of it was there (a node or two):
    # the same physical size on any mesh.
    least = max(1, int(np.ceil(0.5 * min_size / spacing - 1e-9)))
    seen: set[int] = set()
    zones = []
    for step, zone, code, first, last_node, absorbed in follow_zones(codes, spacing, min_size):
        # A zone dates from when its condition appeared where it is (only its first row
        # needs it); the zones of the end of the normal loading date from there.
        onset = step if zone in seen or step == 0 else _onset(codes, step, code, first,
                                                              last_node, least)
        seen.add(zone)
        zones.append(_Zone(int(window[step]), zone, code, float(x[first]), float(x[last_node]),
                           last_node - first, absorbed, int(window[onset])))
    if min_sweep is None:
        min_sweep = MIN_SWEEP_FRACTION * float(x[-1] - x[0])
    events = _events(zones, normal_end, T, N, min_size, min_sweep, 0.5 * float(x[0] + x[-1]))
    if end != "not reached":
        k = last if gross.size else int(tangential[-1])
        events.append({"step": k, "event": end, "T": float(T[k]), "ratio": float(T[k] / N[k])})
    sequence = tuple(e["phrase"] for e in events if e.get("phrase")) + (
        (end,) if end != "not reached" else ())
    openings = [e for e in events if e["event"] == "opening"]
    slips = [e for e in events if e["event"] == "slip"]
    main = _main_slip(zones, slips)
    for event in events:
        event.pop("phrase", None)
        event.pop("zone", None)
    return Behaviour(
        sequence=sequence, events=tuple(events),
        first_opening=openings[0]["where"] if openings else None,
        first_opening_x=openings[0]["x"] if openings else float("nan"),
        first_slip=slips[0]["origin"] if slips else None,
        first_slip_x=slips[0]["x"] if slips else float("nan"),
        main_slip=None if main is None else (main["origin"], main["sweep"]),
        main_swept=0.0 if main is None else (main["swept_left"] + main["swept_right"])
        / float(x[-1] - x[0]),
        end=end, ratio_at_gross=float(T[last] / N[last]) if gross.size else None,
    )


@dataclass(frozen=True)
class _Zone:
    step: int
    zone: int
    code: int
    left: float  # mm
    right: float
    size: int  # nodes - 1
    absorbed: tuple[int, ...]
    onset: int  # step from which the zone's condition was there, however small

    @property
    def centre(self) -> float:
        return 0.5 * (self.left + self.right)


_OPEN, _STICK, _SLIP_BACK, _SLIP_FORWARD = (CONDITIONS.index(c) for c in
                                            ("open", "stick", "slip_back", "slip_forward"))


def _events(zones: list[_Zone], normal_end: int, T: np.ndarray, N: np.ndarray,
            min_size: float, min_sweep: float, middle: float) -> list[dict[str, Any]]:
    """Openings, slip zones (with their sweeps), merges and re-sticking, in step order."""
    by_step: dict[int, list[_Zone]] = {}
    life: dict[int, list[_Zone]] = {}
    merged_at: dict[int, int] = {}
    for zone in zones:
        by_step.setdefault(zone.step, []).append(zone)
        life.setdefault(zone.zone, []).append(zone)
        for absorbed in zone.absorbed:
            merged_at[absorbed] = zone.step
    ends = {step: _closed_ends(group) for step, group in by_step.items()}
    last_step = max(by_step)
    events: list[dict[str, Any]] = []

    def stamp(step: int) -> dict[str, Any]:
        return {"step": step, "T": float(T[step]), "ratio": float(T[step] / N[step])}

    for identity, rows in life.items():
        first = rows[0]
        at_start = first.step == normal_end
        if first.code == _OPEN and not at_start:
            where = _where(first, ends[normal_end])
            events.append({**stamp(first.onset), "event": "opening", "where": where,
                           "x": first.centre, "phrase": f"opening {where}",
                           "established": _established(rows, min_sweep)})
        elif first.code == _SLIP_FORWARD and not at_start:
            events.append({**stamp(first.onset), "event": "unloading slip",
                           "where": _where(first, ends[first.step]), "x": first.centre})
        elif first.code == _SLIP_BACK:
            if at_start:
                if len(rows) == 1:
                    continue  # the normal loading's edge slip stopped at once
                side = "left" if first.centre < middle else "right"
                origin = f"{side} edge, continuing the normal loading's slip"
            else:
                where = _where(first, ends[first.step])
                origin = where if where in ("inside", "whole") else f"{where} edge"
            ended = merged_at.get(identity)
            own = [r for r in rows if ended is None or r.step < ended] or rows[:1]
            sweep, leftward, rightward = _sweep(own, min_size)
            extent = max(r.right - r.left for r in rows)
            decides = extent >= min_sweep
            name = "slip zone inside" if origin == "inside" else f"slip zone from {origin}"
            events.append({**stamp(first.onset), "event": "slip", "zone": identity,
                           "origin": origin, "x": first.centre, "sweep": sweep,
                           "swept_left": leftward, "swept_right": rightward,
                           "extent": round(extent, 6),
                           "established": _established(rows, min_sweep),
                           "phrase": f"{name} sweeps {sweep}" if decides else None})
            if ended is not None:
                events.append({**stamp(ended), "event": "merge", "x": rows[-1].centre,
                               "phrase": "slip zones merge" if decides else None})
            elif rows[-1].step < last_step:
                events.append({**stamp(rows[-1].step + 1), "event": "re-stick",
                               "origin": origin, "x": rows[-1].centre,
                               "phrase": f"{name} sticks again" if decides else None})
    rank = {"opening": 0, "unloading slip": 1, "slip": 2, "merge": 3, "re-stick": 4}
    # Ordered by when each zone was established (reached the decisive extent): their
    # very first nodes, at a corner, come in an order the mesh decides.
    events.sort(key=lambda e: (e.get("established", e["step"]), rank[e["event"]],
                               e.get("x", 0.0)))
    for event in events:
        event.pop("established", None)
    unique: list[dict[str, Any]] = []  # a merge of several zones in one step is one event
    for event in events:
        if event["event"] == "merge" and unique and unique[-1]["event"] == "merge" \
                and unique[-1]["step"] == event["step"]:
            unique[-1]["phrase"] = unique[-1]["phrase"] or event["phrase"]
            continue
        unique.append(event)
    return unique


def _established(rows: list[_Zone], extent: float) -> int:
    """The step a zone first spanned ``extent`` (its last step if it never did)."""
    return next((r.step for r in rows if r.right - r.left >= extent), rows[-1].step)


def _onset(codes: np.ndarray, step: int, code: int, first: int, last: int, least: int) -> int:
    """The step from which a zone's condition held ``least`` nodes where the zone is.

    A zone counts once it is ``min_size`` long, but it started earlier, when its
    condition first appeared there: that start orders it among the events.
    """
    onset = step
    while onset > 1 and (codes[onset - 1, first : last + 1] == code).sum() >= least:
        onset -= 1
    return onset


def _approach_had_friction(ds: xr.Dataset) -> bool:
    value = ds.attrs.get("path_normal_friction", True)
    return str(value).lower() not in ("false", "0")


def _closed_ends(group: list[_Zone]) -> tuple[float, float]:
    closed = [z for z in group if z.code != _OPEN] or group
    return min(z.left for z in closed), max(z.right for z in closed)


def _where(zone: _Zone, ends: tuple[float, float]) -> str:
    """``right``, ``left``, ``whole`` or ``inside``: which ends of the contact it touches."""
    left, right = zone.left <= ends[0], zone.right >= ends[1]
    if left and right:
        return "whole"
    return "left" if left else "right" if right else "inside"


def _sweep(rows: list[_Zone], min_size: float) -> tuple[str, float, float]:
    """Which way a zone grew from where it appeared, and how far each way (mm)."""
    leftward = max(0.0, rows[0].left - min(r.left for r in rows))
    rightward = max(0.0, max(r.right for r in rows) - rows[0].right)
    if max(leftward, rightward) < min_size:
        sweep = "in place"
    elif leftward >= _DOMINANT * rightward:
        sweep = "right-to-left"
    elif rightward >= _DOMINANT * leftward:
        sweep = "left-to-right"
    else:
        sweep = "both ways"
    return sweep, round(leftward, 6), round(rightward, 6)


def _main_slip(zones: list[_Zone], slips: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The slip event of the zone that was largest at the last step before gross sliding."""
    last = max(z.step for z in zones)
    before = [z for z in zones if z.step == last and z.code == _SLIP_BACK]
    if not before or not slips:
        return None
    largest = max(before, key=lambda z: z.size).zone
    return next((e for e in slips if e["zone"] == largest), None)


__all__ = ["Behaviour", "describe_behaviour"]
