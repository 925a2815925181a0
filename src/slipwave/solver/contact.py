"""One load increment of frictional contact against a rigid flat.

The body is any linear elastic body reduced to a stiffness matrix ``K`` on
its n contact nodes (unknowns ``[ux, uy]``, forces ``r = K u`` exerted by the
flat on the body). The flat has tangential position ``dx`` and normal
approach ``dy``; node i has initial gap ``g0_i``. Per node:

- gap ``g = g0 + uy - dy >= 0``, normal force ``P = ry >= 0``, ``g P = 0``;
- relative tangential position ``s = ux - dx``; in this increment
  ``ds = s - s_prev``; stick (``ds = 0``, ``|Q| <= f P``) or slip
  (``Q = -f P sign(ds)``), with ``Q = rx``.

Each of ``dx``, ``dy`` is either prescribed or unknown with the total force
prescribed (``sum Q = T``, ``sum P = N``).

The increment is solved by a primal-dual active-set method (a semi-smooth
Newton method on the Alart-Curnier complementarity functions): guess which
nodes are open, stuck or slipping, solve the linear problem these imply
(only the open and slipping unknowns remain), update the guess from the
augmented multipliers, until it no longer changes.

With a static coefficient above the dynamic one the increment is a cascade:
every node starts stuck (the interface heals), nodes loaded beyond ``fs P``
start slipping and from then on obey ``fd``; their shed load may push others
beyond ``fs``, which join in the next round, until none does. The nodes that
slipped form the increment's wave.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg.lapack import dgetrf, dgetrs

from slipwave.errors import SlipwaveError

OPEN, STICK, SLIP = 0, 1, 2
_ONE = np.ones(1)

_MAX_ITERATIONS = 60
_PREDICTOR = 0.9  # see _iterate
_WEAKENING_TOLERANCE = 1e-6  # relative change of a wave coefficient that ends the fixed point
_MAX_WEAKENINGS = 1000
# Newton steps on the wave's coefficients per cascade round before falling back on the
# plain fixed point (with Aitken's extrapolation); Newton mostly ends in two or three.
_NEWTON_WEAKENINGS = 12
_NEWTON_REACH = 20.0  # the longest Newton step, in plain fixed-point steps
_SLOPE_STEP = 1e-6  # mm: the central difference of the weakening's slope
# Factorised zone states kept per body, least recently used dropped first. A stick-slip
# run revisits few states (about 250 in a 280 s test on 80 elements, against some 4000
# solves): kept, they spare a factorisation each; bounded by their bytes.
_PLANS_BYTES = 128 * 2**20
# Zone states whose layout is kept to factorise again with other coefficients of their
# slipping nodes: a slip-weakening wave meets one state with some 30 coefficients.
_LAYOUTS = 32
# Solves of a zone state after which its affine map is kept: building it costs some ten
# solves, and a state met three times is mostly met many more (a stick-slip cycle).
_OPERATOR_USES = 3


class NotConverged(Exception):  # noqa: N818 - an internal signal, not an error of the API
    """The active set did not settle, or the linear problem was singular."""


@dataclass(frozen=True)
class KeptSolves:
    """What a :class:`Body` keeps of the zone states it has solved.

    Attributes
    ----------
    layouts
        Zone states whose index sets and matrix blocks are kept.
    compliance_layouts
        Those solved in the compliance form (fewer nodes stick than are open, and the
        body alone is held); the others in the stiffness form.
    factorisations
        Factorised linear problems (a zone state with its slipping coefficients).
    affine_maps
        Those met often enough to be solved by a kept affine map of the loads.
    """

    layouts: int
    compliance_layouts: int
    factorisations: int
    affine_maps: int


@dataclass(frozen=True)
class Control:
    """Prescribed flat motion or total force for one increment.

    Exactly one of ``dx`` / ``T`` and one of ``dy`` / ``N`` is given (forces
    per unit width, N/mm). With ``machine`` (a stiffness per unit width between
    an actuator and the flat) the tangential equation is
    ``sum Q + machine * dx = T``: the actuator at X drives the flat through a
    spring when ``T = machine * X``.
    """

    dx: float | None = None
    dy: float | None = None
    T: float | None = None
    N: float | None = None
    machine: float = 0.0
    kinds: tuple[bool, ...] = field(init=False, repr=False, compare=False)
    key: bytes = field(init=False, repr=False, compare=False)
    given: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if (self.dx is None) == (self.T is None) or (self.dy is None) == (self.N is None):
            raise SlipwaveError("give exactly one of dx/T and one of dy/N")
        # what a zone state's factorisation depends on, and the values it is solved
        # for: read at every solve of the increment, so made once
        kinds = (self.dx is None, self.dy is None, self.T is not None, self.N is not None)
        object.__setattr__(self, "kinds", kinds)
        object.__setattr__(self, "key", bytes(kinds) + np.float64(self.machine).tobytes())
        object.__setattr__(self, "given", np.array(
            [value for value in (self.dx, self.dy, self.T, self.N) if value is not None],
            dtype=np.float64))


@dataclass
class Increment:
    """The solution of one increment."""

    u: np.ndarray
    r: np.ndarray
    dx: float
    dy: float
    state: np.ndarray
    direction: np.ndarray
    round_slipped: np.ndarray
    iterations: int
    sign: np.ndarray
    residual: float
    u_before: np.ndarray | None = None
    dx_before: float = 0.0
    substeps: int = 1


class Body:
    """A body reduced to its contact nodes: stiffness, gaps and the derived scales.

    Parameters
    ----------
    stiffness
        (2n, 2n) stiffness on ``[ux, uy]`` of the contact nodes.
    initial_gap
        g0 (n,), mm.
    compliance
        The inverse of ``stiffness`` (the flexibility form); ``None`` when the
        body alone has a rigid mode, and only the stiffness form is used.

    """

    def __init__(
        self,
        stiffness: np.ndarray,
        initial_gap: np.ndarray,
        compliance: np.ndarray | None = None,
    ) -> None:
        self.K = np.ascontiguousarray(stiffness, dtype=np.float64)
        self.n = initial_gap.size
        if self.K.shape != (2 * self.n, 2 * self.n):
            raise SlipwaveError("stiffness must be (2n, 2n) for n contact nodes")
        self.g0 = np.asarray(initial_gap, dtype=np.float64)
        self.ix = np.arange(self.n)
        self.iy = self.n + self.ix
        diagonal = np.diag(self.K)
        self.cx = diagonal[self.ix]  # augmentation: the nodes' own stiffness
        self.cy = diagonal[self.iy]
        self.sum_x = self.K[self.ix].sum(axis=0)  # sum Q = sum_x @ u
        self.sum_y = self.K[self.iy].sum(axis=0)
        # Compliance, for the flexibility form; None when the body alone has a
        # rigid mode (then only the stiffness form is used).
        self.C = compliance
        self._plans: dict[bytes, _Plan] = {}
        self._layouts: dict[bytes, _Layout] = {}
        self._plans_bytes = 0

    def kept_solves(self) -> KeptSolves:
        """What the body keeps of the zone states it has solved (as ``cache_info``).

        Returns
        -------
        KeptSolves
            Counts of the kept layouts and factorisations, by form and kind.

        """
        return KeptSolves(
            layouts=len(self._layouts),
            compliance_layouts=sum(layout.compliance for layout in self._layouts.values()),
            factorisations=len(self._plans),
            affine_maps=sum(plan.operator is not None for plan in self._plans.values()))

    def solve_linear(
        self,
        state: np.ndarray,
        mu: np.ndarray,
        s_prev: np.ndarray,
        control: Control,
    ) -> tuple[np.ndarray, float, float]:
        """Displacements and flat position for a fixed zone state.

        ``mu`` is the signed friction coefficient of slipping nodes (``Q = mu P``).
        The smaller of two equivalent forms is solved: displacements of the open
        and slipping nodes (2 open + slip unknowns), or forces of the stuck and
        slipping ones (2 stick + slip). Each zone state's matrix is factorised
        once and kept for the next increments, which mostly meet it again.

        Parameters
        ----------
        state
            Zone of each node (open, stick or slip).
        mu
            Signed friction coefficient of the slipping nodes.
        s_prev
            Relative tangential positions at the end of the previous increment.
        control
            What is imposed on the flat in this increment.

        Returns
        -------
        tuple
            Contact displacements, flat x and flat y positions.

        """
        u, dx, dy, _ = self.solve_state(state, mu, s_prev, control)
        return u, dx, dy

    def solve_state(
        self,
        state: np.ndarray,
        mu: np.ndarray,
        s_prev: np.ndarray,
        control: Control,
    ) -> tuple[np.ndarray, float, float, np.ndarray]:
        """:meth:`solve_linear`, with the contact forces ``r = K u`` too.

        A zone state solved a few times before is solved again by its kept affine
        map (:meth:`_Plan.keep_operator`): in a stick-slip run most solves meet a
        state seen many times.

        Parameters
        ----------
        state, mu, s_prev, control
            As in :meth:`solve_linear`.

        Returns
        -------
        tuple
            Contact displacements, flat x and y positions, contact forces.

        """
        plan = self._plan(state, mu, control)
        plan.uses += 1
        if plan.uses >= _OPERATOR_USES and plan.operator is None:
            before = plan.nbytes
            plan.keep_operator()
            self._plans_bytes += plan.nbytes - before
        return plan.solve(s_prev, control)

    def slip_sensitivity(
        self,
        state: np.ndarray,
        mu: np.ndarray,
        control: Control,
        pressure: np.ndarray,
    ) -> np.ndarray:
        """How the slipping nodes' slips move with their friction coefficients.

        For a fixed zone state the solution is linear in the loads but not in the
        slipping nodes' coefficients: ``Q_i = mu_i P_i``. Its derivative reuses the
        state's factorisation (one solve with a right-hand side per slipping node),
        which gives slip-weakening's fixed point a Newton step.

        Parameters
        ----------
        state, mu, control
            As in :meth:`solve_linear`, whose solution is differentiated.
        pressure
            Normal force P of every node in that solution.

        Returns
        -------
        numpy.ndarray
            (m, m) for the m slipping nodes in index order: d(ds_j)/d(mu_i), the
            change of node j's slip increment ``ux - dx - s_prev`` per unit change
            of node i's signed coefficient.

        """
        return self._plan(state, mu, control).slip_sensitivity(pressure)

    def _plan(self, state: np.ndarray, mu: np.ndarray, control: Control) -> _Plan:
        """The factorised problem of a zone state, kept or made (and then kept)."""
        shape = state.tobytes() + control.key
        key = shape + np.where(state == SLIP, mu, 0.0).tobytes()
        plan = self._plans.pop(key, None)  # put back last: the most recently used
        if plan is None:
            layout = self._layouts.pop(shape, None)
            if layout is None:
                layout = _Layout(self, state, control.kinds, control.machine)
                while len(self._layouts) >= _LAYOUTS:
                    self._layouts.pop(next(iter(self._layouts)))
            self._layouts[shape] = layout
            plan = _Plan(layout, mu)
            self._plans_bytes += plan.nbytes
            while self._plans and self._plans_bytes > _PLANS_BYTES:
                self._plans_bytes -= self._plans.pop(next(iter(self._plans))).nbytes
        self._plans[key] = plan
        return plan

    def solve_increment(
        self,
        control: Control,
        s_prev: np.ndarray,
        static: float,
        dynamic: float,
        guess: np.ndarray | None = None,
        guess_sign: np.ndarray | None = None,
        weakening: Callable[[np.ndarray], np.ndarray] | None = None,
    ) -> Increment:
        """Solve one increment from the previous relative positions ``s_prev``.

        Parameters
        ----------
        control
            The flat's motion or the total forces.
        s_prev
            ``ux - dx`` of every node at the end of the previous increment.
        static, dynamic
            Friction coefficients fs >= fd.
        guess, guess_sign
            Zone state and friction signs to start from (the previous
            increment's). With fs == fd the iteration starts there, and from a
            stuck interface if that fails; with fs > fd every increment starts
            stuck (the interface heals).
        weakening
            With fs > fd, the friction coefficient of a slipping node as a
            function of its slip in the increment's wave (mm; ``static`` at 0,
            falling to ``dynamic``): slip-weakening. ``None``: the coefficient
            drops to ``dynamic`` as soon as the node slips (Coulomb).

        Raises
        ------
        NotConverged
            When the active set cycles or the linear problem is singular; the
            caller may sub-step.

        Returns
        -------
        Increment
            The converged zone state, displacements and reactions.

        """
        if guess is not None and guess_sign is not None and static == dynamic:
            try:
                return self._iterate(control, s_prev, static, dynamic, guess, guess_sign,
                                     heal=False)
            except NotConverged:
                pass  # e.g. slip reversing direction: start again from a stuck interface
        return self._iterate(control, s_prev, static, dynamic, guess, None, heal=True,
                             weakening=weakening if static > dynamic else None)

    def _iterate(
        self,
        control: Control,
        s_prev: np.ndarray,
        static: float,
        dynamic: float,
        guess: np.ndarray | None,
        guess_sign: np.ndarray | None,
        *,
        heal: bool,
        weakening: Callable[[np.ndarray], np.ndarray] | None = None,
    ) -> Increment:
        n = self.n
        cascade = static > dynamic
        state = np.full(n, STICK, dtype=np.int8) if guess is None else guess.astype(np.int8)
        sign = np.ones(n) if guess_sign is None else guess_sign.astype(np.float64)
        if heal:
            # A stuck predictor finds the slipping nodes with their new directions.
            state[state == SLIP] = STICK
        in_wave = np.zeros(n, dtype=bool)
        round_slipped = np.full(n, -1, dtype=np.int16)
        # The coefficient of each node in the wave: fd, or under slip-weakening its
        # coefficient at the slip it has made in the wave (a fixed point, below).
        wave_limit = np.full(n, float(dynamic))
        iterations = 0
        rounds = 0
        weakenings = 0
        history: list[np.ndarray] = []
        newtons = 0  # Newton steps in this round
        while True:
            # Nodes outside the wave may slip only without a cascade (fs == fd).
            limit = np.where(in_wave, wave_limit, static)
            may_slip = in_wave | (not cascade)
            seen: set[bytes] = set()
            first_iteration = rounds == 0
            for _ in range(_MAX_ITERATIONS):
                iterations += 1
                mu = limit * sign
                u, dx, dy, r = self.solve_state(state, mu, s_prev, control)
                Q, P = r[:n], r[n:]  # ix and iy are the two halves
                gap = self.g0 + u[n:] - dy
                ds = u[:n] - dx - s_prev
                pressure = P - self.cy * gap
                trial = Q - self.cx * ds
                new = (pressure > 0).view(np.int8).copy()  # OPEN 0, STICK 1
                bound = limit * np.maximum(pressure, 0.0)
                slipping = (new == STICK) & may_slip & (np.abs(trial) > bound)
                if first_iteration:
                    # A slip front advances about a node per active-set iteration: a
                    # stuck node beside the slip, already within 10 % of its limit,
                    # starts the increment slipping (it sticks again in the next
                    # iteration if it does not slip). This saves iterations, each a new
                    # factorisation; the converged state is the same.
                    beside = np.convolve(slipping | (state == SLIP), [1, 1, 1], "same") > 0
                    slipping |= ((new == STICK) & may_slip & beside
                                 & (np.abs(trial) > _PREDICTOR * bound))
                    first_iteration = False
                new[slipping] = SLIP
                if (control.dx is None and control.machine == 0.0
                        and not (new == STICK).any() and slipping.any()):
                    # Under load control a state without a stuck node leaves dx
                    # undetermined; keep the least overloaded node stuck. If the
                    # contact truly cannot carry T, the iteration fails and the
                    # caller finds gross sliding.
                    excess = np.where(slipping, np.abs(trial) - bound, np.inf)
                    new[np.argmin(excess)] = STICK
                    slipping = new == SLIP
                # (a frictionless slip carries no shear: its sign changes nothing)
                new_sign = np.where(slipping & (limit > 0), np.sign(trial), sign)
                if (new == state).all() and (new_sign == sign).all():
                    break
                key = new.tobytes() + new_sign.tobytes()
                if key in seen:
                    # A cycle: nodes at the edge of the contact flip between stuck in
                    # tension and open in penetration. They are in contact with a
                    # vanishing pressure, so any shear exceeds f P: they slide (and,
                    # in a cascade, join the wave).
                    flipping = new != state
                    if cascade:
                        joining = flipping & ~in_wave
                        in_wave |= joining
                        round_slipped[joining] = rounds
                        limit = np.where(in_wave, wave_limit, static)
                        may_slip = in_wave
                    new[flipping] = SLIP
                    new_sign[flipping] = np.where(trial[flipping] < 0, -1.0, 1.0)
                    seen.clear()
                seen.add(key)
                state, sign = new, new_sign
            else:
                raise NotConverged(f"active set still changing after {_MAX_ITERATIONS} iterations")
            if rounds == 0:
                # The stuck state of the increment, before any wave: the peak.
                before = (u.copy(), dx)
            if not cascade:
                wave = state == SLIP
                round_slipped[wave] = 0
                break
            if weakening is not None and in_wave.any():
                # Slip-weakening: the wave's coefficients at the slip they give. From
                # fd (the most slip) the slip only shrinks towards the fixed point, the
                # largest equilibrium the weakening allows; Newton's steps go the same
                # way, further.
                slip = np.abs(ds)
                updated = np.where(in_wave & (state == SLIP), weakening(slip), wave_limit)
                updated = np.clip(updated, dynamic, static)
                if np.max(np.abs(updated - wave_limit)) > _WEAKENING_TOLERANCE * static:
                    weakenings += 1
                    if weakenings > _MAX_WEAKENINGS:
                        raise NotConverged("slip-weakening coefficients still changing")
                    if newtons < _NEWTON_WEAKENINGS:
                        newtons += 1
                        wave_limit = self._weakening_newton(
                            state, mu, control, P, ds, wave_limit, updated, weakening,
                            dynamic, static)
                        continue
                    history.append(updated)
                    if len(history) == 3:
                        # Aitken's extrapolation of the slowly converging coefficients
                        a, b, c = history
                        step = (c - b) - (b - a)
                        safe = np.abs(step) > 1e-14
                        jump = np.where(safe, c - (c - b) ** 2 / np.where(safe, step, 1.0), c)
                        updated = np.clip(jump, dynamic, static)
                        history.clear()
                    wave_limit = updated
                    continue
            over = (state == STICK) & ~in_wave & (np.abs(Q) > static * P * (1 + 1e-12))
            if not over.any():
                break
            in_wave |= over
            round_slipped[over] = rounds
            rounds += 1
            newtons = 0
            history.clear()
            # The overloaded nodes start slipping the way their load pushes them.
            state[over] = SLIP
            sign[over] = np.sign(Q[over])

        limit = np.where(in_wave, wave_limit, static)
        residual = self.residual(P, Q, gap, ds, limit, control, dx)
        direction = np.where(state == SLIP, np.sign(ds), 0).astype(np.int8)
        u_before, dx_before = before if cascade else (u, dx)
        return Increment(u=u, r=r, dx=dx, dy=dy, state=state, direction=direction,
                         round_slipped=round_slipped, iterations=iterations, residual=residual,
                         sign=sign, u_before=u_before, dx_before=dx_before)

    def _weakening_newton(
        self,
        state: np.ndarray,
        mu: np.ndarray,
        control: Control,
        P: np.ndarray,
        ds: np.ndarray,
        wave_limit: np.ndarray,
        updated: np.ndarray,
        weakening: Callable[[np.ndarray], np.ndarray],
        dynamic: float,
        static: float,
    ) -> np.ndarray:
        """A Newton step towards the wave coefficients m = W(|ds(m)|) of this zone state.

        The plain fixed point (``updated``, m <- W(|ds(m)|)) converges slowly when a
        node's slip feeds back strongly on its own coefficient (some ten steps per
        cascade round); Newton's step, from the slip's sensitivity to the
        coefficients (which reuses the state's factorisation), takes two or three.
        It is taken only where it extrapolates the plain step (same direction, at
        most :data:`_NEWTON_REACH` times as far): the plain iteration converges only
        to equilibria that attract it, the stable ones, and Newton's alone could
        also find the unstable ones, behind it.
        """
        slipping = state == SLIP
        m = wave_limit[slipping]
        slip = np.abs(ds[slipping])
        # the slope of the clipped weakening: zero where it is held at fd or fs
        ends = [np.clip(weakening(slip + step), dynamic, static)
                for step in (-_SLOPE_STEP, _SLOPE_STEP)]
        slope = (ends[1] - ends[0]) / (2 * _SLOPE_STEP)
        direction = np.sign(ds[slipping])
        # d|ds_j|/dm_i = sign(ds_j) d(ds_j)/d(mu_i) sign_i, mu = m sign
        sensitivity = (direction[:, None] * self.slip_sensitivity(state, mu, control, P)
                       * np.sign(mu[slipping])[None, :])
        jacobian = np.eye(m.size) - slope[:, None] * sensitivity
        plain = updated[slipping] - m
        try:
            step = np.linalg.solve(jacobian, plain)
        except np.linalg.LinAlgError:
            return updated
        if not (np.isfinite(step).all() and np.all(step * plain >= 0.0)
                and np.all(np.abs(step) <= _NEWTON_REACH * np.abs(plain) + 1e-12)):
            return updated
        result = updated.copy()
        result[slipping] = np.clip(m + step, dynamic, static)
        return result

    def residual(
        self,
        P: np.ndarray,
        Q: np.ndarray,
        gap: np.ndarray,
        ds: np.ndarray,
        limit: np.ndarray,
        control: Control,
        dx: float,
    ) -> float:
        """Relative complementarity residual: zero for an exact solution.

        Normal: ``min(P, c g)``; tangential: ``Q - proj_[-f P+, f P+](Q - c ds)``
        (Alart-Curnier); controls: the prescribed totals. Scaled by ``max |P|``.

        Parameters
        ----------
        P, Q
            Normal and tangential contact forces.
        gap
            Normal gaps.
        ds
            Slip increments.
        limit
            Friction limit of each node (``f P``).
        control
            What is imposed on the flat.
        dx
            The flat's tangential position.

        Returns
        -------
        float
            The largest violation relative to the load scale.

        """
        positive = np.maximum(P, 0.0)
        normal = np.minimum(P, self.cy * gap)
        bound = limit * positive
        tangential = Q - np.clip(Q - self.cx * ds, -bound, bound)
        totals = [0.0]
        if control.T is not None:
            totals.append(abs(Q.sum() + control.machine * dx - control.T))
        if control.N is not None:
            totals.append(abs(P.sum() - control.N))
        scale = max(float(np.abs(P).max()), 1e-300)
        worst = max(float(np.abs(normal).max()), float(np.abs(tangential).max()), max(totals))
        return worst / scale

    def slide(
        self,
        s_prev: np.ndarray,
        dynamic: float,
        control: Control,
        dx_floor: float,
        guess: np.ndarray | None = None,
    ) -> Increment:
        """Gross sliding: every contact node slips forward with ``fd``.

        ``dx`` is then free (the flat slides under the body); it is set to at
        least ``dx_floor`` and far enough that every node slips backwards
        relative to the flat, as it must.

        Parameters
        ----------
        s_prev
            Relative tangential positions at the end of the previous increment.
        dynamic
            The dynamic friction coefficient.
        control
            What is imposed on the flat.
        dx_floor
            The least flat position of the increment.
        guess
            A starting zone state, or ``None``.

        Returns
        -------
        Increment
            Every node slipping forward (or open).

        """
        if guess is None:
            state = np.where(self.g0 <= 0, SLIP, OPEN).astype(np.int8)
        else:
            state = np.where(guess == OPEN, OPEN, SLIP).astype(np.int8)
        mu = np.full(self.n, dynamic)
        sliding = Control(dx=dx_floor, dy=control.dy, N=control.N)
        seen: set[bytes] = set()
        for _ in range(_MAX_ITERATIONS):
            u, dx, dy, r = self.solve_state(state, mu, s_prev, sliding)
            gap = self.g0 + u[self.iy] - dy
            new = np.where(r[self.iy] - self.cy * gap > 0, SLIP, OPEN).astype(np.int8)
            if np.array_equal(new, state):
                break
            if new.tobytes() in seen:
                new[new != state] = SLIP  # contact-edge flip: in contact, vanishing pressure
                seen.clear()
            seen.add(new.tobytes())
            state = new
        else:
            raise NotConverged("gross sliding state did not settle")
        dx = max(dx_floor, float((u[self.ix] - s_prev)[state == SLIP].max(initial=dx_floor)))
        P, Q = r[self.iy], r[self.ix]
        ds = u[self.ix] - dx - s_prev
        residual = self.residual(P, Q, gap, ds, np.full(self.n, dynamic), sliding, dx)
        wave = np.where(state == SLIP, 0, -1).astype(np.int16)
        return Increment(u=u, r=r, dx=dx, dy=dy, state=state,
                         direction=np.where(state == SLIP, np.sign(ds), 0).astype(np.int8),
                         round_slipped=wave, iterations=1, residual=residual,
                         sign=np.ones(self.n))


def _block(matrix: np.ndarray, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """``matrix[rows][:, columns]``; two ``take`` are faster than ``np.ix_`` here."""
    return matrix.take(rows, axis=0).take(columns, axis=1)


class _Layout:
    """What a zone state's linear problem is, whatever its slipping nodes' coefficients.

    The index sets and the blocks of K (or C) the equations read; under
    slip-weakening one zone state meets many coefficients (the wave's fixed point),
    and each of its :class:`_Plan` is then a few products away.
    """

    def __init__(self, body: Body, state: np.ndarray, kinds: tuple[bool, ...],
                 machine: float) -> None:
        self.body = body
        self.machine = machine
        self.dx_unknown, self.dy_unknown, self.T_given, self.N_given = kinds
        ix, iy = body.ix, body.iy
        self.stick = state == STICK
        self.slip = state == SLIP
        self.contact = self.stick | self.slip
        self.n_stick = int(self.stick.sum())
        n_open = body.n - int(self.contact.sum())
        self.compliance = body.C is not None and self.n_stick < n_open
        self.stick_nodes = np.flatnonzero(self.stick)
        self.stick_x = ix[self.stick]
        self.contact_y = iy[self.contact]
        self.slip_x = ix[self.slip]
        self.slip_y = iy[self.slip]
        self.along_x = np.zeros(2 * body.n)
        self.along_x[self.stick_x] = 1.0
        self.along_y = np.zeros(2 * body.n)
        self.along_y[self.contact_y] = 1.0
        if self.compliance:
            self._compliance_blocks()
            blocks = (self.c_stuck, self.c_slip_y, self.c_slip_x)
        else:
            self._stiffness_blocks()
            blocks = (self.k_rows, self.k_unknown, self.k_along)
        self.nbytes = sum(block.nbytes for block in blocks)

    # Stiffness form: unknown displacements of open (x, y) and slipping (x) nodes.
    def _stiffness_blocks(self) -> None:
        body, ix, iy = self.body, self.body.ix, self.body.iy
        opened = ~self.contact
        self.unknown = np.concatenate([ix[self.slip | opened], iy[opened]])
        self.rows = np.concatenate([ix[opened], iy[opened], ix[self.slip]])
        self.first_slip_row = self.rows.size - int(self.slip.sum())
        # The only rows of K the equations read: their own and the slipping nodes'
        # normal rows (Q - mu P). Gathered once, they serve the matrix, the flat's
        # columns and every right-hand side of this state.
        self.k_rows = body.K.take(np.concatenate([self.rows, self.slip_y]), axis=0)
        self.k_unknown = self.k_rows.take(self.unknown, axis=1)
        self.extra_rows = [total for total, given in ((body.sum_x, self.T_given),
                                                      (body.sum_y, self.N_given)) if given]
        along = np.stack([self.along_x, self.along_y], axis=1)
        self.k_along = self.k_rows @ along
        self.extra_along = [total @ along for total in self.extra_rows]

    # Compliance form: unknown forces Q, P of stuck nodes and P of slipping ones.
    def _compliance_blocks(self) -> None:
        body, ix, iy = self.body, self.body.ix, self.body.iy
        C = body.C
        assert C is not None
        self.rows = np.concatenate([ix[self.stick], iy[self.contact]])
        C_rows = C.take(self.rows, axis=0)
        self.c_stuck = np.hstack([C_rows.take(ix[self.stick], axis=1),
                                  C_rows.take(iy[self.stick], axis=1)])
        self.c_slip_y = C_rows.take(iy[self.slip], axis=1)
        self.c_slip_x = C_rows.take(ix[self.slip], axis=1)
        self.row_along_x = np.zeros(self.rows.size)
        self.row_along_x[: self.n_stick] = 1.0
        self.row_along_y = 1.0 - self.row_along_x


class _Plan:
    """The factorised linear problem of one zone state (either form)."""

    def __init__(self, layout: _Layout, mu: np.ndarray) -> None:
        self.layout = layout
        self.mu_slip = mu[layout.slip]
        self.operator: np.ndarray | None = None  # see keep_operator
        self.uses = 0
        matrix = self._compliance_matrix() if layout.compliance else self._stiffness_matrix()
        self.size = matrix.shape[0]
        # its layout counted in full: a bound (plans of one layout share it)
        self.nbytes = matrix.nbytes + layout.nbytes
        if self.size:
            self.lu, self.piv, info = dgetrf(matrix, overwrite_a=True)
            if info != 0 or not np.isfinite(self.lu).all():
                raise NotConverged("singular zone state")

    def _stiffness_matrix(self) -> np.ndarray:
        layout = self.layout
        rows, first = layout.rows.size, layout.first_slip_row
        M = layout.k_unknown[:rows].copy()
        M[first:] -= self.mu_slip[:, None] * layout.k_unknown[rows:]
        M = np.vstack([M, *(total[layout.unknown] for total in layout.extra_rows)])
        # What the flat's motion does to the equations: a column where it is
        # unknown, a right-hand side term where it is given.
        flat = layout.k_along[:rows].copy()
        flat[first:] -= self.mu_slip[:, None] * layout.k_along[rows:]
        flat = np.vstack([flat, *layout.extra_along])
        self.flat_x, self.flat_y = flat[:, 0].copy(), flat[:, 1].copy()
        if layout.T_given:
            self.flat_x[rows] += layout.machine  # the machine spring on the flat
        columns = [M]
        if layout.dx_unknown:
            columns.append(self.flat_x[:, None])
        if layout.dy_unknown:
            columns.append(self.flat_y[:, None])
        return np.hstack(columns)

    def _equations_of(self, u: np.ndarray) -> np.ndarray:
        """The stiffness form's left-hand sides for the displacements ``u``."""
        layout = self.layout
        force = layout.k_rows @ u  # K @ u at the rows the equations read (u: columns)
        rows = force[: layout.rows.size]
        rows[layout.first_slip_row :] -= self.mu_slip[:, None] * force[layout.rows.size :]
        return np.vstack([rows, *(total @ u for total in layout.extra_rows)])

    def _compliance_matrix(self) -> np.ndarray:
        layout = self.layout
        mu = self.mu_slip
        columns = [layout.c_stuck, layout.c_slip_y + layout.c_slip_x * mu]
        if layout.dx_unknown:
            columns.append(-layout.row_along_x[:, None])
        if layout.dy_unknown:
            columns.append(-layout.row_along_y[:, None])
        M = np.hstack(columns)
        width = M.shape[1]
        n_stick = layout.n_stick
        zeros = np.zeros(n_stick)
        extra = []
        if layout.T_given:
            extra.append(np.concatenate([np.ones(n_stick), zeros, mu]))
        if layout.N_given:
            extra.append(np.concatenate([zeros, np.ones(n_stick), np.ones(mu.size)]))
        padded = [np.pad(row, (0, width - row.size)) for row in extra]
        if layout.T_given and layout.dx_unknown:
            padded[0][2 * n_stick + mu.size] = layout.machine
        return np.vstack([M, *padded]) if padded else M

    def _solve(self, b: np.ndarray) -> np.ndarray:
        if self.size == 0:
            return np.zeros(b.shape)
        z, info = dgetrs(self.lu, self.piv, b)
        if info != 0 or not np.isfinite(z).all():
            raise NotConverged("singular zone state")
        return np.asarray(z)

    def slip_sensitivity(self, pressure: np.ndarray) -> np.ndarray:
        """d(ds_j)/d(mu_i) between the slipping nodes (:meth:`Body.slip_sensitivity`)."""
        layout = self.layout
        body = layout.body
        slipping = layout.slip_x
        m = slipping.size
        p = pressure[slipping]
        # Differentiating Q_i = mu_i P_i leaves the state's own matrix, with P_i as the
        # source of node i's friction equation: one column per slipping node.
        if layout.compliance:
            n_stick = layout.n_stick
            rhs = np.zeros((self.size, m))
            rhs[: layout.rows.size] = -layout.c_slip_x * p
            if layout.T_given:
                rhs[layout.rows.size] = -p
            dz = self._solve(rhs) if m else rhs
            dr = np.zeros((2 * body.n, m))
            dr[layout.stick_x] = dz[:n_stick]
            dr[layout.stick_x + body.n] = dz[n_stick : 2 * n_stick]
            dr[layout.slip_y] = dz[2 * n_stick : 2 * n_stick + m]
            dr[layout.slip_x] = self.mu_slip[:, None] * dr[layout.slip_y] + np.diag(p)
            assert body.C is not None
            du_x = body.C[slipping] @ dr
            k = 2 * n_stick + m
        else:
            rhs = np.zeros((self.size, m))
            rhs[layout.first_slip_row + np.arange(m), np.arange(m)] = p
            dz = self._solve(rhs) if m else rhs
            k = layout.unknown.size
            du = np.zeros((2 * body.n, m))
            du[layout.unknown] = dz[:k]  # a slipping node's ux is an unknown
            du_x = du[slipping]
        if layout.dx_unknown:
            du_x = du_x - dz[k]  # ds = ux - dx - s_prev
        return du_x

    def inputs(self, s_prev: np.ndarray, control: Control) -> np.ndarray:
        """The inputs a solve of this state is affine in.

        1, the stuck nodes' s_prev, then what this state's kind prescribes of dx,
        dy, T and N, in that order.
        """
        return np.concatenate((_ONE, s_prev.take(self.layout.stick_nodes), control.given))

    def keep_operator(self) -> None:
        """Keep the solution as an affine map of :meth:`inputs`.

        A zone state met again is then solved by two products with the map, not by
        the factorisation's substitutions and the assembly around them.
        """
        layout = self.layout
        n_stick = layout.n_stick
        n_given = (int(not layout.dx_unknown) + int(not layout.dy_unknown)
                   + int(layout.T_given) + int(layout.N_given))
        inputs = np.eye(1 + n_stick + n_given)
        inputs[0] = 1.0  # every column carries the constant; unit inputs added to it
        u, dx, dy, r = self.solve_batch(inputs)
        solution = np.vstack([u, dx, dy, r])
        solution[:, 1:] -= solution[:, :1]
        self.operator = solution
        self.nbytes += solution.nbytes

    def solve(self, s_prev: np.ndarray, control: Control
              ) -> tuple[np.ndarray, float, float, np.ndarray]:
        """Displacements, dx, dy and the contact forces for this state and these loads."""
        v = self.inputs(s_prev, control)
        if self.operator is not None:
            y = self.operator @ v
            n2 = 2 * self.layout.body.n
            return y[:n2], float(y[n2]), float(y[n2 + 1]), y[n2 + 2:]
        u, dx, dy, r = self.solve_batch(v[:, None])
        return u[:, 0], float(dx[0]), float(dy[0]), r[:, 0]

    def solve_batch(self, inputs: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """u, dx, dy and r = K u for columns of :meth:`inputs`."""
        layout = self.layout
        body = layout.body
        count = inputs.shape[1]
        n_stick = layout.n_stick
        stuck = inputs[1 : 1 + n_stick]
        given = iter(inputs[1 + n_stick :])
        dx = None if layout.dx_unknown else next(given)
        dy = None if layout.dy_unknown else next(given)
        totals = list(given)
        if layout.compliance:
            b = np.vstack([stuck, -body.g0[layout.contact][:, None] * inputs[:1]])
            if dx is not None:
                b += layout.row_along_x[:, None] * dx
            if dy is not None:
                b += layout.row_along_y[:, None] * dy
            z = self._solve(np.vstack([b, *totals]) if totals else b)
            n_slip = self.mu_slip.size
            r = np.zeros((2 * body.n, count))
            r[layout.stick_x] = z[:n_stick]
            r[layout.stick_x + body.n] = z[n_stick : 2 * n_stick]
            r[layout.slip_y] = z[2 * n_stick : 2 * n_stick + n_slip]
            r[layout.slip_x] = self.mu_slip[:, None] * r[layout.slip_y]
            k = 2 * n_stick + n_slip
            dx = z[k] if dx is None else dx
            dy = z[-1] if dy is None else dy
            assert body.C is not None
            return body.C @ r, dx, dy, r
        base = np.zeros((2 * body.n, count))
        base[layout.stick_x] = stuck
        base[layout.contact_y] = -body.g0[layout.contact][:, None] * inputs[:1]
        b = np.zeros((self.size, count))
        if totals:
            b[self.size - len(totals):] = totals
        b -= self._equations_of(base)
        if dx is not None:
            b -= self.flat_x[:, None] * dx
        if dy is not None:
            b -= self.flat_y[:, None] * dy
        z = self._solve(b)
        k = layout.unknown.size
        dx = z[k] if dx is None else dx
        dy = z[-1] if dy is None else dy
        u = base + layout.along_x[:, None] * dx + layout.along_y[:, None] * dy
        u[layout.unknown] = z[:k]
        return u, dx, dy, body.K @ u
