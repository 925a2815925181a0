"""The bench's load path, followed increment by increment."""

from __future__ import annotations

import functools
from collections.abc import Callable, Collection
from dataclasses import dataclass, field, fields
from typing import Any, Literal, NamedTuple

import numpy as np
import xarray as xr

from slipwave import __version__
from slipwave.defaults import (
    CONVENTIONS,
    NORMAL_CONTROL,
    NORMAL_FRICTION,
    NORMAL_LOAD_N,
    TANGENTIAL_STEP_N,
)
from slipwave.errors import SlipwaveError, SolverError
from slipwave.solver.cache import SolverCache
from slipwave.solver.contact import (
    OPEN,
    STICK,
    Body,
    Control,
    Increment,
    NotConverged,
    Weakening,
)
from slipwave.solver.slab import Condensed, Slab, condensation_memory, condense, geometry_key

RESIDUAL_TOLERANCE = 1e-8
"""Largest relative complementarity residual of a returned step."""

ASYMPTOTIC_LOAD_RATIO = 100.0
"""Under a held normal displacement, a contact whose zero-approach limit sticks is
jammed once T reaches this many times the normal load: the normal approach then
weighs less than 1 % in the state, which is that limit's."""

SIMULATION_VARIABLES = (
    "state", "slip_direction", "cascade_round", "p", "q", "gap", "slip", "ux", "uy",
    "ux_before_wave", "uy_before_wave", "T", "N", "DG", "DD", "DT", "approach", "actuator",
    "T_before_wave", "N_before_wave", "DG_before_wave", "DD_before_wave", "DT_before_wave",
    "phase", "wave", "static_friction", "residual", "iterations", "substeps")
"""The data variables of :func:`simulate`'s result, in its order."""

_MAX_SPLITS = 6  # sub-stepping depth: an increment is cut into at most 64 parts
_CAPACITY_MARGIN = 1e-9  # relative: T this far past fs N has no equilibrium (rounding aside)


@dataclass(frozen=True)
class Coulomb:
    """Coulomb friction with a static (stick limit) and a dynamic coefficient.

    ``fd`` defaults to ``fs``. An optional run-in makes the static coefficient
    go linearly from ``fs`` to ``fs_final`` over the first ``runin_slips`` gross
    slips (an interface whose adhesion builds up as it is worn in, or falls as a
    surface film is wiped off); the dynamic one stays. ``runin_slips`` need not be
    whole: after g gross slips the coefficient has gone min(g / runin_slips, 1) of the
    way, so a fit can move it continuously. With ``fs_peak`` the run-in passes through
    a turn: from ``fs`` to ``fs_peak`` over ``runin_slips`` gross slips, then to
    ``fs_final`` over as many more (a surface cleaned by the first slips, then
    smoothed by wear): no law the fit knows follows it (the virtual bench's
    misspecified recording).
    """

    fs: float
    fd: float | None = None
    fs_final: float | None = None
    runin_slips: float = 0
    fs_peak: float | None = None

    def __post_init__(self) -> None:
        if self.fd is None:
            object.__setattr__(self, "fd", self.fs)
        if not (0.0 <= self.dynamic <= self.fs and np.isfinite(self.fs)):
            raise SlipwaveError(f"friction needs 0 <= fd <= fs, got fs={self.fs}, fd={self.fd}")
        if self.fs_final is not None and not (self.fs_final >= self.dynamic
                                              and self.runin_slips > 0):
            raise SlipwaveError("a run-in needs fs_final >= fd and runin_slips > 0")
        if self.fs_peak is not None and not (self.fs_final is not None
                                             and self.fs_peak >= self.dynamic):
            raise SlipwaveError("a run-in's turn needs fs_final and fs_peak >= fd")

    def static_after(self, gross_slips: int) -> float:
        """The static coefficient after ``gross_slips`` gross slips.

        Parameters
        ----------
        gross_slips
            Gross slips so far.

        Returns
        -------
        float
            The static coefficient.

        """
        if self.fs_final is None:
            return self.fs
        progress = min(gross_slips / self.runin_slips, 1.0)
        if self.fs_peak is None:
            return self.fs + (self.fs_final - self.fs) * progress
        back = min(max(gross_slips / self.runin_slips - 1.0, 0.0), 1.0)
        return self.fs + (self.fs_peak - self.fs) * progress + (
            self.fs_final - self.fs_peak) * back

    @property
    def dynamic(self) -> float:
        """Fd as a float.

        Returns
        -------
        float
            fd, or fs when fd is not given.

        """
        return float(self.fs if self.fd is None else self.fd)


@dataclass(frozen=True)
class SlipWeakening(Coulomb):
    """Linear slip-weakening: a slipping node's coefficient falls from fs to fd over Dc.

    mu(delta) = fs - (fs - fd) min(delta / Dc, 1), delta the node's slip in the current
    wave; a stuck node holds up to fs (the interface heals between waves, as under
    Coulomb with fs > fd, which is the limit Dc -> 0). Run-in (``fs_final``) applies to
    fs as for :class:`Coulomb`.

    Attributes
    ----------
    dc
        The slip-weakening distance Dc, mm.

    """

    dc: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (self.dc > 0 and np.isfinite(self.dc)):
            raise SlipwaveError(f"slip-weakening needs a distance dc > 0 mm, not {self.dc}")
        if not self.fs > self.dynamic:
            raise SlipwaveError("slip-weakening needs fs > fd")

    def weakening(self, slip: np.ndarray) -> np.ndarray:
        """The coefficient of slipping nodes against their slip in the wave.

        Parameters
        ----------
        slip
            Each node's slip in the current wave, mm.

        Returns
        -------
        numpy.ndarray
            fs - (fs - fd) min(slip / dc, 1) (with the run-in's fs of the moment
            taken by the solver as the upper bound).

        Examples
        --------
        >>> SlipWeakening(fs=1.0, fd=0.6, dc=0.2).weakening(np.array([0.0, 0.1, 0.5])).tolist()
        [1.0, 0.8, 0.6]

        """
        progress = np.minimum(np.asarray(slip, dtype=float) / self.dc, 1.0)
        return self.fs - (self.fs - self.dynamic) * progress


@dataclass(frozen=True)
class LoadPath:
    """The bench's loading: normal approach, then the flat's tangential travel.

    Attributes
    ----------
    normal_load
        Normal load (N, compressive, full width) reached in step 1.
    tangential_step
        Increment of T (N) per tangential step until gross sliding.
    normal_steps
        Equal load steps of the normal approach.
    normal_control
        After step 1: ``"displacement"`` holds the flat's normal position (the
        bench), ``"force"`` holds N.
    max_travel
        If set, go on past gross sliding, in flat-travel increments, until the
        flat has travelled this far (mm): stick-slip cycles.
    travel_step
        Flat travel (mm) per increment past gross sliding; by default the travel
        that raises T by ``tangential_step`` while the whole contact sticks.
    machine_stiffness
        If set (N/mm, full width), the tangential phase is driven from the start
        by an actuator through a spring of this stiffness between it and the
        flat, in ``travel_step`` increments of the actuator up to ``max_travel``
        (both then required): T = k (X - DT), so a slip releases load and the
        flat's travel DT shows it, as on the bench.
    max_tangential_load
        If set, stop the load-controlled phase there (N) if the contact has not
        slid by then. By default there is no cap: a run ends at gross sliding, or
        (held normal displacement) when the contact is found jammed; the
        dataset's ``gross_sliding`` attribute says which.
    max_steps
        Safety bound on the number of steps.
    normal_friction
        Whether friction acts during the normal loading (the flat pressed with
        friction, the edges held: a locked-in shear); ``False``: the normal
        loading is frictionless and friction acts from the first tangential
        increment.

    """

    normal_load: float = NORMAL_LOAD_N
    tangential_step: float = TANGENTIAL_STEP_N
    normal_steps: int = 5
    normal_control: Literal["displacement", "force"] = NORMAL_CONTROL
    max_travel: float | None = None
    travel_step: float | None = None
    machine_stiffness: float | None = None
    max_tangential_load: float | None = None
    max_steps: int = 5000
    normal_friction: bool = NORMAL_FRICTION

    def __post_init__(self) -> None:
        if not (self.normal_load > 0 and self.tangential_step > 0 and self.normal_steps >= 1):
            raise SlipwaveError("normal_load, tangential_step and normal_steps must be positive")
        for name in ("max_travel", "travel_step", "max_tangential_load"):
            value = getattr(self, name)
            if value is not None and not value > 0:
                raise SlipwaveError(f"{name} must be positive, not {value:g}")
        if self.normal_control not in ("displacement", "force"):
            raise SlipwaveError(f"normal_control {self.normal_control!r}: displacement or force")
        if self.machine_stiffness is not None and not (
            self.machine_stiffness > 0 and self.max_travel and self.travel_step
        ):
            raise SlipwaveError("a machine drive needs machine_stiffness > 0, max_travel and "
                                "travel_step")


class _Step(NamedTuple):
    """A recorded step: its increment, and what the driver adds to it."""

    increment: Increment
    slip: np.ndarray
    phase: str
    wave: str
    static_friction: float
    actuator: float


@dataclass
class _Run:
    """What the driver accumulates, step by step."""

    slab: Slab
    friction: Coulomb
    body: Body
    condensed: Condensed
    s_prev: np.ndarray
    slip: np.ndarray
    steps: list[_Step] = field(default_factory=list)
    guess: np.ndarray | None = None
    guess_sign: np.ndarray | None = None
    reached_gross: bool = False
    gross_slips: int = 0
    frictionless: bool = False
    jammed: bool = False

    def __post_init__(self) -> None:
        self.tributary = self.slab.tributary_length
        law = self.friction
        self.weakening = (Weakening(law.fs, law.dynamic, law.dc)
                          if isinstance(law, SlipWeakening) else None)

    def advance(self, previous: Control, control: Control, phase: str) -> None:
        """Solve the increment from ``previous`` to ``control`` and keep it.

        An increment that does not converge is cut in halves, recursively.
        """
        try:
            increment = self._attempt(control)
        except NotConverged:
            self.record(self._split(previous, control, depth=1), phase, advanced=True)
        else:
            self.record(increment, phase)

    def _attempt(self, control: Control) -> Increment:
        fs, fd = self.friction.static_after(self.gross_slips), self.friction.dynamic
        if self.frictionless:
            fs = fd = 0.0
        increment = self.body.solve_increment(control, self.s_prev, fs, fd, self.guess,
                                              self.guess_sign, weakening=self.weakening)
        if not increment.residual <= RESIDUAL_TOLERANCE:
            raise NotConverged(f"residual {increment.residual:.3g} above tolerance")
        return increment

    def _split(self, start: Control, end: Control, depth: int) -> Increment:
        """Sub-stepping: reach ``end`` from ``start`` in two halves, recursively."""
        halfway = Control(machine=end.machine, **{
            key: None if getattr(end, key) is None else
            0.5 * (getattr(start, key) + getattr(end, key))
            for key in ("dx", "dy", "T", "N")
        })
        parts: list[Increment] = []
        for origin, target in ((start, halfway), (halfway, end)):
            try:
                part = self._attempt(target)
            except NotConverged as err:
                if depth >= _MAX_SPLITS:
                    raise SolverError(len(self.steps), float("nan"),
                                      f"no convergence after {_MAX_SPLITS} sub-step levels: "
                                      f"{err}") from err
                part = self._split(origin, target, depth + 1)
            self._advance(part)
            parts.append(part)
        # Report the whole increment: its end state and every node that slipped in it.
        merged = parts[-1]
        merged.round_slipped = np.maximum(parts[0].round_slipped, parts[1].round_slipped)
        merged.iterations = parts[0].iterations + parts[1].iterations
        merged.substeps = parts[0].substeps + parts[1].substeps
        merged.residual = max(parts[0].residual, parts[1].residual)
        return merged

    def _advance(self, increment: Increment) -> None:
        relative = increment.u[self.body.ix] - increment.dx
        # a new array, not an update in place: the steps keep the earlier ones
        slip = relative - self.s_prev
        slip += self.slip
        self.slip = slip
        self.s_prev = relative
        self.guess = increment.state
        self.guess_sign = increment.sign

    def record(
        self,
        increment: Increment,
        phase: str,
        *,
        advanced: bool = False,
        actuator: float = float("nan"),
    ) -> None:
        """Keep a step (``advanced``: the sub-stepping has already moved the state).

        Only what the driver reads as it goes is worked out here (the step's wave);
        the per-node fields and totals are formed for all steps at once in the
        dataset (:func:`_to_dataset`).
        """
        if not advanced:
            self._advance(increment)
        if increment.u_before is None:  # no wave split off: the stuck state is the end's
            increment.u_before, increment.r_before = increment.u, increment.r
            increment.dx_before = increment.dx
        elif increment.r_before is None:
            increment.r_before = self.body.K @ increment.u_before
        # (counts: half the time of any() and all() on arrays this small)
        wave = increment.round_slipped >= 0
        kind = "none"
        if np.count_nonzero(wave):
            contact = increment.state != OPEN
            touching = np.count_nonzero(contact)
            kind = ("gross" if touching and np.count_nonzero(wave & contact) == touching
                    else "partial")
        # (an increment's arrays are its own: kept without copies)
        self.steps.append(_Step(increment, self.slip, phase, kind,
                                self.friction.static_after(self.gross_slips), actuator))

    def count_gross(self) -> None:
        """After recording: one more gross slip if the last step was one."""
        self.gross_slips += int(self.gross)

    @property
    def gross(self) -> bool:
        return bool(self.steps) and self.steps[-1].wave == "gross"

    def tangential_load(self, step: _Step) -> float:
        """A step's T (N, full width)."""
        return self.slab.width * float(step.increment.r[self.body.ix].sum())

    def contact_fields(self, u: np.ndarray, r: np.ndarray, dy: float | np.ndarray,
                       state: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pressure and shear (MPa) and gap (mm) at each node, of a step or of steps stacked.

        ``u``, ``r`` (..., 2n), ``dy`` (...) and ``state`` (..., n): one step's, or every
        step's in rows.
        """
        n = self.body.n
        gap = np.where(state != OPEN, 0.0, self.body.g0 + u[..., n:] - np.asarray(dy)[..., None])
        return r[..., n:] / self.tributary, r[..., :n] / self.tributary, gap


def simulation_memory(slab: Slab, path: LoadPath, *, samples: float = 0.0,
                      recovery: bool = False) -> int:
    """Bytes a simulation takes at its peak, estimated before it starts.

    The slab's condensation (:func:`~slipwave.solver.slab.condensation_memory`), the
    steps (a few dozen arrays over the contact's nodes each; a load-controlled path
    takes about three times N / ``tangential_step`` of them) and the signals sampled
    from them with their working copies. Every command checks it with
    :func:`slipwave.resources.require_memory` before it simulates.

    Parameters
    ----------
    slab, path
        The simulation's.
    samples
        Samples of the recording drawn from it (duration times rate).
    recovery
        Whether the displacement recovery of the virtual bench's camera is built.

    Returns
    -------
    int
        The estimate, bytes (the measured peaks lie below it).

    Examples
    --------
    >>> path = LoadPath(machine_stiffness=40.0, max_travel=14.0, travel_step=0.03)
    >>> small = simulation_memory(Slab(elements=80), path, samples=28_000)
    >>> big = simulation_memory(Slab(elements=80), path, samples=2.8e9)
    >>> small < 100e6 < 500e9 < big
    True
    """
    if path.max_travel is not None and path.travel_step is not None:
        steps = path.max_travel / path.travel_step
    else:
        steps = 3.0 * path.normal_load / path.tangential_step
    steps = path.normal_steps + min(steps, path.max_steps)
    nodes = slab.elements + 1
    total = condensation_memory(slab, recovery=recovery) + steps * nodes * 8 * 48 + samples * 256
    return int(min(total, 2.0**62))


def simulate(
    slab: Slab,
    friction: Coulomb,
    path: LoadPath | None = None,
    *,
    cache: SolverCache | None = None,
    variables: Collection[str] | None = None,
) -> xr.Dataset:
    """Follow the bench's load path on a slab, increment by increment.

    Step 1 presses the flat onto the slab in ``normal_steps`` load steps; step
    2 moves the flat towards +x so that T grows by ``tangential_step`` per
    step, until gross sliding (every contact node slipping), and optionally on
    past it in flat-travel increments up to ``max_travel``.

    Returns
    -------
    xarray.Dataset
        Coordinates ``step`` and ``x`` (mm, contact nodes, left to right).
        Per node and step: ``state`` (0 open, 1 stick, 2 slip),
        ``slip_direction`` (sign of the slip increment), ``cascade_round``
        (round of the increment's cascade in which the node started slipping,
        -1 if it did not), ``p`` and ``q`` (MPa, pressure and shear traction
        on the slab, positive along +y and +x), ``gap`` and ``slip`` (mm,
        accumulated slip of the slab relative to the flat). Per step: ``T``,
        ``N`` (N, full width, N compressive positive), ``DG``, ``DD`` (mm,
        lateral displacement of the left and right faces at 5 mm), ``DT`` (mm,
        flat travel), ``approach`` (mm, normal approach of the flat),
        ``phase`` (``normal``/``tangential``), ``wave`` (``none``,
        ``partial``, ``gross``), ``residual``, ``iterations``. Also per node and step
        ``ux``, ``uy`` (mm, the contact nodes' displacements) and ``ux_before_wave``,
        ``uy_before_wave`` (in the step's stuck state, before its wave); per step
        ``T_before_wave`` to ``DT_before_wave`` (the peak before the wave),
        ``actuator`` (mm, NaN unless the machine drives the flat),
        ``static_friction`` and ``substeps``: :data:`SIMULATION_VARIABLES`.

    Raises
    ------
    SolverError
        If an increment does not converge, even sub-stepped.
    ValueError
        If ``variables`` names one :data:`SIMULATION_VARIABLES` does not have.

    Parameters
    ----------
    slab
        The slab and its mesh.
    friction
        The interface's friction law.
    path
        The load path (``None``: :class:`LoadPath`'s defaults).
    cache
        Where the slab's condensation and its frictionless normal approach are
        looked up and kept (a map row's, a fit's); ``None``: computed afresh.
    variables
        The data variables to return, by name (:data:`SIMULATION_VARIABLES`, described
        under Returns); the coordinates and attributes always come. ``None``: all. A
        caller that reads a few (the map's events, a fit's signals) saves the time of
        making the others.

    Examples
    --------
    >>> ds = simulate(Slab(elements=40), Coulomb(fs=0.5), LoadPath(normal_load=76.0))
    >>> bool(ds["wave"][-1] == "gross"), round(float(ds["T"][-1] / ds["N"][-1]), 6)
    (True, 0.5)

    """
    unknown = sorted(set(variables or ()) - set(SIMULATION_VARIABLES))
    if unknown:
        raise ValueError(f"simulate has no variable {', '.join(unknown)}; "
                         f"it has {', '.join(SIMULATION_VARIABLES)}")
    path = path or LoadPath()
    condensed, body = _reduced(slab, cache)
    run = _Run(slab, friction, body, condensed, s_prev=np.zeros(body.n), slip=np.zeros(body.n))
    width = slab.width

    _normal_loading(run, path, cache)
    held = run.steps[-1].increment.dy
    run.guess = run.guess_sign = None

    def hold(**motion: float) -> Control:
        if path.normal_control == "displacement":
            return Control(dy=held, **motion)
        return Control(N=path.normal_load / width, **motion)

    # Tangential loading by load increments, until gross sliding, or until the
    # contact is found jammed (held normal displacement only: see _jammed).
    start_T = run.tangential_load(run.steps[-1]) / width
    step_travel = path.tangential_step / width / _stick_stiffness(body, path.normal_control)
    k = 1
    cap = path.max_tangential_load or np.inf
    can_jam = path.normal_control == "displacement" and _may_jam(run)
    while path.machine_stiffness is None and len(run.steps) < path.max_steps:
        if start_T + k * path.tangential_step / width > cap / width + 1e-12:
            break
        control = hold(T=start_T + k * path.tangential_step / width)
        try:
            if _beyond_friction(run, control):
                raise NotConverged("T beyond fs N: no equilibrium")
            run.record(run._attempt(control), "tangential")
        except NotConverged:
            sliding = _sliding(run, control, run.steps[-1].increment.dx + step_travel)
            if sliding is not None:
                run.record(sliding, "tangential")
            else:
                previous = hold(T=start_T + (k - 1) * path.tangential_step / width)
                run.record(run._split(previous, control, depth=1), "tangential", advanced=True)
        k += 1
        if run.gross:
            break
        if can_jam and (_jammed(run, run.friction.fs) or run.tangential_load(run.steps[-1])
                        >= ASYMPTOTIC_LOAD_RATIO * path.normal_load):
            run.jammed = True
            break

    run.reached_gross = run.gross
    if path.machine_stiffness is not None:
        _drive_through_machine(run, path, hold)
    elif path.max_travel is not None:
        travel_step = path.travel_step or step_travel
        dx = run.steps[-1].increment.dx
        while dx < path.max_travel - 1e-12 and len(run.steps) < path.max_steps:
            previous = hold(dx=dx)
            dx = min(dx + travel_step, path.max_travel)
            run.advance(previous, hold(dx=dx), "tangential")

    return _to_dataset(run, path, variables)


def _reduced(slab: Slab, cache: SolverCache | None) -> tuple[Condensed, Body]:
    """The slab condensed, and reduced to a body whose every node sticks.

    A ``cache`` keeps both for the slab: a map row's or a fit's simulations restart
    its body rather than condense, allocate and zero one each (5 % of a map case).
    """
    gap = slab.initial_gap()

    def reduce() -> tuple[Condensed, Body]:
        condensed = condense(slab, cache=cache)
        return condensed, Body(condensed.stiffness, gap)

    if cache is None:
        return reduce()
    condensed, body = cache.body((geometry_key(slab), slab.youngs_modulus, gap.tobytes()),
                                 reduce)
    body.restart()
    return condensed, body


def _normal_loading(run: _Run, path: LoadPath, cache: SolverCache | None) -> None:
    """Step 1: the flat pressed onto the slab in ``normal_steps`` load steps.

    A frictionless approach does not depend on the friction law: a ``cache`` keeps its
    steps, so that a map row or a fit computes it once per slab.
    """
    slab = run.slab
    key = ("frictionless approach", geometry_key(slab), slab.youngs_modulus, slab.width,
           run.body.g0.tobytes(), path.normal_load, path.normal_steps)
    kept = None if path.normal_friction or cache is None else cache.approach(key)
    if kept is not None:
        steps, s_prev, slip = kept
        static = run.friction.static_after(0)
        run.steps = [step._replace(static_friction=static) for step in steps]
        run.s_prev, run.slip = s_prev.copy(), slip.copy()
        return
    previous = Control(dx=0.0, N=0.0)
    run.frictionless = not path.normal_friction
    for k in range(1, path.normal_steps + 1):
        control = Control(dx=0.0, N=path.normal_load / slab.width * k / path.normal_steps)
        run.advance(previous, control, "normal")
        previous = control
    run.frictionless = False
    if not path.normal_friction and cache is not None:
        cache.keep_approach(key, (list(run.steps), run.s_prev.copy(), run.slip.copy()))


def _drive_through_machine(run: _Run, path: LoadPath, hold: Any) -> None:
    """The tangential phase driven by an actuator through the machine's spring."""
    assert path.machine_stiffness and path.max_travel and path.travel_step
    machine = path.machine_stiffness / run.slab.width
    start = run.tangential_load(run.steps[-1]) / run.slab.width  # the actuator starts where T is
    steps = int(np.ceil(path.max_travel / path.travel_step - 1e-9))
    previous = hold(T=start, machine=machine)
    for k in range(1, steps + 1):
        if len(run.steps) >= path.max_steps:
            break
        actuator = min(k * path.travel_step, path.max_travel)
        control = hold(T=start + machine * actuator, machine=machine)
        try:
            run.record(run._attempt(control), "tangential", actuator=actuator)
        except NotConverged:
            run.record(run._split(previous, control, depth=1), "tangential", advanced=True,
                       actuator=actuator)
        run.reached_gross = run.reached_gross or run.gross
        run.count_gross()
        previous = control


def _may_jam(run: _Run) -> bool:
    """Whether the contact can jam: its state when T dwarfs the normal loading sticks.

    Under a held normal displacement N grows with T. Once T is large the normal
    approach and the path are negligible, and the problem is the flat at zero
    approach loaded by T alone, which is positively homogeneous in T (Coulomb's law
    and unilateral contact scale with the loads): its zone state is the same at
    every T. If that state slides, gross sliding comes at a finite T, and the run
    goes on until it does; if some of it sticks, the contact may jam.
    """
    if run.slab.profile is not None:
        return False  # an initial gap breaks the scaling: no asymptote to read
    fs, fd = run.friction.fs, run.friction.dynamic
    try:
        limit = run.body.solve_increment(Control(T=1.0, dy=0.0), np.zeros(run.body.n), fs, fd)
    except NotConverged:
        return False
    return bool(limit.residual <= RESIDUAL_TOLERANCE and (limit.state == STICK).any())


def _jammed(run: _Run, fs: float) -> bool:
    """Whether the contact has jammed: its present zone state holds for every larger T.

    Over the last three steps the zone state (and slip directions) did not change,
    so the response to T is linear: pressure and shear grow by fixed increments per
    step. The state then holds for ever if no contact node's pressure decreases, no
    open node closes, and every sticking node's shear increment stays below fs times
    its pressure increment: along that straight line |q| / p moves monotonically
    from its present value (below fs) towards |dq| / dp (below fs too), so it never
    reaches fs and no node can start slipping; the whole contact can never slip.
    """
    if len(run.steps) < 3:
        return False
    a, b, c = (step.increment for step in run.steps[-3:])
    same = (np.array_equal(a.state, b.state) and np.array_equal(b.state, c.state)
            and np.array_equal(b.direction, c.direction))
    if not same or (run.steps[-1].wave != "none" and not (c.state == STICK).any()):
        return False
    (pa, _, _), (pb, qb, gap_b), (pc, qc, gap_c) = (
        run.contact_fields(made.u, made.r, made.dy, made.state) for made in (a, b, c))
    dp, dq = pc - pb, qc - qb
    if not np.allclose(dp, pb - pa, rtol=1e-6, atol=1e-12):
        return False  # not yet linear
    contact, stick = c.state != OPEN, c.state == STICK
    dgap = gap_c - gap_b
    margin = 1.0 - 1e-9
    return bool(stick.any() and (dp[contact] >= 0).all() and (dgap[~contact] >= 0).all()
                and (np.abs(dq[stick]) < margin * fs * dp[stick]).all())


def _stick_stiffness(body: Body, normal_control: str) -> float:
    """dT/d(dx) per unit width while every contact node sticks (N/mm per mm)."""
    state = np.full(body.n, 1, dtype=np.int8)
    zero = np.zeros(body.n)
    if normal_control == "displacement":
        u, _, _ = body.solve_linear(state, zero, zero, Control(dx=1.0, dy=0.0))
    else:
        u, _, _ = body.solve_linear(state, zero, zero, Control(dx=1.0, N=0.0))
    return float(body.sum_x @ u)


def _beyond_friction(run: _Run, control: Control) -> bool:
    """Whether a load-controlled T exceeds what any state can carry: fs times N.

    Every contact node's shear is at most its coefficient (at most fs) times its
    pressure, so no equilibrium exists past fs N: the active set need not search
    for one (it would cycle until its iteration limit).
    """
    if control.T is None or control.N is None or control.machine:
        return False
    fs = run.friction.static_after(run.gross_slips)
    return abs(control.T) > fs * abs(control.N) * (1.0 + _CAPACITY_MARGIN)


def _sliding(run: _Run, control: Control, dx_floor: float) -> Increment | None:
    """The gross-sliding state, if the contact cannot carry the T that ``control`` asks.

    A T-controlled increment that fails either asks more than the sliding
    contact carries (gross sliding: returned) or is merely hard (``None``: the
    caller sub-steps it).
    """
    try:
        sliding = run.body.slide(run.s_prev, run.friction.dynamic, control, dx_floor, run.guess)
    except NotConverged as err:
        raise SolverError(len(run.steps), float("nan"), f"gross sliding state: {err}") from err
    if control.T is None or float(sliding.r[run.body.ix].sum()) >= control.T:
        return None
    if not sliding.residual <= RESIDUAL_TOLERANCE:
        raise SolverError(len(run.steps), sliding.residual, "gross sliding state inexact")
    return sliding


def _to_dataset(run: _Run, path: LoadPath, variables: Collection[str] | None) -> xr.Dataset:
    steps = run.steps
    slab = run.slab
    width, n = slab.width, run.body.n
    increments = [step.increment for step in steps]

    # Each array is made when a wanted variable first needs it, and once.
    @functools.cache
    def stacked(name: str) -> np.ndarray:
        """An increment's field, for every step."""
        return np.array([getattr(increment, name) for increment in increments])

    @functools.cache
    def edges() -> np.ndarray:
        # a product per step, as each step alone would have it (a product of all steps
        # at once rounds differently)
        return np.array([run.condensed.sensors @ row for row in stacked("u")])

    @functools.cache
    def before_wave() -> dict[str, np.ndarray]:
        r_before = stacked("r_before")
        edges_before = np.array([edges()[k] if increment.u_before is increment.u
                                 else run.condensed.sensors @ increment.u_before
                                 for k, increment in enumerate(increments)])
        return {"T": width * r_before[:, :n].sum(axis=1),
                "N": width * r_before[:, n:].sum(axis=1),
                "DG": edges_before[:, 0], "DD": edges_before[:, 1], "DT": stacked("dx_before")}

    @functools.cache
    def contact() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return run.contact_fields(stacked("u"), stacked("r"), stacked("dy"), stacked("state"))

    def peak(name: str, units: str) -> tuple[Any, ...]:
        return ("step", before_wave()[name], {
            "units": units,
            "long_name": f"{name} in the stuck state of the step, before its wave (the peak)"})

    node = ("step", "x")
    made: dict[str, Callable[[], tuple[Any, ...]]] = {
        "state": lambda: (node, stacked("state").astype(np.int8), {
            "long_name": "contact state", "flag_values": np.array([0, 1, 2], dtype=np.int8),
            "flag_meanings": "open stick slip"}),
        "slip_direction": lambda: (node, stacked("direction").astype(np.int8), {
            "long_name": "sign of the slab's slip increment relative to the flat",
            "units": "1"}),
        "cascade_round": lambda: (node, stacked("round_slipped").astype(np.int16), {
            "long_name": "cascade round in which the node started slipping in this step "
                         "(-1: it did not)", "units": "1"}),
        "p": lambda: (node, contact()[0], {"units": "MPa", "long_name": "contact pressure"}),
        "q": lambda: (node, contact()[1], {
            "units": "MPa", "long_name": "shear traction on the slab (positive along +x)"}),
        "gap": lambda: (node, contact()[2], {"units": "mm", "long_name": "normal gap"}),
        "slip": lambda: (node, np.array([step.slip for step in steps]), {
            "units": "mm", "long_name": "accumulated slip of the slab relative to the flat"}),
        "ux": lambda: (node, stacked("u")[:, :n], {
            "units": "mm", "long_name": "tangential displacement of the contact nodes"}),
        "uy": lambda: (node, stacked("u")[:, n:], {
            "units": "mm", "long_name": "normal displacement of the contact nodes"}),
        "ux_before_wave": lambda: (node, stacked("u_before")[:, :n], {
            "units": "mm", "long_name": "ux in the stuck state of the step, before its wave"}),
        "uy_before_wave": lambda: (node, stacked("u_before")[:, n:], {
            "units": "mm", "long_name": "uy in the stuck state of the step, before its wave"}),
        "T": lambda: ("step", width * stacked("r")[:, :n].sum(axis=1), {
            "units": "N", "long_name": "tangential load"}),
        "N": lambda: ("step", width * stacked("r")[:, n:].sum(axis=1), {
            "units": "N", "long_name": "normal load", "comment": "compressive load, positive"}),
        "DG": lambda: ("step", edges()[:, 0], {
            "units": "mm",
            "long_name": "left-edge lateral displacement of the slab, 5 mm above the contact"}),
        "DD": lambda: ("step", edges()[:, 1], {
            "units": "mm",
            "long_name": "right-edge lateral displacement of the slab, 5 mm above the contact"}),
        "DT": lambda: ("step", stacked("dx"), {"units": "mm", "long_name": "flat displacement"}),
        "approach": lambda: ("step", stacked("dy"), {
            "units": "mm", "long_name": "normal approach of the flat"}),
        "actuator": lambda: ("step", np.array([step.actuator for step in steps]), {
            "units": "mm", "long_name": "actuator travel (machine drive; NaN otherwise)"}),
        **{f"{name}_before_wave": functools.partial(peak, name, units) for name, units in
           (("T", "N"), ("N", "N"), ("DG", "mm"), ("DD", "mm"), ("DT", "mm"))},
        "phase": lambda: ("step", np.array([step.phase for step in steps]), {
            "long_name": "load phase"}),
        "wave": lambda: ("step", np.array([step.wave for step in steps]), {
            "long_name": "nodes that slipped in the step: none, partial or gross (all)"}),
        "static_friction": lambda: ("step", np.array([step.static_friction for step in steps]), {
            "units": "1", "long_name": "static friction coefficient in force during the step"}),
        "residual": lambda: ("step", stacked("residual"), {
            "units": "1", "long_name": "relative complementarity residual"}),
        "iterations": lambda: ("step", stacked("iterations").astype(np.int32), {
            "units": "1", "long_name": "active-set iterations"}),
        "substeps": lambda: ("step", stacked("substeps").astype(np.int32), {
            "units": "1", "long_name": "parts the step was solved in (1: whole; more: "
                                       "sub-stepped, each part its own wave)"}),
    }
    if variables is not None:
        made = {name: make for name, make in made.items() if name in variables}
    coords = {
        "step": ("step", np.arange(len(steps)), {"long_name": "load step"}),
        "x": ("x", slab.x, {"units": "mm", "long_name": "position along the contact, "
                            "origin at its centre"}),
        "tributary_length": ("x", slab.tributary_length, {
            "units": "mm", "long_name": "contact length each node stands for"}),
    }
    attrs: dict[str, Any] = {
        "title": "slipwave frictional contact simulation",
        "Conventions": CONVENTIONS,
        "source": f"slipwave {__version__} slipwave.solver.simulate",
        "element": "bilinear quadrilaterals, selective reduced integration, plane strain",
    }
    # (the fields read as they are: asdict would deep-copy them)
    attrs.update({f"slab_{item.name}": getattr(slab, item.name) for item in fields(slab)
                  if item.name != "profile"})
    attrs["slab_profile"] = "flat" if slab.profile is None else repr(slab.profile)
    attrs["friction_fs"] = run.friction.fs
    attrs["friction_fd"] = run.friction.dynamic
    if isinstance(run.friction, SlipWeakening):
        attrs["friction_law"] = "linear slip-weakening"
        attrs["friction_dc"] = run.friction.dc
    else:
        attrs["friction_law"] = "Coulomb"
    if run.friction.fs_final is not None:
        attrs["friction_fs_final"] = run.friction.fs_final
        attrs["friction_runin_slips"] = run.friction.runin_slips
    if run.friction.fs_peak is not None:
        attrs["friction_fs_peak"] = run.friction.fs_peak
    attrs.update({f"path_{item.name}": "none" if getattr(path, item.name) is None
                  else getattr(path, item.name) for item in fields(path)})
    attrs["gross_sliding"] = ("reached" if run.reached_gross else
                              "jammed: no further increment can make the whole contact slip"
                              if run.jammed else
                              "not reached: the tangential load cap or step limit came first")
    # made Variables first: xarray then skips inferring each one (a third of a map
    # case's time went to building its Dataset)
    return xr.Dataset({name: xr.Variable(*make()) for name, make in made.items()},
                      coords=coords, attrs=attrs)
