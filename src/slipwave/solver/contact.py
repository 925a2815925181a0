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
augmented multipliers, until it no longer changes. The loop is compiled
(:mod:`slipwave.solver.active_set`): it solves each guess with a kept inverse,
updated as nodes change zone rather than factorised again.

With a static coefficient above the dynamic one the increment is a cascade:
every node starts stuck (the interface heals), nodes loaded beyond ``fs P``
start slipping and from then on obey ``fd``; their shed load may push others
beyond ``fs``, which join in the next round, until none does. The nodes that
slipped form the increment's wave.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from slipwave.errors import SlipwaveError
from slipwave.solver import active_set
from slipwave.solver.active_set import COUNTERS, OPEN, SLIP, STICK, Flat

__all__ = ["OPEN", "SLIP", "STICK", "Body", "Control", "Increment", "NotConverged",
           "Weakening"]

_NO_WEAKENING = np.zeros(0)


class NotConverged(Exception):  # noqa: N818 - an internal signal, not an error of the API
    """The active set did not settle, or the linear problem was singular."""


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
    flat: Flat = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if (self.dx is None) == (self.T is None) or (self.dy is None) == (self.N is None):
            raise SlipwaveError("give exactly one of dx/T and one of dy/N")
        # the compiled kernels' form, made once: read at every solve of the increment
        object.__setattr__(self, "flat", active_set.flat(self.dx, self.dy, self.T, self.N,
                                                         self.machine))


@dataclass(frozen=True)
class Weakening:
    """Linear slip-weakening of a slipping node's coefficient over its slip in the wave.

    ``fs - (fs - fd) min(slip / dc, 1)``, held within the increment's [fd, fs]
    (a run-in's static coefficient of the moment bounds it).
    """

    fs: float
    fd: float
    dc: float


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
    r_before: np.ndarray | None = None
    dx_before: float = 0.0
    substeps: int = 1


class Body:
    """A body reduced to its contact nodes: stiffness, gaps and the kept zone state.

    Parameters
    ----------
    stiffness
        (2n, 2n) stiffness on ``[ux, uy]`` of the contact nodes.
    initial_gap
        g0 (n,), mm.

    """

    def __init__(self, stiffness: np.ndarray, initial_gap: np.ndarray) -> None:
        self.n = initial_gap.size
        if stiffness.shape != (2 * self.n, 2 * self.n):
            raise SlipwaveError("stiffness must be (2n, 2n) for n contact nodes")
        self.zones = active_set.zone_solver(stiffness, initial_gap)
        self.K = self.zones.K
        self.g0 = self.zones.g0
        # the x and y displacements' places in [ux, uy]: slices, so reading them copies nothing
        self.ix = slice(0, self.n)
        self.iy = slice(self.n, 2 * self.n)
        self.cy = np.diag(self.K)[self.iy].copy()  # augmentation: the nodes' own stiffness
        self.sum_x = self.zones.sum_x  # sum Q = sum_x @ u
        self.sum_y = self.zones.sum_y
        self._stuck = np.full(self.n, STICK, dtype=np.int8)  # a guess: every node stuck
        self._forward = np.ones(self.n)  # friction signs: every one forward

    def restart(self) -> None:
        """Every node stuck again and nothing factorised, as the body was made."""
        active_set.restart(self.zones)

    def work(self) -> dict[str, int]:
        """What the kept zone state has done so far (as ``cache_info``).

        Returns
        -------
        dict
            Its present size (free displacements), then counts of solves,
            displacements freed and fixed again, rows changed (slipping
            coefficients), rebuilds from scratch and refinements.

        """
        return dict(zip(COUNTERS, self.zones.counts.tolist(), strict=True))

    def solve_linear(
        self,
        state: np.ndarray,
        mu: np.ndarray,
        s_prev: np.ndarray,
        control: Control,
    ) -> tuple[np.ndarray, float, float]:
        """Displacements and flat position for a fixed zone state.

        ``mu`` is the signed friction coefficient of slipping nodes (``Q = mu P``).

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

        Parameters
        ----------
        state, mu, s_prev, control
            As in :meth:`solve_linear`.

        Returns
        -------
        tuple
            Contact displacements, flat x and y positions, contact forces.

        Raises
        ------
        NotConverged
            If the state's linear problem is singular.

        """
        active_set.set_base(self.zones, np.asarray(s_prev, dtype=np.float64))
        self._move_to(state, mu)
        u, r = np.empty(2 * self.n), np.empty(2 * self.n)
        dx, dy, regular = active_set.solve(self.zones, control.flat, u, r)
        if not regular:
            raise NotConverged("singular zone state")
        return u, dx, dy, r

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
        state's kept inverse (a column per slipping node), which gives
        slip-weakening's fixed point a Newton step.

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
        state = self._move_to(state, mu)
        return active_set.slip_sensitivity(self.zones, control.flat, state,
                                           np.asarray(pressure, dtype=np.float64))

    def _move_to(self, state: np.ndarray, mu: np.ndarray) -> np.ndarray:
        state = np.asarray(state, dtype=np.int8)
        if not active_set.move_to(self.zones, state, np.asarray(mu, dtype=np.float64)):
            raise NotConverged("singular zone state")
        return state

    def solve_increment(
        self,
        control: Control,
        s_prev: np.ndarray,
        static: float,
        dynamic: float,
        guess: np.ndarray | None = None,
        guess_sign: np.ndarray | None = None,
        weakening: Weakening | None = None,
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
            With fs > fd, a slipping node's coefficient falls with its slip in the
            increment's wave from ``static`` towards ``dynamic`` (slip-weakening).
            ``None``: the coefficient drops to ``dynamic`` as soon as the node slips
            (Coulomb).

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
        weakening: Weakening | None = None,
    ) -> Increment:
        n = self.n
        s_prev = np.asarray(s_prev, dtype=np.float64)
        law = (_NO_WEAKENING if weakening is None else
               np.array([weakening.fs, weakening.fd, weakening.dc], dtype=np.float64))
        # (read, not written, by the kernel: no copies)
        start = self._stuck if guess is None else np.asarray(guess, dtype=np.int8)
        start_sign = (self._forward if guess_sign is None
                      else np.asarray(guess_sign, dtype=np.float64))
        u, r, u_before, r_before = np.empty((4, 2 * n))
        state, direction = np.empty(n, dtype=np.int8), np.empty(n, dtype=np.int8)
        sign = np.empty(n)
        round_slipped = np.empty(n, dtype=np.int16)
        scalars = np.empty(5)
        status = active_set.iterate(*self.zones, *control.flat, s_prev, float(static),
                                    float(dynamic), law, start, start_sign, heal, u, r,
                                    u_before, r_before, state, sign, direction, round_slipped,
                                    scalars)
        if status != active_set.CONVERGED:
            raise NotConverged(active_set.FAILURES[status])
        dx, dy, dx_before, residual, iterations = scalars.tolist()
        return Increment(u=u, r=r, dx=dx, dy=dy, state=state, direction=direction,
                         round_slipped=round_slipped, iterations=int(iterations),
                         residual=residual, sign=sign, u_before=u_before,
                         r_before=r_before, dx_before=dx_before)

    def residual(
        self,
        u: np.ndarray,
        r: np.ndarray,
        dx: float,
        dy: float,
        s_prev: np.ndarray,
        limit: np.ndarray,
        control: Control,
    ) -> float:
        """Relative complementarity residual: zero for an exact solution.

        Normal: ``min(P, c g)``; tangential: ``Q - proj_[-f P+, f P+](Q - c ds)``
        (Alart-Curnier); controls: the prescribed totals. Scaled by ``max |P|``.

        Parameters
        ----------
        u, r
            Displacements and contact forces.
        dx, dy
            The flat's position.
        s_prev
            Relative tangential positions at the end of the previous increment.
        limit
            Friction coefficient of each node.
        control
            What is imposed on the flat.

        Returns
        -------
        float
            The largest violation relative to the load scale.

        """
        return float(active_set.residual(self.zones, control.flat, u, r, float(dx), float(dy),
                                     np.asarray(s_prev, dtype=np.float64),
                                     np.asarray(limit, dtype=np.float64)))

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

        Raises
        ------
        NotConverged
            If the contact's extent does not settle, or a state is singular.

        """
        if guess is None:
            state = np.where(self.g0 <= 0, SLIP, OPEN).astype(np.int8)
        else:
            state = np.where(guess == OPEN, OPEN, SLIP).astype(np.int8)
        mu = np.full(self.n, dynamic)
        sliding = Control(dx=dx_floor, dy=control.dy, N=control.N)
        seen: set[bytes] = set()
        for _ in range(active_set.MAX_ITERATIONS):
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
        ds = u[self.ix] - dx - s_prev
        residual = self.residual(u, r, dx, dy, s_prev, np.full(self.n, dynamic), sliding)
        wave = np.where(state == SLIP, 0, -1).astype(np.int16)
        return Increment(u=u, r=r, dx=dx, dy=dy, state=state,
                         direction=np.where(state == SLIP, np.sign(ds), 0).astype(np.int8),
                         round_slipped=wave, iterations=1, residual=residual,
                         sign=np.ones(self.n))
