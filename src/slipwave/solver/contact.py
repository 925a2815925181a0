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

from dataclasses import dataclass

import numpy as np

OPEN, STICK, SLIP = 0, 1, 2

_MAX_ITERATIONS = 60


class NotConverged(Exception):  # noqa: N818 - an internal signal, not an error of the API
    """The active set did not settle, or the linear problem was singular."""


@dataclass
class Control:
    """Prescribed flat motion or total force for one increment.

    Exactly one of ``dx`` / ``T`` and one of ``dy`` / ``N`` is given (forces
    per unit width, N/mm).
    """

    dx: float | None = None
    dy: float | None = None
    T: float | None = None
    N: float | None = None

    def __post_init__(self) -> None:
        if (self.dx is None) == (self.T is None) or (self.dy is None) == (self.N is None):
            raise ValueError("give exactly one of dx/T and one of dy/N")


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
    residual: float


class Body:
    """A body reduced to its contact nodes: stiffness, gaps and the derived scales.

    Parameters
    ----------
    stiffness
        (2n, 2n) stiffness on ``[ux, uy]`` of the contact nodes.
    initial_gap
        g0 (n,), mm.

    """

    def __init__(self, stiffness: np.ndarray, initial_gap: np.ndarray) -> None:
        self.K = np.ascontiguousarray(stiffness, dtype=np.float64)
        self.n = initial_gap.size
        if self.K.shape != (2 * self.n, 2 * self.n):
            raise ValueError("stiffness must be (2n, 2n) for n contact nodes")
        self.g0 = np.asarray(initial_gap, dtype=np.float64)
        self.ix = np.arange(self.n)
        self.iy = self.n + self.ix
        diagonal = np.diag(self.K)
        self.cx = diagonal[self.ix]  # augmentation: the nodes' own stiffness
        self.cy = diagonal[self.iy]
        self.sum_x = self.K[self.ix].sum(axis=0)  # sum Q = sum_x @ u
        self.sum_y = self.K[self.iy].sum(axis=0)

    def solve_linear(
        self,
        state: np.ndarray,
        mu: np.ndarray,
        s_prev: np.ndarray,
        control: Control,
    ) -> tuple[np.ndarray, float, float]:
        """Displacements and flat position for a fixed zone state.

        ``mu`` is the signed friction coefficient of slipping nodes (``Q = mu P``).
        """
        K, ix, iy = self.K, self.ix, self.iy
        contact = state != OPEN
        stick = state == STICK
        slip = state == SLIP
        opened = ~contact
        unknown = np.concatenate([ix[slip | opened], iy[opened]])
        base = np.zeros(2 * self.n)
        base[ix[stick]] = s_prev[stick]
        base[iy[contact]] = -self.g0[contact]
        along_x = np.zeros(2 * self.n)
        along_x[ix[stick]] = 1.0
        along_y = np.zeros(2 * self.n)
        along_y[iy[contact]] = 1.0

        rows = [K[ix[opened]], K[iy[opened]], K[ix[slip]] - mu[slip, None] * K[iy[slip]]]
        rhs = [np.zeros(2 * int(opened.sum()) + int(slip.sum()))]
        if control.T is not None:
            rows.append(self.sum_x[None])
            rhs.append(np.array([control.T]))
        if control.N is not None:
            rows.append(self.sum_y[None])
            rhs.append(np.array([control.N]))
        R = np.concatenate(rows)
        b = np.concatenate(rhs) - R @ base
        columns = [R[:, unknown]]
        if control.dx is None:
            columns.append((R @ along_x)[:, None])
        else:
            b -= control.dx * (R @ along_x)
        if control.dy is None:
            columns.append((R @ along_y)[:, None])
        else:
            b -= control.dy * (R @ along_y)
        M = np.concatenate(columns, axis=1)
        if M.shape[0] == 0:
            z = np.zeros(0)
        else:
            try:
                z = np.linalg.solve(M, b)
            except np.linalg.LinAlgError as err:
                raise NotConverged("singular zone state") from err
            if not np.isfinite(z).all():
                raise NotConverged("singular zone state")
        k = unknown.size
        dx = control.dx if control.dx is not None else float(z[k])
        dy = control.dy if control.dy is not None else float(z[-1])
        u = base + dx * along_x + dy * along_y
        u[unknown] = z[:k]
        return u, dx, dy

    def solve_increment(
        self,
        control: Control,
        s_prev: np.ndarray,
        static: float,
        dynamic: float,
        guess: np.ndarray | None = None,
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
        guess
            Zone state to start from (the previous increment's, usually).

        Raises
        ------
        NotConverged
            When the active set cycles or the linear problem is singular; the
            caller may sub-step.

        """
        n = self.n
        cascade = static > dynamic
        state = np.full(n, STICK, dtype=np.int8) if guess is None else guess.astype(np.int8)
        # Every increment starts stuck: the interface heals (fs > fd), and a stuck
        # predictor finds the slipping nodes with their new directions in one pass.
        state[state == SLIP] = STICK
        in_wave = np.zeros(n, dtype=bool)
        round_slipped = np.full(n, -1, dtype=np.int16)
        sign = np.ones(n)
        iterations = 0
        rounds = 0
        while True:
            # Nodes outside the wave may slip only without a cascade (fs == fd).
            limit = np.where(in_wave, dynamic, static)
            may_slip = in_wave | (not cascade)
            seen: set[bytes] = set()
            for _ in range(_MAX_ITERATIONS):
                iterations += 1
                mu = limit * sign
                u, dx, dy = self.solve_linear(state, mu, s_prev, control)
                r = self.K @ u
                P, Q = r[self.iy], r[self.ix]
                gap = self.g0 + u[self.iy] - dy
                ds = u[self.ix] - dx - s_prev
                pressure = P - self.cy * gap
                trial = Q - self.cx * ds
                new = np.where(pressure > 0, STICK, OPEN).astype(np.int8)
                bound = limit * np.maximum(pressure, 0.0)
                slipping = (new == STICK) & may_slip & (np.abs(trial) > bound)
                new[slipping] = SLIP
                if control.dx is None and not (new == STICK).any() and slipping.any():
                    # Under load control a state without a stuck node leaves dx
                    # undetermined; keep the least overloaded node stuck. If the
                    # contact truly cannot carry T, the iteration fails and the
                    # caller finds gross sliding.
                    excess = np.where(slipping, np.abs(trial) - bound, np.inf)
                    new[np.argmin(excess)] = STICK
                    slipping = new == SLIP
                new_sign = np.where(slipping, np.sign(trial), sign)
                if np.array_equal(new, state) and np.array_equal(new_sign, sign):
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
                        limit = np.where(in_wave, dynamic, static)
                        may_slip = in_wave
                    new[flipping] = SLIP
                    new_sign[flipping] = np.where(trial[flipping] < 0, -1.0, 1.0)
                    seen.clear()
                seen.add(key)
                state, sign = new, new_sign
            else:
                raise NotConverged(f"active set still changing after {_MAX_ITERATIONS} iterations")
            if not cascade:
                wave = state == SLIP
                round_slipped[wave] = 0
                break
            over = (state == STICK) & ~in_wave & (np.abs(Q) > static * P * (1 + 1e-12))
            if not over.any():
                break
            in_wave |= over
            round_slipped[over] = rounds
            rounds += 1
            # The overloaded nodes start slipping the way their load pushes them.
            state[over] = SLIP
            sign[over] = np.sign(Q[over])

        limit = np.where(in_wave, dynamic, static)
        residual = self.residual(P, Q, gap, ds, limit, control)
        direction = np.where(state == SLIP, np.sign(ds), 0).astype(np.int8)
        return Increment(u=u, r=r, dx=dx, dy=dy, state=state, direction=direction,
                         round_slipped=round_slipped, iterations=iterations, residual=residual)

    def residual(
        self,
        P: np.ndarray,
        Q: np.ndarray,
        gap: np.ndarray,
        ds: np.ndarray,
        limit: np.ndarray,
        control: Control,
    ) -> float:
        """Relative complementarity residual: zero for an exact solution.

        Normal: ``min(P, c g)``; tangential: ``Q - proj_[-f P+, f P+](Q - c ds)``
        (Alart-Curnier); controls: the prescribed totals. Scaled by ``max |P|``.
        """
        positive = np.maximum(P, 0.0)
        normal = np.minimum(P, self.cy * gap)
        bound = limit * positive
        tangential = Q - np.clip(Q - self.cx * ds, -bound, bound)
        totals = [0.0]
        if control.T is not None:
            totals.append(abs(Q.sum() - control.T))
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
        """
        if guess is None:
            state = np.where(self.g0 <= 0, SLIP, OPEN).astype(np.int8)
        else:
            state = np.where(guess == OPEN, OPEN, SLIP).astype(np.int8)
        mu = np.full(self.n, dynamic)
        sliding = Control(dx=dx_floor, dy=control.dy, N=control.N)
        seen: set[bytes] = set()
        for _ in range(_MAX_ITERATIONS):
            u, dx, dy = self.solve_linear(state, mu, s_prev, sliding)
            r = self.K @ u
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
        residual = self.residual(P, Q, gap, ds, np.full(self.n, dynamic), sliding)
        wave = np.where(state == SLIP, 0, -1).astype(np.int16)
        return Increment(u=u, r=r, dx=dx, dy=dy, state=state,
                         direction=np.where(state == SLIP, np.sign(ds), 0).astype(np.int8),
                         round_slipped=wave, iterations=1, residual=residual)
