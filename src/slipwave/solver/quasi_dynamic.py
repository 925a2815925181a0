"""A quasi-dynamic contact under rate-and-state friction: slips that travel at a speed.

The quasi-static solver (:func:`slipwave.solver.simulate`) finds where the contact
slips at each load increment; its slips have no duration and its waves no speed.
Here time is real: the flat travels at the drive's speed, every closed contact node
obeys the rate-and-state law (:mod:`slipwave.solver.rate_state`), and the slab's
inertia enters as radiation damping, the shear impedance G / (2 c_s) times each
node's slip rate (Rice 1993): the quasi-dynamic approximation of the cycle
simulators (QDYN; Lapusta et al. 2000 for what it leaves out). A front then
runs at the speed at which the law lets the interface fail, the slow fronts of
Rubinstein, Cohen and Fineberg (2004) and Bar-Sinai et al. (2012).

The normal problem is solved as the quasi-static one's: a node is closed
(on the flat, pressed) or open (off it, free of load); the closed nodes change
only where a normal force or a gap crosses zero, found by cutting the time step
there. Between changes the body is reduced onto its closed nodes, so that every
force the steps need is an affine map of their positions
(:mod:`slipwave.solver.quasi_dynamic_steps`).

Units are the slab's: mm, N per mm of width, MPa, s; the law's speeds and lengths
(m/s, m) are converted.

>>> from slipwave.solver.rate_state import RateState
>>> body = spring_slider_body(stiffness=100.0, normal_load=0.3)
>>> law = RateState(a=0.01, b=0.005, dc=1e-6, mu0=0.6)
>>> ds = simulate_quasi_dynamic(body, law, Drive(normal_load=0.3, drive_speed=0.01),
...                             duration=2.0, sample_rate=10.0)
>>> round(float(ds["T"][-1] / ds["N"][-1]), 4)  # steady sliding above the reference rate
0.6115
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Literal

import numpy as np
import xarray as xr
from scipy.optimize import brentq

from slipwave import __version__
from slipwave.defaults import CONVENTIONS
from slipwave.errors import SlipwaveError
from slipwave.solver import quasi_dynamic_steps as steps
from slipwave.solver import quasi_dynamic_stretch as stretch_steps
from slipwave.solver import stiff_steps
from slipwave.solver.cache import SolverCache
from slipwave.solver.rate_state import RateState, cutoff_log_ages, states
from slipwave.solver.slab import Slab, condense

MM_PER_M = 1000.0
"""The law's lengths and speeds are in m and m/s, the slab's in mm and mm/s."""

SLAB_DENSITY = 1200.0
"""The polyurethane's density, kg/m^3 (its shear-wave speed is then about 44 m/s)."""

INITIAL_AGE = 10.0
"""The contacts' age when the tangential drive starts, s: the state theta after the
normal loading, which on the bench takes seconds."""

TOLERANCE = 1e-5
"""The steps' tolerance: on s in units of the smallest Dc, on ln theta, and relative."""

FRONT_SPEED_RATIO = 10.0
"""A node slips (a front has reached it) while its slip rate is above this many times
the drive's speed."""

_MAX_CONTACT_CHANGES = 100  # changes of the closed set at one instant before giving up
_MAX_STEP = 0.1  # s: the longest step, so that a change of contact is looked for often
_CROSSINGS_BUFFER = 64  # crossings held per node before the compiled steps hand them over
_FIELD_BUFFER = 256  # field states the compiled steps hold before they hand them over

JACOBIAN_BAND_NODES = 8
"""The Jacobian the steps factorise keeps each node's coupling to this many neighbours on
either side: the stiffness that sets the steps is local, and a band of 8 gave the same
slips and front speeds as the whole Jacobian at 160 elements, its factorisation a sixth of
the dense one's time (a Newton matrix with entries left out costs iterations, never
accuracy)."""


@dataclass(frozen=True)
class ContactBody:
    """An elastic body reduced to its contact nodes, with its radiation damping.

    Attributes
    ----------
    stiffness
        (2n, 2n) on ``[ux, uy]``, N/mm per mm of width (forces the flat exerts).
    initial_gap
        g0 (n,), mm.
    damping
        Each node's radiation damping, N s/mm per mm of width (its force per unit slip
        rate): G / (2 c_s) times the length of contact it stands for.
    x
        The nodes' positions along the contact, mm.
    tributary
        The length of contact each node stands for, mm.
    sensors
        (k, 2n): displacements read off the contact's (the slab's edge sensors), or
        (0, 2n).
    width
        The out-of-plane width, mm: loads are reported for it.
    """

    stiffness: np.ndarray
    initial_gap: np.ndarray
    damping: np.ndarray
    x: np.ndarray
    tributary: np.ndarray
    sensors: np.ndarray
    width: float

    @property
    def nodes(self) -> int:
        """The number of contact nodes.

        Returns
        -------
        int
            n.
        """
        return int(self.initial_gap.size)


@dataclass(frozen=True)
class Drive:
    """How the flat is driven.

    Attributes
    ----------
    normal_load
        The normal load the flat is pressed with before the drive starts, N (full width).
    drive_speed
        The flat's tangential speed, mm/s.
    normal_control
        ``"displacement"`` holds the flat's normal position after the pressing (the
        bench), ``"force"`` the normal load.
    initial_age
        The contacts' state theta when the drive starts, s.
    """

    normal_load: float
    drive_speed: float
    normal_control: Literal["displacement", "force"] = "displacement"
    initial_age: float = INITIAL_AGE

    def __post_init__(self) -> None:
        if not (self.normal_load > 0 and self.drive_speed > 0 and self.initial_age > 0):
            raise SlipwaveError(f"a drive needs normal load, speed and initial age > 0, got "
                                f"{asdict(self)}")
        if self.normal_control not in ("displacement", "force"):
            raise SlipwaveError(f"normal control {self.normal_control!r}: displacement or "
                                "force")


def shear_impedance(slab: Slab, density: float = SLAB_DENSITY) -> float:
    """The slab's radiation damping per unit area, G / (2 c_s) = sqrt(G rho) / 2.

    Parameters
    ----------
    slab
        The slab (its Young's modulus and Poisson ratio, MPa).
    density
        Its density, kg/m^3.

    Returns
    -------
    float
        MPa s/mm: the shear stress that resists a slip rate of 1 mm/s.
    """
    if not density > 0:
        raise SlipwaveError(f"the slab's density must be > 0 kg/m^3, got {density}")
    shear_modulus = slab.youngs_modulus / (2.0 * (1.0 + slab.poisson_ratio))
    density_t_mm3 = density * 1e-12  # tonnes per mm^3: with MPa and mm, speeds in mm/s
    return math.sqrt(shear_modulus * density_t_mm3) / 2.0


def slab_body(slab: Slab, *, density: float = SLAB_DENSITY,
              cache: SolverCache | None = None) -> ContactBody:
    """The slab condensed onto its contact, with each node's radiation damping.

    Parameters
    ----------
    slab
        The slab.
    density
        Its density, kg/m^3.
    cache
        Keeps the condensed stiffness (:func:`slipwave.solver.slab.condense`).

    Returns
    -------
    ContactBody
        The slab's contact, with its edge sensors (DG, DD).
    """
    condensed = condense(slab, cache=cache)
    tributary = slab.tributary_length
    return ContactBody(condensed.stiffness, slab.initial_gap(),
                       shear_impedance(slab, density) * tributary, slab.x, tributary,
                       condensed.sensors, slab.width)


def spring_slider_body(*, stiffness: float, normal_load: float,
                       damping: float = 0.0) -> ContactBody:
    """One contact node held by a tangential spring: the spring-slider, reduced.

    A rigid block pressed on the flat with ``normal_load`` and tied to a fixed point by
    a spring: driving the flat is the spring-slider of
    :mod:`slipwave.solver.spring_slider` seen from the flat. A unit width, so that forces
    are the slider's.

    Parameters
    ----------
    stiffness
        The spring's stiffness, N/mm.
    normal_load
        The normal load, N (sets the normal stiffness so the block sinks by 1 um).
    damping
        The radiation damping, N s/mm (0: the massless slider).

    Returns
    -------
    ContactBody
        One node.
    """
    normal_stiffness = normal_load / 1e-3
    matrix = np.diag([stiffness, normal_stiffness])
    return ContactBody(matrix, np.zeros(1), np.array([damping]), np.zeros(1), np.ones(1),
                       np.zeros((0, 2)), 1.0)


@dataclass(frozen=True)
class _Contact:
    """The body reduced onto a set of closed nodes, and how to recover the open ones."""

    reduction: steps.Reduction
    open: np.ndarray
    response: np.ndarray  # the open nodes' [ux, uy] from the closed nodes' [ux, uy]


def _affine(rows: np.ndarray, closed_gap: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A map on the closed nodes' ``[ux, uy]`` as one on (s, dx, dy).

    Their ``ux = dx + s`` and ``uy = dy - g0``.
    """
    c = closed_gap.size
    tangential, normal = rows[:, :c], rows[:, c:]
    return (np.ascontiguousarray(tangential), tangential.sum(axis=1), normal.sum(axis=1),
            -normal @ closed_gap)


def _condense_onto(K: np.ndarray, kept: np.ndarray, free: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The free unknowns in terms of the kept ones (no load on them), and the Schur complement.

    Returns ``response`` (``u_free = response @ u_kept``) and the kept unknowns'
    stiffness with the free ones eliminated.
    """
    if not free.size:
        return np.zeros((0, kept.size)), K[np.ix_(kept, kept)].copy()
    response = -np.linalg.solve(K[np.ix_(free, free)], K[np.ix_(free, kept)])
    return response, K[np.ix_(kept, kept)] + K[np.ix_(kept, free)] @ response


def _reduce(body: ContactBody, closed: np.ndarray, flat: np.ndarray) -> _Contact:
    """The body reduced onto a set of closed nodes (the open ones carry no load)."""
    n = body.nodes
    is_closed = np.zeros(n, dtype=bool)
    is_closed[closed] = True
    open_ = np.flatnonzero(~is_closed)
    kept = np.concatenate([closed, n + closed])
    free = np.concatenate([open_, n + open_])
    response, schur = _condense_onto(body.stiffness, kept, free)
    c, o = closed.size, open_.size
    g0 = body.initial_gap
    gaps_M, gaps_x, gaps_y, gaps_0 = _affine(response[o:], g0[closed])
    sensors = body.sensors[:, kept] + body.sensors[:, free] @ response
    readout_rows = np.vstack([schur[:c].sum(axis=0), schur[c:].sum(axis=0), sensors])
    reduction = steps.Reduction(n, closed.astype(np.int64), *_affine(schur, g0[closed]),
                                gaps_M, gaps_x, gaps_y - 1.0, gaps_0 + g0[open_],
                                *_affine(readout_rows, g0[closed]), flat, body.damping)
    return _Contact(reduction, open_, response)


def _approach(body: ContactBody, normal_load: float) -> tuple[np.ndarray, float, np.ndarray]:
    """The flat pressed without friction: displacements, normal position, closed nodes.

    An active set on the normal problem: every node closed, then those pulled off opened
    and those pressed in closed, until neither is left.
    """
    n = body.nodes
    K, g0 = body.stiffness, body.initial_gap
    closed = np.arange(n)
    for _ in range(n + _MAX_CONTACT_CHANGES):
        kept = n + closed
        free = np.setdiff1d(np.arange(2 * n), kept)
        response, schur = _condense_onto(K, kept, free)
        dy = (normal_load + schur.sum(axis=0) @ g0[closed]) / schur.sum()
        u = np.zeros(2 * n)
        u[kept] = dy - g0[closed]
        u[free] = response @ u[kept]
        pressed = schur @ u[kept]
        gap = g0 + u[n:] - dy
        pulled = closed[pressed < 0.0]
        pressed_in = np.setdiff1d(np.flatnonzero(gap < -1e-12), closed)
        if not pulled.size and not pressed_in.size:
            return u, float(dy), closed
        closed = np.union1d(np.setdiff1d(closed, pulled), pressed_in)
        if not closed.size:
            break
    raise SlipwaveError("the normal loading found no contact that carries the load")


def _state_at(body: ContactBody, contact: _Contact, times: np.ndarray, ys: np.ndarray,
              stride: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every node's displacements, the flat's forces ``[r_x, r_y]``, gaps; and dx.

    At each of ``times`` (k,), from the states ``ys`` (k, size), a row each; ``stride``:
    entries per node in the state.
    """
    n = body.nodes
    reduction = contact.reduction
    closed, open_ = reduction.closed, contact.open
    s = np.ascontiguousarray(ys[:, ::stride][:, closed])
    dx, dy = np.array([steps.flat_position(t, row, reduction) for t, row in zip(times, s,
                                                                                  strict=True)]).T
    u = np.zeros((times.size, 2 * n))
    u[:, closed] = dx[:, None] + s
    u[:, n + closed] = dy[:, None] - body.initial_gap[closed]
    kept = np.concatenate([closed, n + closed])
    free = np.concatenate([open_, n + open_])
    u[:, free] = u[:, kept] @ contact.response.T
    r = u @ body.stiffness.T
    r[:, free] = 0.0
    gap = body.initial_gap + u[:, n:] - dy[:, None]
    return u, r, gap, dx


def _flat_row(drive: Drive, dy: float, width: float) -> np.ndarray:
    """The steps' ``flat``: from dx 0 at t 0 at the drive's speed, dy, N per width, control."""
    return np.array([0.0, 0.0, drive.drive_speed, dy, drive.normal_load / width,
                     1.0 if drive.normal_control == "force" else 0.0])


def _law(law: RateState) -> steps.Law:
    """The law in the steps' units (mm, mm/s) and form."""
    pairs = states(law)
    ages = cutoff_log_ages(law)
    return steps.Law(law.a, law.v0 * MM_PER_M, law.mu0, law.evolution == "aging",
                     np.array([b for b, _ in pairs]),
                     np.array([math.log(law.v0 / dc) for _, dc in pairs]),
                     np.array([dc * MM_PER_M for _, dc in pairs]),
                     np.full(len(pairs), -np.inf) if ages is None else np.array(ages))


class _Stretch:
    """The right-hand side, Jacobian and readings while the closed nodes stay the same."""

    def __init__(self, contact: _Contact, law: steps.Law,
                 margin_scales: tuple[float, float]) -> None:
        self.contact, self.law, self.margin_scales = contact, law, margin_scales
        self.reduction = contact.reduction
        size = contact.reduction.nodes * (1 + law.b.size)
        self.band = min(JACOBIAN_BAND_NODES * (1 + law.b.size) + law.b.size, size - 1)

    def rates(self, t: float, y: np.ndarray) -> np.ndarray:
        """dy/dt."""
        return steps.rates(t, y, self.reduction, self.law)

    def jacobian(self, t: float, y: np.ndarray) -> np.ndarray:
        """d(dy/dt)/dy within the band, packed (:mod:`slipwave.solver.stiff_steps`)."""
        return steps.jacobian(t, y, self.reduction, self.law, self.band)

    def step_end(self, t: float, y: np.ndarray) -> tuple[float, np.ndarray]:
        """The contact's margin in its floors' units (below -1 it must change); slip rates."""
        margin, speeds = steps.step_end(t, y, self.reduction, self.law, *self.margin_scales)
        return float(margin), speeds

    def change_time(self, within: Callable[[float], np.ndarray], begin: float,
                    end: float) -> float:
        """When the contact's margin crosses its floor in a step (interpolant ``within``)."""
        return float(brentq(lambda t: self.step_end(t, within(t))[0] + 1.0, begin, end,
                            xtol=1e-12))


def simulate_quasi_dynamic(
    body: ContactBody,
    law: RateState,
    drive: Drive,
    *,
    duration: float,
    sample_rate: float,
    field_times: np.ndarray | None = None,
    front_speed: float | None = None,
    tolerance: float = TOLERANCE,
) -> xr.Dataset:
    """Press the flat on the body, then drive it: the contact's response in real time.

    The time steps are scipy's BDF compiled (:mod:`slipwave.solver.stiff_steps`) with the
    analytic Jacobian, one integration per stretch of unchanged contact: a step that
    ends with a closed node pulled off or an open node pressed in beyond the floors
    (``tolerance`` times the mean nodal force, and times the smallest Dc) is cut where
    the change happened (a root of its interpolant), the contact changed there, and the
    integration started again.

    Parameters
    ----------
    body
        The body's contact (:func:`slab_body`, :func:`spring_slider_body`).
    law
        The interface's friction law, the same at every node.
    drive
        The normal load, the drive's speed and what is held.
    duration
        The driven time, s (the record starts when the drive does).
    sample_rate
        Records of the loads and sensors per second.
    field_times
        When to record the nodes' fields, s from the drive's start (increasing, within
        the duration; :func:`record_times` for a rate); the samples' times by default.
    front_speed
        The slip rate, mm/s, above which a node counts as slipping (a front's passage is
        the time it crosses it); :data:`FRONT_SPEED_RATIO` times the drive's by default.
    tolerance
        The steps' tolerance (:data:`TOLERANCE`).

    Returns
    -------
    xarray.Dataset
        Over ``time``: ``T``, ``N`` (N), ``DT`` (the flat's travel), ``approach`` (its
        normal position) and, for a slab, ``DG``, ``DD`` (mm). Over ``field_time`` and
        ``x``: ``slip_rate`` (mm/s), ``log_state`` (ln theta, theta in s), ``p``, ``q``
        (MPa), ``contact`` (1 closed) and the displacements ``ux``, ``uy`` (mm, as the
        quasi-static solver's, from which the slab's stresses follow). Over
        ``crossing``: each node's slip rate passing ``front_speed``, its ``crossing_x``,
        ``crossing_time`` and ``crossing_rising`` (1 a front arriving, 0 the node
        sticking again). Steps, evaluations and contact changes as attributes.

    Raises
    ------
    SlipwaveError
        For numbers out of range, or when the integration fails (the message says when).
    """
    if not (duration > 0 and sample_rate > 0 and tolerance > 0):
        raise SlipwaveError(f"duration, sample rate and tolerance must be > 0, got "
                            f"{duration}, {sample_rate}, {tolerance}")
    sample_times = record_times(duration, sample_rate)
    field_times = sample_times if field_times is None else np.asarray(field_times, dtype=float)
    front_speed = FRONT_SPEED_RATIO * drive.drive_speed if front_speed is None else front_speed
    if not front_speed > 0:
        raise SlipwaveError(f"the front speed must be > 0, got {front_speed}")
    if field_times.ndim != 1 or not (np.all(np.diff(field_times) > 0) and (
            field_times.size == 0 or (field_times[0] >= 0 and field_times[-1] <= duration))):
        raise SlipwaveError(f"the field times must increase within 0 to {duration} s")
    n = body.nodes
    state_count = len(states(law))
    smallest_dc = min(dc for _, dc in states(law)) * MM_PER_M
    normal_w = drive.normal_load / body.width
    u, dy, closed = _approach(body, normal_w)
    stride = 1 + state_count
    y = np.full(n * stride, math.log(drive.initial_age))
    y[::stride] = u[:n]
    flat = _flat_row(drive, dy, body.width)
    contact = _reduce(body, closed, flat)
    record = _Record(sample_times, field_times, n, contact.reduction.readouts_x.size + 2,
                     n * stride)
    scales = (tolerance * normal_w / n, tolerance * smallest_dc)
    atol = np.full(n * stride, tolerance)
    atol[::stride] = tolerance * smallest_dc
    steps_law = _law(law)
    t, counts = 0.0, {"steps": 0, "evaluations": 0, "jacobians": 0, "factorisations": 0,
                      "contact_changes": 0}
    while t < duration:
        stretch = _Stretch(contact, steps_law, scales)
        stepper = stiff_steps.start(t, y, duration, tolerance, atol, _MAX_STEP,
                                    stretch.reduction, steps_law, stretch.band)
        taken = record.start(stretch.step_end(t, y)[1])
        changed = False
        while t < duration:
            status = stretch_steps.advance(stepper, stretch.reduction, steps_law,
                                           stretch.band, *scales, math.inf, front_speed,
                                           taken)
            if status == stretch_steps.TOO_SMALL:
                raise SlipwaveError(f"the quasi-dynamic steps fell below the smallest at "
                                    f"t = {stepper.scalars[stiff_steps.T]:.9g} s")
            within = _Interpolant(stepper)
            if status == stretch_steps.CHANGES:
                # the contact changes in this step: where its margin crosses the floor
                begin = float(stepper.scalars[stiff_steps.T_OLD])
                t = stretch.change_time(within, begin, float(stepper.scalars[stiff_steps.T]))
                y = within(t)
                stretch_steps.record_step(stepper, stretch.reduction, steps_law, begin, t,
                                          stretch.step_end(t, y)[1], front_speed, taken)
                changed = True
            else:
                t = float(stepper.scalars[stiff_steps.T])
                y = stepper.D[0].copy()
            record.take_fields(stretch, body, within, t)
            record.drain()
            if changed:
                break
        for name, index in (("steps", stiff_steps.STEPS),
                            ("evaluations", stiff_steps.EVALUATIONS),
                            ("jacobians", stiff_steps.JACOBIANS),
                            ("factorisations", stiff_steps.FACTORISATIONS)):
            counts[name] += int(stepper.counts[index])
        if changed:
            contact = _change_contact(body, contact, y, t, stride)
            counts["contact_changes"] += 1
    return _to_dataset(body, law, drive, record, counts, front_speed)


def contact_displacements(run: xr.Dataset) -> np.ndarray:
    """Each field record's contact displacements ``[ux, uy]``, as the slab's images take them.

    Parameters
    ----------
    run
        From :func:`simulate_quasi_dynamic`.

    Returns
    -------
    numpy.ndarray
        (field records, 2 nodes), mm (:meth:`slipwave.photoelastic.Photoelastic.stress`'s
        ``u`` row by row).
    """
    return np.concatenate([run["ux"].values, run["uy"].values], axis=1)


def record_times(duration: float, rate: float) -> np.ndarray:
    """Times from 0 to the duration at a rate, both ends included where they fall on it.

    Parameters
    ----------
    duration
        s.
    rate
        Records per second.

    Returns
    -------
    numpy.ndarray
        The times, s.

    Examples
    --------
    >>> record_times(1.0, 4.0)
    array([0.  , 0.25, 0.5 , 0.75, 1.  ])

    An end a rounding short of a record is that record, at the duration itself (a
    fit's run of 320.15999999999974 s filmed at 25 frames/s ends at it, not at 320.16):

    >>> float(record_times(320.15999999999974, 25.0)[-1])
    320.15999999999974
    """
    if not (duration > 0 and rate > 0):
        raise SlipwaveError(f"duration and rate must be > 0, got {duration}, {rate}")
    return np.minimum(np.arange(int(np.floor(duration * rate + 1e-9)) + 1) / rate, duration)


class _Interpolant:
    """The last step's interpolant: a state at a time, or a column per time."""

    def __init__(self, stepper: stiff_steps.Stepper) -> None:
        self.stepper = stepper

    def __call__(self, times: float | np.ndarray) -> np.ndarray:
        """The state at a time (size,), or at each of an array of times (size, times)."""
        values = stiff_steps.interpolate(self.stepper, np.atleast_1d(np.asarray(
            times, dtype=float)))
        return values[:, 0] if np.ndim(times) == 0 else values


class _Record:
    """What a run records: the readouts and crossings (by the compiled steps), the fields."""

    def __init__(self, sample_times: np.ndarray, field_times: np.ndarray, nodes: int,
                 readouts: int, size: int) -> None:
        self.sample_times, self.field_times = sample_times, field_times
        self.fields = np.zeros((7, field_times.size, nodes))
        buffer = _CROSSINGS_BUFFER * nodes
        self.steps_record = stretch_steps.Record(
            sample_times, np.full((readouts, sample_times.size), np.nan),
            np.zeros(buffer, dtype=np.int64), np.zeros(buffer),
            np.zeros(buffer, dtype=np.bool_), field_times, np.zeros((_FIELD_BUFFER, size)),
            np.zeros(4, dtype=np.int64), np.zeros(0))
        self.crossings: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []

    @property
    def samples(self) -> np.ndarray:
        """(readouts + 2, sample_times): the readouts, dx and dy."""
        return self.steps_record.samples

    def start(self, speeds: np.ndarray) -> stretch_steps.Record:
        """The record the compiled steps fill over a stretch whose slip rates start at these."""
        self.steps_record = self.steps_record._replace(speeds=speeds)
        return self.steps_record

    def take_fields(self, stretch: _Stretch, body: ContactBody, within: _Interpolant,
                    end: float) -> None:
        """Record the fields at the field times up to ``end`` (within the last step).

        Those whose states the compiled steps hold, then any the buffer had no room for.
        """
        cursor = self.steps_record.cursor
        held, taken = int(cursor[stretch_steps.FIELDS_HELD]), int(
            cursor[stretch_steps.NEXT_FIELD])
        if held:
            self.fields[:, taken - held:taken] = _fields(
                stretch, body, self.field_times[taken - held:taken],
                self.steps_record.field_states[:held])
            cursor[stretch_steps.FIELDS_HELD] = 0
        stop = int(np.searchsorted(self.field_times, end, side="right"))
        if stop > taken:
            times = self.field_times[taken:stop]
            self.fields[:, taken:stop] = _fields(stretch, body, times, within(times).T)
            cursor[stretch_steps.NEXT_FIELD] = stop

    def drain(self) -> None:
        """Move the crossings out of the compiled steps' buffer."""
        held = self.steps_record
        count = int(held.cursor[stretch_steps.CROSSINGS])
        if count:
            self.crossings.append((held.crossing_node[:count].copy(),
                                   held.crossing_time[:count].copy(),
                                   held.crossing_rising[:count].copy()))
            held.cursor[stretch_steps.CROSSINGS] = 0

    def crossing_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every crossing's node, time and whether the rate rises, in time order."""
        if not self.crossings:
            return np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0, dtype=bool)
        return (np.concatenate([node for node, _, _ in self.crossings]),
                np.concatenate([time for _, time, _ in self.crossings]),
                np.concatenate([rising for _, _, rising in self.crossings]))


def _change_contact(body: ContactBody, contact: _Contact, y: np.ndarray, t: float,
                    stride: int) -> _Contact:
    """Open the closed nodes pulled off, close the open ones pressed in, until none is.

    A node that closes takes its position on the flat where it lands.
    """
    n = body.nodes
    for _ in range(_MAX_CONTACT_CHANGES):
        at_t = _state_at(body, contact, np.array([t]), y[None], stride)
        u, r, gap, dx = (part[0] for part in at_t)
        closed = contact.reduction.closed
        pulled = closed[r[n + closed] < 0.0]
        pressed_in = contact.open[gap[contact.open] < 0.0]
        if not pulled.size and not pressed_in.size:
            return contact
        y[pressed_in * stride] = u[pressed_in] - dx
        closed = np.union1d(np.setdiff1d(closed, pulled), pressed_in)
        if not closed.size:
            raise SlipwaveError(f"the contact opened whole at t = {t:.9g} s")
        contact = _reduce(body, closed, contact.reduction.flat)
    raise SlipwaveError(f"the contact's closed nodes kept changing at t = {t:.9g} s")


def _fields(stretch: _Stretch, body: ContactBody, times: np.ndarray, ys: np.ndarray
            ) -> np.ndarray:
    """(7, times, nodes): the slip rate, ln theta (the first state's), p, q, contact, ux, uy.

    At each of ``times``, from the states ``ys`` (times, size).
    """
    n = body.nodes
    stride = 1 + stretch.law.b.size
    closed = stretch.reduction.closed
    u, r, _, _ = _state_at(body, stretch.contact, times, ys, stride)
    speed = np.zeros((times.size, n))
    speed[:, closed] = steps.slip_rates(times, ys, stretch.reduction, stretch.law)
    contact = np.zeros((times.size, n))
    contact[:, closed] = 1.0
    return np.stack([speed, ys[:, 1::stride], r[:, n:] / body.tributary,
                     r[:, :n] / body.tributary, contact, u[:, :n], u[:, n:]])


def _to_dataset(body: ContactBody, law: RateState, drive: Drive, record: _Record,
                counts: dict[str, int], front_speed: float) -> xr.Dataset:
    """The record as a dataset with CF attributes."""
    width = body.width
    samples, fields = record.samples, record.fields
    crossing_node, crossing_time, crossing_rising = record.crossing_arrays()
    names = ["T", "N"] + (["DG", "DD"] if body.sensors.shape[0] == 2 else
                          [f"sensor_{k}" for k in range(body.sensors.shape[0])])
    data: dict[str, tuple] = {}
    for k, name in enumerate(names):
        scale = width if name in ("T", "N") else 1.0
        unit = "N" if name in ("T", "N") else "mm"
        data[name] = ("time", scale * samples[k], {"units": unit})
    data["DT"] = ("time", samples[len(names)], {"units": "mm",
                                                "long_name": "flat tangential travel"})
    data["approach"] = ("time", samples[len(names) + 1], {
        "units": "mm", "long_name": "flat normal position"})
    field_names = (("slip_rate", "mm s-1", "slip rate of the slab on the flat"),
                   ("log_state", "1", "natural logarithm of the state theta in s"),
                   ("p", "MPa", "contact pressure"), ("q", "MPa", "shear stress"),
                   ("contact", "1", "1 where the node is on the flat"),
                   ("ux", "mm", "tangential displacement of the slab's contact node"),
                   ("uy", "mm", "normal displacement of the slab's contact node"))
    for (name, unit, long_name), values in zip(field_names, fields, strict=True):
        data[name] = (("field_time", "x"), values, {"units": unit, "long_name": long_name})
    data["crossing_x"] = ("crossing", body.x[crossing_node], {"units": "mm"})
    data["crossing_time"] = ("crossing", crossing_time, {"units": "s"})
    data["crossing_rising"] = ("crossing", crossing_rising.astype(np.int8), {
        "long_name": "1 where the slip rate rises through the front speed"})
    ds = xr.Dataset(
        data,
        coords={"time": ("time", record.sample_times, {"units": "s"}),
                "field_time": ("field_time", record.field_times, {"units": "s"}),
                "x": ("x", body.x, {"units": "mm"})})
    ds.attrs.update({
        "Conventions": CONVENTIONS,
        "title": "quasi-dynamic contact under rate-and-state friction",
        "source": f"slipwave {__version__}",
        "law": repr(law),
        "normal_load": drive.normal_load, "drive_speed": drive.drive_speed,
        "normal_control": drive.normal_control, "initial_age": drive.initial_age,
        "front_speed": front_speed,
        **counts,
    })
    return ds
