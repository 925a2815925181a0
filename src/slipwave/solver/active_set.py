"""The active set of one increment, compiled: zone states, their kept inverse, the cascade.

A zone state (each contact node open, stuck or slipping with a signed coefficient
``mu``) leaves some displacements free: ``ux`` of slipping and open nodes, ``uy`` of
open ones. Each free displacement has its own equation: ``r = 0`` for an open node's
two, ``r_x - mu r_y = 0`` (``Q = mu P``) for a slipping node's ``ux``. The stuck
nodes' ``ux`` follow the flat (``s_prev + dx``) and the contact nodes' ``uy`` its
approach (``dy - g0``). With ``r = K u``, the free displacements solve ``M z = b``,
``M`` the equations' rows of ``K`` at the free columns, and the flat's unknown motion
(``dx`` under a prescribed T, ``dy`` under a prescribed N) is eliminated through a
Schur complement of at most 2 x 2.

The inverse of ``M`` is kept between solves. A node changing zone adds or removes
one or two free displacements (a bordered inverse, or its reduction: O(m^2) for m
free displacements), and a slipping node's new coefficient changes one row
(Sherman-Morrison, O(m^2)); the increment's active set, which changes a few nodes
per iteration, then never factorises. Each solve checks its residual: above
:data:`REFINE_ABOVE` (or :data:`ACCURACY_MARGIN` times what a freshly formed inverse
reached on the state, when that is more) it takes a step of iterative refinement, and
if that is not enough the inverse is formed again from scratch (Gaussian elimination),
as it is whenever that is cheaper than the updates or an update meets a vanishing
pivot. A state that is singular (no inverse) is reported as such, never solved.

The increment's loop (:func:`iterate`: the algorithm of
:meth:`slipwave.solver.contact.Body.solve_increment`, whose docstring and module
describe it) runs on this kept inverse: each iteration moves it to the new guess by
low-rank updates, O(m^2) each, and solves it by the kept responses and one product
with the free columns of the stiffness, O(n m) for m free displacements of n nodes.

The cascade keeps its order: nodes join the wave round by round, those loaded
beyond ``fs P`` by the previous round's slip, and within a round the active set
settles before the next round is looked for. Where a law's result depends on the
order in which nodes slip (Coulomb with fs > fd, slip-weakening), this is the
order, as before the solver was compiled.

Everything here is compiled by numba (``cache=True``: once per machine, kept on disk
beside the module). It is one module because numba's cache of a function does not
follow changes to the functions it calls in other modules.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, types

OPEN, STICK, SLIP = 0, 1, 2

# The dot products' sums may be reordered (vectorised); NaN and infinities keep their
# meaning, which the checks of singular states read. Only where it pays: it lengthens
# the compilation.
FAST = {"reassoc", "contract"}

REFINE_ABOVE = 1e-12
"""Relative residual of a solve (scaled by the largest contact force) above which it
is refined: a few hundred times rounding, far below the solver's 1e-8 tolerance."""

ACCURACY_MARGIN = 10.0
"""A solve is refined above this many times the residual that a freshly formed inverse
reached (when that exceeds :data:`REFINE_ABOVE`): on an ill-conditioned zone state (a
tall slab on a fine mesh) no update can beat a fresh inverse, and forming one again
at every solve (O(m^3)) bought nothing."""

ACCURACY_CAP = 1e-10
"""The largest residual of a fresh inverse taken as the body's accuracy (refinement
then aims at 1e-9, ten times below the increments' tolerance)."""

# counters of ZoneSolver.counts (PENDING: the rank-one terms not yet added to the inverse)
SIZE, SOLVES, ADDED, REMOVED, ROWS_CHANGED, REBUILDS, REFINEMENTS, INCREMENTS, PENDING = \
    range(9)
COUNTERS = ("size", "solves", "added", "removed", "rows changed", "rebuilds", "refinements",
            "increments", "pending")
PENDING_TERMS = 8
"""Rank-one terms of the bordered inverse's updates kept aside before they are added to
it in one pass: a free displacement added costs one read of the inverse, not a read
and a rewrite."""
ROW_CHANGE_COST = 1.7
"""A row's new coefficient (Sherman-Morrison) in units of m^2 of :func:`move_to`'s cost
model, where a free displacement added or removed is 4 m^2: measured inside compiled
code, 70 rows changed at m 90 took 0.16 ms (45 at m 65: 0.06 ms). A cascade changes
the coefficient of every node in its wave, and slip-weakening at each of its steps."""
REBUILD_COST = 1.0
"""A rebuild (M formed and inverted by LAPACK, its known products made afresh) in units
of m^3 of the same model, plus 12 n^2. Set on slip-weakening runs, where most rebuilds
and row changes are (40 random laws at 80 elements, 4 at 160): 0.6, 1.0, 1.2 and 1.4
took 7.7, 7.2, 7.3 and 7.4 s at 80 elements, 5.9, 5.8, 6.3 and 7.2 s at 160. (Timed
alone, a rebuild at n 161 cost as much as 26 row changes at m 80 and 60 at m 170.)"""
# The known displacements' product is updated by the nodes whose s_prev moved, and
# made afresh every this many increments: the updates' rounding does not build up.
_REFRESH_EVERY = 256


class ZoneSolver(NamedTuple):
    """A body's stiffness and the kept inverse of its present zone state's matrix.

    Made by :func:`zone_solver`; the kernels update it in place.

    Attributes
    ----------
    K
        (2n, 2n) stiffness on ``[ux, uy]`` of the contact nodes.
    KT
        Its transpose, contiguous: row d is column d of K.
    g0
        Initial gaps (n,).
    sum_x, sum_y
        Sums of K's x and y rows (2n,): ``sum Q = sum_x @ u``, ``sum P = sum_y @ u``.
    inverse
        (2n, 2n); its leading m x m block plus the pending terms' products is the
        inverse of M.
    columns
        (2n, 2n); row p is the column of K of free displacement p.
    coefficient
        (2n,): free displacement p's equation is ``K[d_p] - coefficient_p K[n + d_p]``.
    known
        (3, 2n): ``K @ v`` for v the known displacements' values without the flat's
        motion (``s_prev`` of stuck x, ``-g0`` of contact y), for v the indicator of
        the stuck x and for v that of the contact y.
    base
        (2n,): ``[s_prev, -g0]``, the known displacements' values before the flat's.
    dofs
        (2n,): the free displacements' indices in ``[ux, uy]``.
    position
        (2n,): each displacement's place among the free ones, -1 if known.
    counts
        Counters (:data:`COUNTERS`); ``counts[SIZE]`` is m.
    pending_u, pending_v
        (:data:`PENDING_TERMS`, 2n): the first ``counts[PENDING]`` rows are rank-one
        terms ``u v^T`` of the inverse not yet added to ``inverse`` (zero from m on).
    responses
        (3, 2n): the inverse times each known product's part in the equations
        (:func:`_flat_terms`), kept along with the inverse: a solve is then O(n m)
        products, no pass over the inverse.
    accuracy
        (1,): the relative residual that the last inverse formed afresh for accuracy
        reached, refined, when that missed the aim (0 before any): what refinement
        can aim at on this body (:data:`ACCURACY_MARGIN`).

    """

    K: np.ndarray
    KT: np.ndarray
    g0: np.ndarray
    sum_x: np.ndarray
    sum_y: np.ndarray
    inverse: np.ndarray
    columns: np.ndarray
    coefficient: np.ndarray
    known: np.ndarray
    base: np.ndarray
    dofs: np.ndarray
    position: np.ndarray
    counts: np.ndarray
    pending_u: np.ndarray
    pending_v: np.ndarray
    responses: np.ndarray
    accuracy: np.ndarray


class Flat(NamedTuple):
    """What a solve prescribes of the flat (the compiled form of a ``Control``).

    ``values`` holds dx, dy, T, N and the machine's stiffness (NaN where not given);
    ``dx_unknown`` and ``dy_unknown`` say which motion is solved for (T, N given).
    """

    values: np.ndarray
    dx_unknown: bool
    dy_unknown: bool


def zone_solver(stiffness: np.ndarray, initial_gap: np.ndarray) -> ZoneSolver:
    """A :class:`ZoneSolver` for a body, its zone state every node stuck.

    Parameters
    ----------
    stiffness
        (2n, 2n) stiffness on ``[ux, uy]`` of the contact nodes.
    initial_gap
        g0 (n,), mm.

    Returns
    -------
    ZoneSolver
        No free displacement yet: every node stuck, nothing factorised.

    """
    K = np.ascontiguousarray(stiffness, dtype=np.float64)
    n2 = K.shape[0]
    KT = np.ascontiguousarray(K.T)
    g0 = np.asarray(initial_gap, dtype=np.float64)
    solver = ZoneSolver(
        K=K, KT=KT, g0=g0,
        sum_x=K[: n2 // 2].sum(axis=0), sum_y=K[n2 // 2 :].sum(axis=0),
        inverse=np.zeros((n2, n2)), columns=np.zeros((n2, n2)), coefficient=np.zeros(n2),
        known=np.zeros((3, n2)), base=np.concatenate([np.zeros(g0.size), -g0]),
        dofs=np.zeros(n2, dtype=np.int64),
        position=np.full(n2, -1, dtype=np.int64),
        counts=np.zeros(len(COUNTERS), dtype=np.int64),
        pending_u=np.zeros((PENDING_TERMS, n2)), pending_v=np.zeros((PENDING_TERMS, n2)),
        responses=np.zeros((3, n2)), accuracy=np.zeros(1))
    _refresh_known(solver)
    return solver


def restart(solver: ZoneSolver) -> None:
    """Put a :class:`ZoneSolver` back, in place, to the state :func:`zone_solver` makes.

    Every node stuck and nothing factorised, as a new one would be, to the bit: a
    process that simulates one slab many times (a map row, a fit) keeps its solver
    and restarts it rather than allocate and zero another. The inverse and the free
    displacements' columns are left as they are: the kernels write each entry of
    the present size's block before they read it.

    Parameters
    ----------
    solver
        Its stiffness and gaps are kept; its zone state is reset.

    """
    n2 = solver.K.shape[0]
    for kept in (solver.coefficient, solver.dofs, solver.counts, solver.pending_u,
                 solver.pending_v, solver.responses, solver.accuracy):
        kept.fill(0)
    solver.position.fill(-1)
    solver.base[: n2 // 2] = 0.0
    solver.base[n2 // 2 :] = -solver.g0
    _refresh_known(solver)


def flat(dx: float | None, dy: float | None, T: float | None, N: float | None,
         machine: float) -> Flat:
    """The compiled kernels' form of what is prescribed of the flat.

    Parameters
    ----------
    dx, dy, T, N
        As in :class:`~slipwave.solver.contact.Control` (``None``: not given).
    machine
        The machine's stiffness between the actuator and the flat.

    Returns
    -------
    Flat
        The values, NaN where not given.

    """
    values = np.array([np.nan if v is None else v for v in (dx, dy, T, N)] + [machine])
    return Flat(values, dx is None, dy is None)


# ----------------------------------------------------------------------------------
# The kept inverse and its updates


@njit(cache=True)
def _copy(destination: np.ndarray, source: np.ndarray) -> None:
    """``destination[:] = source`` for 1-d arrays, as a loop (cheaper to compile)."""
    for k in range(source.size):
        destination[k] = source[k]


@njit(cache=True)
def _slipping(state: np.ndarray) -> np.ndarray:
    """Indices of the slipping nodes, in order."""
    count = 0
    for i in range(state.size):
        count += state[i] == SLIP
    nodes = np.empty(count, dtype=np.int64)
    k = 0
    for i in range(state.size):
        if state[i] == SLIP:
            nodes[k] = i
            k += 1
    return nodes


@njit(cache=True)
def _equation_entry(K: np.ndarray, dof: int, coefficient: float, column: int) -> float:
    """Entry of free displacement ``dof``'s equation at displacement ``column``."""
    value = K[dof, column]
    if coefficient != 0.0:
        value -= coefficient * K[K.shape[0] // 2 + dof, column]
    return value


@njit(cache=True)
def _known_values(base: np.ndarray, dof: int) -> np.ndarray:
    """A known displacement's value in each known product: its base, x or y indicator."""
    values = np.zeros(3)
    values[0] = base[dof]
    values[1 if dof < base.size // 2 else 2] = 1.0
    return values


@njit(cache=True)
def _row_terms(known: np.ndarray, dof: int, coefficient: float) -> np.ndarray:
    """Equation ``K[dof] - coefficient K[n + dof]`` applied to each known product."""
    n = known.shape[1] // 2
    terms = np.empty(3)
    for k in range(3):
        terms[k] = known[k, dof]
        if coefficient != 0.0:
            terms[k] -= coefficient * known[k, n + dof]
    return terms


@njit(cache=True)
def _refresh_responses(s: ZoneSolver) -> None:
    """The responses afresh: one pass over the inverse."""
    m = s.counts[SIZE]
    solved = _apply_inverse(s, _flat_terms(s, m), 3, m)
    for k in range(3):
        for p in range(m):
            s.responses[k, p] = solved[k, p]


@njit(cache=True)
def _release(KT: np.ndarray, known: np.ndarray, base: np.ndarray, dof: int,
             sign: float) -> None:
    """Take displacement ``dof`` out of the known ones (sign -1) or back in (+1).

    (The solver's arrays are passed one by one, here as in the other small kernels
    called on every iteration: a call taking the whole :class:`ZoneSolver`
    reference-counts each of its arrays on the way in and out.)
    """
    n2 = base.size
    which = 1 if dof < n2 // 2 else 2
    value = base[dof]
    for k in range(n2):
        known[0, k] += sign * value * KT[dof, k]
        known[which, k] += sign * KT[dof, k]


@njit(cache=True, fastmath=FAST)
def _flush(s: ZoneSolver) -> None:
    """Add the pending rank-one terms to the kept inverse, in one pass over it."""
    count = s.counts[PENDING]
    if count == 0:
        return
    m = s.counts[SIZE]
    B = s.inverse
    V = s.pending_v
    for a in range(m):
        for j in range(count):
            factor = s.pending_u[j, a]
            if factor != 0.0:
                for b in range(m):
                    B[a, b] += factor * V[j, b]
    s.counts[PENDING] = 0


@njit(cache=True, fastmath=FAST)
def _add(s: ZoneSolver, dof: int, coefficient: float) -> bool:
    """Free displacement ``dof`` with its equation: the bordered inverse, O(m^2).

    False (nothing changed) when the new matrix's pivot vanishes.
    """
    m = s.counts[SIZE]
    B = s.inverse
    K = s.K
    column = np.empty(m)  # the present equations at the new column
    row = np.empty(m)  # the new equation at the present columns
    n = s.g0.size
    along = s.KT[dof]  # column dof of K, read along a row
    for p in range(m):
        d = s.dofs[p]
        c = s.coefficient[p]
        column[p] = along[d] - c * along[n + d] if c != 0.0 else along[d]
        row[p] = K[dof, d] - coefficient * K[n + dof, d] if coefficient != 0.0 else K[dof, d]
    corner = _equation_entry(K, dof, coefficient, dof)
    B_column = np.zeros(m)
    row_B = np.zeros(m)
    for a in range(m):
        total = 0.0
        for b in range(m):
            total += B[a, b] * column[b]
            row_B[b] += row[a] * B[a, b]
        B_column[a] = total
    for j in range(s.counts[PENDING]):  # the pending terms' part of the products
        u, v = s.pending_u[j], s.pending_v[j]
        v_column = 0.0
        row_u = 0.0
        for a in range(m):
            v_column += v[a] * column[a]
            row_u += row[a] * u[a]
        for a in range(m):
            B_column[a] += u[a] * v_column
            row_B[a] += row_u * v[a]
    pivot = corner
    scale = abs(corner)
    for a in range(m):
        pivot -= row[a] * B_column[a]
        scale += abs(row[a] * B_column[a])
    if not (np.isfinite(pivot) and abs(pivot) > 1e-14 * scale):
        return False
    # the responses: the bordered inverse applied to the terms, which lose the new
    # column times the displacement's known value (it is free now) and gain a row
    values = _known_values(s.base, dof)
    row_responses = np.zeros(3)
    for k in range(3):
        for p in range(m):
            row_responses[k] += row[p] * s.responses[k, p]
    if s.counts[PENDING] == PENDING_TERMS:
        _flush(s)
    # the old block gains (B column)(row B) / pivot: a pending term
    k = s.counts[PENDING]
    u, v = s.pending_u[k], s.pending_v[k]
    for a in range(m):
        u[a] = B_column[a] / pivot
        v[a] = row_B[a]
        B[a, m] = -u[a]
        B[m, a] = -row_B[a] / pivot
    for a in range(m, u.size):
        u[a] = v[a] = 0.0
    s.counts[PENDING] = k + 1
    B[m, m] = 1.0 / pivot
    s.dofs[m] = dof
    s.coefficient[m] = coefficient
    s.position[dof] = m
    _copy(s.columns[m], s.KT[dof])
    s.counts[SIZE] = m + 1
    s.counts[ADDED] += 1
    _release(s.KT, s.known, s.base, dof, -1.0)
    new_terms = _row_terms(s.known, dof, coefficient)
    for k in range(3):
        w = (new_terms[k] + values[k] * corner - row_responses[k]) / pivot
        y = s.responses[k]
        for p in range(m):
            y[p] -= B_column[p] * w
        y[m] = w - values[k]
    return True


@njit(cache=True)
def _remove(s: ZoneSolver, p: int) -> bool:
    """Fix free displacement ``p`` again (its equation leaves too): O(m^2).

    The last free displacement takes its place. False (nothing changed) when the
    reduced matrix is singular.
    """
    _flush(s)
    m = s.counts[SIZE]
    B = s.inverse
    last = m - 1
    if B[p, p] == 0.0 or not np.isfinite(B[p, p]):
        return False
    if p != last:  # swap p and last, in the inverse's rows and columns and the lists
        for k in range(m):
            B[p, k], B[last, k] = B[last, k], B[p, k]
        for k in range(m):
            B[k, p], B[k, last] = B[k, last], B[k, p]
        s.dofs[p], s.dofs[last] = s.dofs[last], s.dofs[p]
        s.coefficient[p], s.coefficient[last] = s.coefficient[last], s.coefficient[p]
        for k in range(3):
            s.responses[k, p], s.responses[k, last] = s.responses[k, last], s.responses[k, p]
        s.position[s.dofs[p]] = p
        for k in range(s.columns.shape[1]):
            s.columns[p, k], s.columns[last, k] = s.columns[last, k], s.columns[p, k]
    pivot = B[last, last]
    dof = s.dofs[last]
    # the responses of the reduced inverse, the terms gaining the fixed column
    values = _known_values(s.base, dof)
    for k in range(3):
        y = s.responses[k]
        w = (y[last] + values[k]) / pivot
        for a in range(last):
            y[a] -= B[a, last] * w
    for a in range(last):
        factor = B[a, last] / pivot
        for b in range(last):
            B[a, b] -= factor * B[last, b]
    s.position[dof] = -1
    s.counts[SIZE] = last
    s.counts[REMOVED] += 1
    _release(s.KT, s.known, s.base, dof, 1.0)
    return True


@njit(cache=True)
def _change_row(s: ZoneSolver, p: int, coefficient: float) -> bool:
    """A slipping node's new coefficient (or none: opened): Sherman-Morrison, O(m^2)."""
    _flush(s)
    m = s.counts[SIZE]
    n = s.g0.size
    B = s.inverse
    dof = s.dofs[p]
    change = s.coefficient[p] - coefficient  # the row gains change * K[n + dof]
    delta = np.empty(m)
    for b in range(m):
        delta[b] = change * s.K[n + dof, s.dofs[b]]
    delta_B = np.zeros(m)
    for a in range(m):
        for b in range(m):
            delta_B[b] += delta[a] * B[a, b]
    column = np.empty(m)
    for a in range(m):
        column[a] = B[a, p]
    denominator = 1.0 + delta_B[p]
    if not (np.isfinite(denominator) and abs(denominator) > 1e-14):
        return False
    # the responses: row p's term changes with its coefficient
    for k in range(3):
        y = s.responses[k]
        product = 0.0
        for b in range(m):
            product += delta[b] * y[b]
        w = (change * s.known[k, n + dof] - product) / denominator
        for a in range(m):
            y[a] += column[a] * w
    for a in range(m):
        factor = column[a] / denominator
        for b in range(m):
            B[a, b] -= factor * delta_B[b]
    s.coefficient[p] = coefficient
    s.counts[ROWS_CHANGED] += 1
    return True


@njit(cache=True)
def _refresh_known(s: ZoneSolver) -> None:
    """``known`` from scratch, for the present free displacements and ``base``."""
    n2 = s.K.shape[0]
    n = n2 // 2
    known = s.known
    for k in range(n2):
        known[0, k] = known[1, k] = known[2, k] = 0.0
    for d in range(n2):
        if s.position[d] < 0:
            column = s.KT[d]
            value = s.base[d]
            which = 1 if d < n else 2
            for k in range(n2):
                known[0, k] += value * column[k]
                known[which, k] += column[k]


@njit(cache=True)
def _lu_solve(A: np.ndarray, B: np.ndarray) -> bool:
    """Solve ``A X = B`` in place (X in B, A destroyed): Gaussian elimination, partial pivoting.

    False if a pivot vanishes (A singular) or the result is not finite. For the small
    systems of the weakening's Newton step (a rebuild's inverse is LAPACK's).
    """
    n = A.shape[0]
    k = B.shape[1]
    for j in range(n):
        pivot = j
        for i in range(j + 1, n):
            if abs(A[i, j]) > abs(A[pivot, j]):
                pivot = i
        if A[pivot, j] == 0.0 or not np.isfinite(A[pivot, j]):
            return False
        if pivot != j:
            for c in range(n):
                A[j, c], A[pivot, c] = A[pivot, c], A[j, c]
            for c in range(k):
                B[j, c], B[pivot, c] = B[pivot, c], B[j, c]
        for i in range(j + 1, n):
            factor = A[i, j] / A[j, j]
            if factor != 0.0:
                for c in range(j + 1, n):
                    A[i, c] -= factor * A[j, c]
                for c in range(k):
                    B[i, c] -= factor * B[j, c]
    # back substitution row by row: B's rows are read along their length
    for j in range(n - 1, -1, -1):
        for i in range(j + 1, n):
            factor = A[j, i]
            if factor != 0.0:
                for c in range(k):
                    B[j, c] -= factor * B[i, c]
        pivot = A[j, j]
        for c in range(k):
            B[j, c] /= pivot
            if not np.isfinite(B[j, c]):
                return False
    return True


@njit(cache=True)
def _rebuild(s: ZoneSolver, dofs: np.ndarray, coefficients: np.ndarray) -> bool:
    """Form M for these free displacements and invert it; False if singular."""
    m = dofs.size
    for d in range(s.position.size):
        s.position[d] = -1
    for p in range(m):
        s.dofs[p] = dofs[p]
        s.coefficient[p] = coefficients[p]
        s.position[dofs[p]] = p
        _copy(s.columns[p], s.KT[dofs[p]])
    s.counts[SIZE] = m
    s.counts[REBUILDS] += 1
    s.counts[PENDING] = 0
    _refresh_known(s)
    if m == 0:
        return True
    M = np.empty((m, m))
    K = s.K
    n = s.g0.size
    for p in range(m):
        for q in range(m):
            M[p, q] = K[dofs[p], dofs[q]]
            if coefficients[p] != 0.0:
                M[p, q] -= coefficients[p] * K[n + dofs[p], dofs[q]]
    # LAPACK's (getrf, getri): about three times the speed of an elimination of our own
    # at m 175, where a slip-weakening wave changes most rows at once
    try:
        inverse = np.linalg.inv(M)
        regular = np.isfinite(inverse).all()
    except Exception:  # numba raises LinAlgError for an exactly singular M
        regular = False
    if not regular:
        s.counts[SIZE] = 0  # nothing usable is kept
        for p in range(m):
            s.position[dofs[p]] = -1
        _refresh_known(s)
        return False
    for p in range(m):
        _copy(s.inverse[p, :m], inverse[p])
    _refresh_responses(s)
    return True


@njit(cache=True)
def _target(state: np.ndarray, mu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The free displacements of a zone state (node order, x before y) and their rows."""
    n = state.size
    count = 0
    for i in range(n):
        count += 2 if state[i] == OPEN else 1 if state[i] == SLIP else 0
    dofs = np.empty(count, dtype=np.int64)
    coefficients = np.zeros(count)
    k = 0
    for i in range(n):
        if state[i] != STICK:
            dofs[k] = i
            coefficients[k] = mu[i] if state[i] == SLIP else 0.0
            k += 1
        if state[i] == OPEN:
            dofs[k] = n + i
            k += 1
    return dofs, coefficients


@njit(cache=True)
def move_to(s: ZoneSolver, state: np.ndarray, mu: np.ndarray) -> bool:
    """Bring the kept inverse to a zone state, by updates or afresh if cheaper.

    Parameters
    ----------
    s
        The solver, updated in place.
    state
        Zone of each node.
    mu
        Signed friction coefficient of each node (read for the slipping ones).

    Returns
    -------
    bool
        False if the state's matrix is singular.

    """
    n = state.size
    dofs, coefficients = _target(state, mu)
    wanted = np.empty(2 * n)  # each free displacement's row coefficient (NaN: fixed)
    for d in range(2 * n):
        wanted[d] = np.nan
    for k in range(dofs.size):
        wanted[dofs[k]] = coefficients[k]
    m = s.counts[SIZE]
    removals = 0
    changes = 0
    for p in range(m):
        d = s.dofs[p]
        if np.isnan(wanted[d]):
            removals += 1
        elif wanted[d] != s.coefficient[p]:
            changes += 1
    additions = dofs.size - (m - removals)
    updates = removals + changes + additions
    if updates == 0:
        return True
    # a free displacement added or removed costs about 4 m^2, a row's new coefficient
    # ROW_CHANGE_COST m^2, and a rebuild REBUILD_COST m^3 + 12 n^2 (its known products)
    largest = max(m, dofs.size)
    cost = (4.0 * (removals + additions) + ROW_CHANGE_COST * changes) * largest * largest
    if cost > REBUILD_COST * dofs.size ** 3 + 12.0 * n * n:
        return _rebuild(s, dofs, coefficients)
    p = m - 1
    while p >= 0:  # highest first: the last one, moved into p, was already kept
        if np.isnan(wanted[s.dofs[p]]) and not _remove(s, p):
            return _rebuild(s, dofs, coefficients)
        p -= 1
    for p in range(s.counts[SIZE]):
        coefficient = wanted[s.dofs[p]]
        if coefficient != s.coefficient[p] and not _change_row(s, p, coefficient):
            return _rebuild(s, dofs, coefficients)
    for k in range(dofs.size):
        if s.position[dofs[k]] < 0 and not _add(s, dofs[k], coefficients[k]):
            return _rebuild(s, dofs, coefficients)
    return True


@njit(cache=True)
def set_base(s: ZoneSolver, s_prev: np.ndarray) -> None:
    """Start an increment from the relative positions ``s_prev``.

    Parameters
    ----------
    s
        The solver, updated in place.
    s_prev
        ``ux - dx`` of every node at the end of the previous increment.

    """
    n = s_prev.size
    s.counts[INCREMENTS] += 1
    moved = 0
    for i in range(n):
        moved += s_prev[i] != s.base[i] and s.position[i] < 0
    if 4 * moved > n or s.counts[INCREMENTS] % _REFRESH_EVERY == 0:
        _copy(s.base[:n], s_prev)
        _refresh_known(s)
    else:
        known = s.known[0]
        for i in range(n):
            change = s_prev[i] - s.base[i]
            if change != 0.0 and s.position[i] < 0:
                column = s.KT[i]
                for k in range(2 * n):
                    known[k] += change * column[k]
            s.base[i] = s_prev[i]
    _refresh_responses(s)


# ----------------------------------------------------------------------------------
# Solves


@njit(cache=True)
def _flat_terms(s: ZoneSolver, m: int) -> np.ndarray:
    """The known vectors' part in the equations: ``E_p @ v`` for rows 0 (values) 1, 2."""
    terms = np.empty((3, m))
    for p in range(m):
        row = _row_terms(s.known, s.dofs[p], s.coefficient[p])
        for k in range(3):
            terms[k, p] = row[k]
    return terms


@njit(cache=True)
def _totals(known: np.ndarray) -> np.ndarray:
    """Each known product summed over the x rows (T) and over the y rows (N)."""
    n = known.shape[1] // 2
    totals = np.zeros((3, 2))
    for k in range(3):
        for i in range(n):
            totals[k, 0] += known[k, i]
            totals[k, 1] += known[k, n + i]
    return totals


@njit(cache=True)
def _inverse_times(s: ZoneSolver, b: np.ndarray) -> np.ndarray:
    """The kept inverse times one vector."""
    m = b.size
    rhs = np.empty((1, m))
    _copy(rhs[0], b)
    return _apply_inverse(s, rhs, 1, m)[0]


@njit(cache=True, fastmath=FAST)
def _apply_inverse(s: ZoneSolver, rhs: np.ndarray, count: int, m: int) -> np.ndarray:
    """The inverse times ``rhs[k]`` for the first ``count`` rows of rhs.

    Once per increment and per refinement: written for a short compilation rather than
    for speed.
    """
    B = s.inverse
    out = np.zeros((count, m))
    for a in range(m):
        for k in range(count):
            total = 0.0
            for c in range(m):
                total += B[a, c] * rhs[k, c]
            out[k, a] = total
    for j in range(s.counts[PENDING]):
        u, v = s.pending_u[j], s.pending_v[j]
        for k in range(count):
            product = 0.0
            for c in range(m):
                product += v[c] * rhs[k, c]
            for a in range(m):
                out[k, a] += u[a] * product
    return out


@njit(cache=True)
def _flat_system(sum_x: np.ndarray, sum_y: np.ndarray, dofs: np.ndarray,
                 responses: np.ndarray, m: int, fl: Flat, totals: np.ndarray
                 ) -> tuple[np.ndarray, int, np.ndarray, bool]:
    """The flat's unknown motions and the Schur complement that eliminates them.

    Returns which motions are unknown (0: dx, with T's equation; 1: dy, with N's), how
    many, their 2 x 2 complement and whether it is regular. Its columns come from the
    kept responses 1 and 2: the inverse times the terms of the stuck x (dx) and of the
    contact y (dy), for the m free displacements ``dofs``.
    """
    which = np.zeros(2, dtype=np.int64)
    count = 0
    if fl.dx_unknown:
        which[count] = 0
        count += 1
    if fl.dy_unknown:
        which[count] = 1
        count += 1
    S = np.zeros((2, 2))
    for e in range(count):
        totals_row = sum_x if which[e] == 0 else sum_y
        for k in range(count):
            value = totals[1 + which[k], which[e]]
            if which[e] == 0 and which[k] == 0:
                value += fl.values[4]  # the machine's spring
            response = 1 + which[k]
            for p in range(m):
                value -= totals_row[dofs[p]] * responses[response, p]
            S[e, k] = value
    regular = True
    if count == 1:
        regular = S[0, 0] != 0.0 and np.isfinite(S[0, 0])
    elif count == 2:
        det = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
        scale = abs(S[0, 0] * S[1, 1]) + abs(S[0, 1] * S[1, 0])
        regular = np.isfinite(det) and abs(det) > 1e-14 * scale
    return which, count, S, regular


@njit(cache=True)
def _flat_motion(sum_x: np.ndarray, sum_y: np.ndarray, dofs: np.ndarray,
                 responses: np.ndarray, which: np.ndarray, count: int, S: np.ndarray,
                 z: np.ndarray, flat_rhs: np.ndarray, motion: np.ndarray) -> None:
    """Eliminate the flat's motion: z, the inverse times b on entry, corrected in place.

    ``motion`` receives the dx and dy parts (zero where given); S must be regular.
    """
    m = z.size
    motion[0] = motion[1] = 0.0
    if count == 0:
        return
    flat = np.zeros(2)
    for e in range(count):
        totals_row = sum_x if which[e] == 0 else sum_y
        value = flat_rhs[which[e]]
        for p in range(m):
            value -= totals_row[dofs[p]] * z[p]
        flat[e] = value
    f = np.zeros(2)
    if count == 1:
        f[0] = flat[0] / S[0, 0]
    else:
        det = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
        f[0] = (flat[0] * S[1, 1] - S[0, 1] * flat[1]) / det
        f[1] = (S[0, 0] * flat[1] - S[1, 0] * flat[0]) / det
    for k in range(count):
        motion[which[k]] = f[k]
        response = 1 + which[k]
        for p in range(m):
            z[p] -= responses[response, p] * f[k]


@njit(cache=True)
def _assemble(base: np.ndarray, known: np.ndarray, dofs: np.ndarray, C: np.ndarray,
              z: np.ndarray, dx: float, dy: float, u: np.ndarray, r: np.ndarray) -> None:
    """Fill u, and r = K u, from the free displacements z and the flat's position.

    ``base``, ``known``, ``dofs`` and ``C`` (the free columns) are the solver's.
    """
    n = base.size // 2
    for i in range(n):
        u[i] = base[i] + dx
        u[n + i] = base[n + i] + dy
    m = z.size
    for p in range(m):
        u[dofs[p]] = z[p]
    for k in range(2 * n):
        r[k] = known[0, k] + dx * known[1, k] + dy * known[2, k]
    # four columns per pass over r: a quarter of its loads and stores
    # (indexed in two dimensions: a row taken as an array would be reference-counted)
    p = 0
    while p + 4 <= m:
        z0, z1, z2, z3 = z[p], z[p + 1], z[p + 2], z[p + 3]
        for k in range(2 * n):
            r[k] += z0 * C[p, k] + z1 * C[p + 1, k] + z2 * C[p + 2, k] + z3 * C[p + 3, k]
        p += 4
    while p < m:
        zp = z[p]
        for k in range(2 * n):
            r[k] += zp * C[p, k]
        p += 1


@njit(cache=True)
def _residuals(dofs: np.ndarray, coefficient: np.ndarray, m: int, fl: Flat,
               r: np.ndarray, dx: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The equations' residuals (free rows; T, N) and their largest, relative."""
    n = r.size // 2
    rows = np.empty(m)
    worst = 0.0
    for p in range(m):
        d = dofs[p]
        rows[p] = r[d] - coefficient[p] * r[n + d] if coefficient[p] != 0.0 else r[d]
        worst = max(worst, abs(rows[p]))
    flat_rows = np.zeros(2)
    if fl.dx_unknown:
        total = 0.0
        for i in range(n):
            total += r[i]
        flat_rows[0] = total + fl.values[4] * dx - fl.values[2]
        worst = max(worst, abs(flat_rows[0]))
    if fl.dy_unknown:
        total = 0.0
        for i in range(n):
            total += r[n + i]
        flat_rows[1] = total - fl.values[3]
        worst = max(worst, abs(flat_rows[1]))
    scale = 1e-300
    for k in range(2 * n):
        scale = max(scale, abs(r[k]))
    return rows, flat_rows, worst / scale


@njit(cache=True)
def solve(s: ZoneSolver, fl: Flat, u: np.ndarray, r: np.ndarray) -> tuple[float, float, bool]:
    """Solve the kept zone state for the flat's prescribed motion or loads.

    Parameters
    ----------
    s
        The solver, at the zone state (:func:`move_to`) and the increment's base
        (:func:`set_base`).
    fl
        What is prescribed of the flat.
    u, r
        (2n,) filled with the displacements and the contact forces ``K u``.

    Returns
    -------
    tuple
        dx, dy and False if the state is singular.

    """
    s.counts[SOLVES] += 1
    given_dx = 0.0 if fl.dx_unknown else fl.values[0]
    given_dy = 0.0 if fl.dy_unknown else fl.values[1]
    dx, dy = given_dx, given_dy
    motion = np.zeros(2)
    aim = max(REFINE_ABOVE, ACCURACY_MARGIN * s.accuracy[0])
    for attempt in range(2):  # the second with the inverse formed afresh
        m = s.counts[SIZE]
        totals = _totals(s.known)
        which, count, S, regular = _flat_system(s.sum_x, s.sum_y, s.dofs, s.responses, m,
                                                fl, totals)
        y = s.responses
        z = np.empty(m)  # the inverse times b = -(terms 0 + dx terms 1 + dy terms 2)
        for p in range(m):
            z[p] = -(y[0, p] + given_dx * y[1, p] + given_dy * y[2, p])
        flat_rhs = np.zeros(2)
        if fl.dx_unknown:  # T = sum Q + machine dx
            flat_rhs[0] = fl.values[2] - totals[0, 0] - given_dy * totals[2, 0]
        if fl.dy_unknown:
            flat_rhs[1] = fl.values[3] - totals[0, 1] - given_dx * totals[1, 1]
        motion[0] = motion[1] = 0.0
        if regular:
            _flat_motion(s.sum_x, s.sum_y, s.dofs, s.responses, which, count, S, z,
                         flat_rhs, motion)
        dx = motion[0] if fl.dx_unknown else given_dx
        dy = motion[1] if fl.dy_unknown else given_dy
        _assemble(s.base, s.known, s.dofs, s.columns, z, dx, dy, u, r)
        if not regular:
            return dx, dy, regular
        rows, flat_rows, relative = _residuals(s.dofs, s.coefficient, m, fl, r, dx)
        if relative <= aim:
            return dx, dy, True
        # one step of iterative refinement: the same system for the residual
        s.counts[REFINEMENTS] += 1
        for p in range(m):
            rows[p] = -rows[p]
        for k in range(2):
            flat_rows[k] = -flat_rows[k]
        correction = _inverse_times(s, rows)
        _flat_motion(s.sum_x, s.sum_y, s.dofs, s.responses, which, count, S,
                     correction, flat_rows, motion)
        for p in range(m):
            z[p] += correction[p]
        dx += motion[0]
        dy += motion[1]
        _assemble(s.base, s.known, s.dofs, s.columns, z, dx, dy, u, r)
        refined = _residuals(s.dofs, s.coefficient, m, fl, r, dx)[2]
        if refined <= aim:
            if attempt == 0:  # the updates' rounding, cleared (a rebuild just did)
                _refresh_responses(s)
            return dx, dy, True
        if attempt == 1:  # an inverse formed afresh, refined, does no better: the state's
            s.accuracy[0] = min(refined, ACCURACY_CAP)
            return dx, dy, True
        # the updates have lost accuracy: the inverse afresh
        dofs = np.empty(m, dtype=np.int64)
        coefficients = np.empty(m)
        for p in range(m):
            dofs[p] = s.dofs[p]
            coefficients[p] = s.coefficient[p]
        if not _rebuild(s, dofs, coefficients):
            return dx, dy, False
    return dx, dy, False


@njit(cache=True)
def slip_sensitivity(s: ZoneSolver, fl: Flat, state: np.ndarray, pressure: np.ndarray
                     ) -> np.ndarray:
    """d(ds_j)/d(mu_i) between the slipping nodes, in index order, at the kept state.

    Differentiating ``Q_i = mu_i P_i`` leaves the state's own matrix with ``P_i`` as
    the source of node i's friction equation: a column of the kept inverse each.

    Parameters
    ----------
    s
        The solver, at the zone state that was solved.
    fl
        What is prescribed of the flat.
    state
        That zone state.
    pressure
        Normal force P of every node in its solution.

    Returns
    -------
    numpy.ndarray
        (k, k) for the k slipping nodes.

    """
    m = s.counts[SIZE]
    slipping = _slipping(state)
    k = slipping.size
    which, count, S, regular = _flat_system(s.sum_x, s.sum_y, s.dofs, s.responses, m, fl,
                                            _totals(s.known))
    sensitivity = np.empty((k, k))
    dz = np.empty(m)
    motion = np.zeros(2)
    no_load = np.zeros(2)
    B = s.inverse
    for column in range(k):
        q = s.position[slipping[column]]
        source = pressure[slipping[column]]
        for a in range(m):  # the inverse's column q (with its pending terms), times P
            dz[a] = B[a, q] * source
        for j in range(s.counts[PENDING]):
            factor = s.pending_v[j, q] * source
            for a in range(m):
                dz[a] += s.pending_u[j, a] * factor
        if regular:
            _flat_motion(s.sum_x, s.sum_y, s.dofs, s.responses, which, count, S, dz,
                         no_load, motion)
        for j in range(k):
            sensitivity[j, column] = dz[s.position[slipping[j]]] - motion[0]
    return sensitivity


# ----------------------------------------------------------------------------------
# The increment




MAX_ITERATIONS = 60
PREDICTOR = 0.9  # see iterate
WEAKENING_TOLERANCE = 1e-6  # relative change of a wave coefficient that ends the fixed point
MAX_WEAKENINGS = 1000
# Newton steps on the wave's coefficients per cascade round before falling back on the
# plain fixed point (with Aitken's extrapolation); Newton mostly ends in two or three.
NEWTON_WEAKENINGS = 12
NEWTON_REACH = 20.0  # the longest Newton step, in plain fixed-point steps
SLOPE_STEP = 1e-6  # mm: the central difference of the weakening's slope

# what iterate returns
CONVERGED, CYCLING, SINGULAR, WEAKENING = range(4)
FAILURES = {CYCLING: f"active set still changing after {MAX_ITERATIONS} iterations",
            SINGULAR: "singular zone state",
            WEAKENING: "slip-weakening coefficients still changing"}


@njit(cache=True)
def weakened(slip: np.ndarray, law: np.ndarray) -> np.ndarray:
    """Linear slip-weakening ``fs - (fs - fd) min(slip / dc, 1)``, law ``[fs, fd, dc]``.

    Parameters
    ----------
    slip
        Each node's slip in the wave, mm.
    law
        The weakening's fs, fd and Dc.

    Returns
    -------
    numpy.ndarray
        The coefficients.

    """
    result = np.empty(slip.size)
    for i in range(slip.size):
        result[i] = law[0] - (law[0] - law[1]) * min(slip[i] / law[2], 1.0)
    return result


@njit(cache=True)
def residual(s: ZoneSolver, fl: Flat, u: np.ndarray, r: np.ndarray, dx: float, dy: float,
             s_prev: np.ndarray, limit: np.ndarray) -> float:
    """Relative complementarity residual of a solution: zero for an exact one.

    Normal ``min(P, c g)``; tangential ``Q - proj_[-f P+, f P+](Q - c ds)``
    (Alart-Curnier, ``c`` the nodes' own stiffness); the prescribed totals. Scaled by
    ``max |P|``.

    Parameters
    ----------
    s
        The body's solver (its stiffness gives the augmentation).
    fl
        What is prescribed of the flat.
    u, r
        Displacements and contact forces.
    dx, dy
        The flat's position.
    s_prev
        Relative tangential positions at the end of the previous increment.
    limit
        Friction coefficient of each node.

    Returns
    -------
    float
        The largest violation relative to the load scale.

    """
    n = s_prev.size
    worst = 0.0
    scale = 1e-300
    total_q = 0.0
    total_p = 0.0
    for i in range(n):
        P, Q = r[n + i], r[i]
        total_q += Q
        total_p += P
        gap = s.g0[i] + u[n + i] - dy
        ds = u[i] - dx - s_prev[i]
        bound = limit[i] * max(P, 0.0)
        trial = Q - s.K[i, i] * ds
        worst = max(worst, abs(min(P, s.K[n + i, n + i] * gap)),
                    abs(Q - min(max(trial, -bound), bound)))
        scale = max(scale, abs(P))
    if fl.dx_unknown:
        worst = max(worst, abs(total_q + fl.values[4] * dx - fl.values[2]))
    if fl.dy_unknown:
        worst = max(worst, abs(total_p - fl.values[3]))
    return worst / scale


@njit(cache=True)
def _classify(g0: np.ndarray, K: np.ndarray, u: np.ndarray, r: np.ndarray, dx: float,
              dy: float, s_prev: np.ndarray, limit: np.ndarray, in_wave: np.ndarray,
              cascade: bool, work: np.ndarray, new: np.ndarray, slipping: np.ndarray
              ) -> None:
    """The next guess from a solution: open, stuck, or slipping where it may.

    ``work`` receives Q, P, gap, ds, trial (``Q - c ds``) and bound (``f`` times
    the augmented pressure) per node, in its rows 0 to 5.
    """
    n = s_prev.size
    for i in range(n):
        Q = work[0, i] = r[i]
        P = work[1, i] = r[n + i]
        gap = work[2, i] = g0[i] + u[n + i] - dy
        ds = work[3, i] = u[i] - dx - s_prev[i]
        pressure = P - K[n + i, n + i] * gap
        trial = work[4, i] = Q - K[i, i] * ds
        bound = work[5, i] = limit[i] * max(pressure, 0.0)
        new[i] = STICK if pressure > 0 else OPEN
        # Nodes outside the wave may slip only without a cascade (fs == fd).
        slipping[i] = (new[i] == STICK and (in_wave[i] or not cascade)
                       and abs(trial) > bound)


@njit(cache=True)
def _predict(state: np.ndarray, new: np.ndarray, slipping: np.ndarray, work: np.ndarray,
             in_wave: np.ndarray, cascade: bool) -> None:
    """Start the increment with the slip front a node ahead where it is near its limit.

    A slip front advances about a node per active-set iteration: a stuck node beside
    the slip, already within 10 % of its limit, starts the increment slipping (it
    sticks again in the next iteration if it does not slip). This saves iterations;
    the converged state is the same.
    """
    n = state.size
    beside = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        if slipping[i] or state[i] == SLIP:
            for j in range(max(i - 1, 0), min(i + 2, n)):
                beside[j] = True
    for i in range(n):
        if (new[i] == STICK and (in_wave[i] or not cascade) and beside[i]
                and abs(work[4, i]) > PREDICTOR * work[5, i]):
            slipping[i] = True


@njit(cache=True)
def _keep_one_stuck(new: np.ndarray, slipping: np.ndarray, work: np.ndarray) -> None:
    """Keep the least overloaded node stuck when a load-controlled guess has none.

    Under load control a state without a stuck node leaves dx undetermined. If the
    contact truly cannot carry T, the iteration fails and the caller finds gross
    sliding.
    """
    any_slipping = False
    for i in range(new.size):
        if new[i] == STICK:
            return
        any_slipping = any_slipping or slipping[i]
    if not any_slipping:
        return
    least = -1
    excess = np.inf
    for i in range(new.size):
        if slipping[i] and abs(work[4, i]) - work[5, i] < excess:
            excess = abs(work[4, i]) - work[5, i]
            least = i
    new[least] = STICK
    slipping[least] = False


@njit(cache=True)
def _same(a: np.ndarray, b: np.ndarray) -> bool:
    for i in range(a.size):  # noqa: SIM110 - a loop compiles lighter than all()
        if a[i] != b[i]:
            return False
    return True


@njit(cache=True)
def _seen(states: np.ndarray, signs: np.ndarray, count: int, state: np.ndarray,
          sign: np.ndarray) -> bool:
    for k in range(count):  # noqa: SIM110 - a loop compiles lighter than any()
        if _same(states[k], state) and _same(signs[k], sign):
            return True
    return False


@njit(cache=True)
def _weakened_limits(state: np.ndarray, in_wave: np.ndarray, work: np.ndarray,
                     wave_limit: np.ndarray, law: np.ndarray, dynamic: float,
                     static: float) -> tuple[np.ndarray, float]:
    """The wave's coefficients at the slips they gave, and their largest change."""
    n = state.size
    slip = np.empty(n)
    for i in range(n):
        slip[i] = abs(work[3, i])
    weak = weakened(slip, law)
    updated = np.empty(n)
    change = 0.0
    for i in range(n):
        value = weak[i] if in_wave[i] and state[i] == SLIP else wave_limit[i]
        updated[i] = min(max(value, dynamic), static)
        change = max(change, abs(updated[i] - wave_limit[i]))
    return updated, change


@njit(cache=True)
def _aitken(history: np.ndarray, dynamic: float, static: float) -> np.ndarray:
    """Aitken's extrapolation of three slowly converging iterates of the coefficients."""
    n = history.shape[1]
    jumped = np.empty(n)
    for i in range(n):
        a, b, c = history[0, i], history[1, i], history[2, i]
        step = (c - b) - (b - a)
        jump = c - (c - b) ** 2 / step if abs(step) > 1e-14 else c
        jumped[i] = min(max(jump, dynamic), static)
    return jumped


@njit(cache=True)
def _weakening_newton(s: ZoneSolver, fl: Flat, state: np.ndarray, mu: np.ndarray,
                      P: np.ndarray, ds: np.ndarray, wave_limit: np.ndarray,
                      updated: np.ndarray, law: np.ndarray, dynamic: float,
                      static: float) -> np.ndarray:
    """A Newton step towards the wave coefficients m = W(|ds(m)|) of this zone state.

    The plain fixed point (``updated``, m <- W(|ds(m)|)) converges slowly when a
    node's slip feeds back strongly on its own coefficient; Newton's step, from the
    slip's sensitivity to the coefficients (columns of the kept inverse), takes two
    or three. It is taken only where it extrapolates the plain step (same direction,
    at most :data:`NEWTON_REACH` times as far): the plain iteration converges only to
    equilibria that attract it, the stable ones, and Newton's alone could also find
    the unstable ones, behind it.
    """
    slipping = _slipping(state)
    k = slipping.size
    m = np.empty(k)
    slip = np.empty(k)
    for j in range(k):
        m[j] = wave_limit[slipping[j]]
        slip[j] = abs(ds[slipping[j]])
    # the slope of the clipped weakening: zero where it is held at fd or fs
    low = weakened(slip - SLOPE_STEP, law)
    high = weakened(slip + SLOPE_STEP, law)
    sensitivity = slip_sensitivity(s, fl, state, P)
    # d|ds_j|/dm_i = sign(ds_j) d(ds_j)/d(mu_i) sign_i, mu = m sign
    jacobian = np.zeros((k, k))
    plain = np.empty((k, 1))
    for j in range(k):
        slope = (min(max(high[j], dynamic), static)
                 - min(max(low[j], dynamic), static)) / (2 * SLOPE_STEP)
        direction = np.sign(ds[slipping[j]])
        jacobian[j, j] = 1.0
        for i in range(k):
            jacobian[j, i] -= (slope * direction * sensitivity[j, i]
                               * np.sign(mu[slipping[i]]))
        plain[j, 0] = updated[slipping[j]] - m[j]
    step = np.empty((k, 1))
    for j in range(k):
        step[j, 0] = plain[j, 0]
    if not _lu_solve(jacobian, step):
        return updated
    for j in range(k):
        if not (step[j, 0] * plain[j, 0] >= 0.0
                and abs(step[j, 0]) <= NEWTON_REACH * abs(plain[j, 0]) + 1e-12):
            return updated
    result = np.empty(updated.size)
    _copy(result, updated)
    for j in range(k):
        result[slipping[j]] = min(max(m[j] + step[j, 0], dynamic), static)
    return result


@njit(cache=True)
def iterate(K: np.ndarray, KT: np.ndarray, g0: np.ndarray, sum_x: np.ndarray,
            sum_y: np.ndarray, inverse: np.ndarray, columns: np.ndarray,
            coefficient: np.ndarray, known: np.ndarray, base: np.ndarray,
            dofs: np.ndarray, position: np.ndarray, counts: np.ndarray,
            pending_u: np.ndarray, pending_v: np.ndarray, responses: np.ndarray,
            accuracy: np.ndarray, flat_values: np.ndarray, dx_unknown: bool, dy_unknown: bool,
            s_prev: np.ndarray, static: float, dynamic: float, law: np.ndarray,
            guess: np.ndarray, guess_sign: np.ndarray, heal: bool, u: np.ndarray,
            r: np.ndarray, u_before: np.ndarray, r_before: np.ndarray, state: np.ndarray,
            sign: np.ndarray, direction: np.ndarray, round_slipped: np.ndarray,
            scalars: np.ndarray) -> int:
    """Solve one increment by the active set, with the cascade when fs > fd.

    The body's :class:`ZoneSolver` and the increment's :class:`Flat` come as their
    fields: numba reads plain arrays from Python several times faster than named
    tuples of them, and an increment is a call from Python. The round's settling is
    written here too: each level of calls between compiled functions has LLVM
    optimise its callees' code again, and a wrapper and a settling function of their
    own made the compilation about 10 s longer (45 s against 35 s).

    Parameters
    ----------
    K, KT, g0, sum_x, sum_y, inverse, columns, coefficient, known, base, dofs, position
        The fields of the body's :class:`ZoneSolver`, in order; its kept inverse is
        moved along.
    counts, pending_u, pending_v, responses, accuracy
        Its last fields.
    flat_values, dx_unknown, dy_unknown
        The fields of the increment's :class:`Flat`.
    s_prev
        ``ux - dx`` of every node at the end of the previous increment.
    static, dynamic
        Friction coefficients fs >= fd.
    law
        ``[fs, fd, Dc]`` of linear slip-weakening, or empty (Coulomb).
    guess, guess_sign
        Zone state and friction signs to start from.
    heal
        Whether slipping nodes of the guess start stuck (the interface heals).
    u, r, u_before, r_before
        (2n,) filled with the displacements and the contact forces, and those of
        the stuck state before the wave.
    state, sign, direction, round_slipped
        (n,) filled with the converged zone state, friction signs, the slipping nodes'
        slip directions (the sign of ``ux - dx - s_prev``; 0 where not slipping) and
        the cascade round in which each node started slipping (-1: it did not).
    scalars
        Filled with dx, dy, the flat's x before the wave, the residual, iterations.

    Returns
    -------
    int
        :data:`CONVERGED`, or the reason it did not (:data:`FAILURES`).

    """
    s = ZoneSolver(K, KT, g0, sum_x, sum_y, inverse, columns, coefficient, known, base,
                   dofs, position, counts, pending_u, pending_v, responses, accuracy)
    fl = Flat(flat_values, dx_unknown, dy_unknown)
    n = s_prev.size
    cascade = static > dynamic
    weakening = law.size == 3 and cascade
    set_base(s, s_prev)
    _copy(state, guess)
    _copy(sign, guess_sign)
    in_wave = np.zeros(n, dtype=np.bool_)
    # The coefficient of each node in the wave: fd, or under slip-weakening its
    # coefficient at the slip it has made in the wave (a fixed point, below).
    wave_limit = np.empty(n)
    limit = np.empty(n)
    for i in range(n):
        if heal and state[i] == SLIP:
            # A stuck predictor finds the slipping nodes with their new directions.
            state[i] = STICK
        round_slipped[i] = -1
        wave_limit[i] = dynamic
    mu = np.empty(n)
    work = np.empty((6, n))  # Q, P, gap, ds, trial, bound
    new = np.empty(n, dtype=np.int8)  # each iteration's next guess
    new_sign = np.empty(n)
    slipping = np.empty(n, dtype=np.bool_)
    seen_states = np.empty((0, n), dtype=np.int8)  # the guesses of a round's iterations
    seen_signs = np.empty((0, n))
    flat_position = np.zeros(2)
    history = np.empty((3, n))
    kept = 0  # of history
    iterations = 0
    rounds = 0  # the cascade round
    weakenings = 0
    newtons = 0  # Newton steps in this round
    dx_before = 0.0
    while True:
        for i in range(n):
            limit[i] = wave_limit[i] if in_wave[i] else static
        # The round's active set settles.
        taken = -1  # the iterations it took; -1: still cycling, -2: a singular state
        first = rounds == 0
        seen = 0
        for iteration in range(1, MAX_ITERATIONS + 1):
            for i in range(n):
                mu[i] = limit[i] * sign[i]
            if not move_to(s, state, mu):
                taken = -2
                break
            dx, dy, regular = solve(s, fl, u, r)
            if not regular:
                taken = -2
                break
            flat_position[0] = dx
            flat_position[1] = dy
            _classify(s.g0, s.K, u, r, dx, dy, s_prev, limit, in_wave, cascade, work, new,
                      slipping)
            if first:
                _predict(state, new, slipping, work, in_wave, cascade)
                first = False
            for i in range(n):
                if slipping[i]:
                    new[i] = SLIP
            if fl.dx_unknown and fl.values[4] == 0.0:
                _keep_one_stuck(new, slipping, work)
            # (a frictionless slip carries no shear: its sign changes nothing)
            for i in range(n):
                new_sign[i] = np.sign(work[4, i]) if slipping[i] and limit[i] > 0 else sign[i]
            if _same(new, state) and _same(new_sign, sign):
                taken = iteration
                break
            if seen_states.shape[0] == 0:  # kept once a round takes a second iteration
                seen_states = np.empty((MAX_ITERATIONS + 1, n), dtype=np.int8)
                seen_signs = np.empty((MAX_ITERATIONS + 1, n))
            repeated = _seen(seen_states, seen_signs, seen, new, new_sign)
            _copy(seen_states[seen if not repeated else 0], new)
            _copy(seen_signs[seen if not repeated else 0], new_sign)
            seen = 1 if repeated else seen + 1
            if repeated:
                # A cycle: nodes at the edge of the contact flip between stuck in
                # tension and open in penetration. They are in contact with a vanishing
                # pressure, so any shear exceeds f P: they slide (and, in a cascade,
                # join the wave).
                for i in range(n):
                    if new[i] != state[i]:
                        if cascade and not in_wave[i]:
                            in_wave[i] = True
                            round_slipped[i] = rounds
                            limit[i] = wave_limit[i]
                        new[i] = SLIP
                        new_sign[i] = -1.0 if work[4, i] < 0 else 1.0
            _copy(state, new)
            _copy(sign, new_sign)
        if taken == -1:
            return CYCLING
        if taken == -2:
            return SINGULAR
        iterations += taken
        if rounds == 0:
            # The stuck state of the increment, before any wave: the peak.
            _copy(u_before, u)
            _copy(r_before, r)
            dx_before = flat_position[0]
        if not cascade:
            for i in range(n):
                if state[i] == SLIP:
                    round_slipped[i] = 0
            break
        any_wave = False
        for i in range(n):
            any_wave = any_wave or in_wave[i]
        if weakening and any_wave:
            # Slip-weakening: the wave's coefficients at the slip they give. From fd
            # (the most slip) the slip only shrinks towards the fixed point, the
            # largest equilibrium the weakening allows; Newton's steps go the same
            # way, further.
            updated, change = _weakened_limits(state, in_wave, work, wave_limit, law,
                                               dynamic, static)
            if change > WEAKENING_TOLERANCE * static:
                weakenings += 1
                if weakenings > MAX_WEAKENINGS:
                    return WEAKENING
                if newtons < NEWTON_WEAKENINGS:
                    newtons += 1
                    wave_limit = _weakening_newton(s, fl, state, mu, work[1], work[3],
                                                   wave_limit, updated, law, dynamic,
                                                   static)
                    continue
                _copy(history[kept], updated)
                kept += 1
                if kept == 3:
                    updated = _aitken(history, dynamic, static)
                    kept = 0
                wave_limit = updated
                continue
        any_over = False
        for i in range(n):
            if (state[i] == STICK and not in_wave[i]
                    and abs(work[0, i]) > static * work[1, i] * (1 + 1e-12)):
                any_over = True
                # The overloaded nodes start slipping the way their load pushes them.
                in_wave[i] = True
                round_slipped[i] = rounds
                state[i] = SLIP
                sign[i] = np.sign(work[0, i])
        if not any_over:
            break
        rounds += 1
        newtons = 0
        kept = 0
    for i in range(n):
        limit[i] = wave_limit[i] if in_wave[i] else static
    dx, dy = flat_position[0], flat_position[1]
    for i in range(n):
        direction[i] = np.sign(u[i] - dx - s_prev[i]) if state[i] == SLIP else 0
    scalars[0] = dx
    scalars[1] = dy
    scalars[2] = dx_before if cascade else dx
    scalars[3] = residual(s, fl, u, r, dx, dy, s_prev, limit)
    scalars[4] = iterations
    if not cascade:
        _copy(u_before, u)
        _copy(r_before, r)
    return CONVERGED


def callee_examples(body: ZoneSolver, law: np.ndarray) -> list[tuple[str, tuple]]:
    """Arguments typed as :func:`iterate` passes them to its callees.

    numba compiles a callee once for each set of argument types and caches it;
    compiled first from these (in other processes, in parallel), the callees are
    loaded when :func:`iterate` is compiled, which then optimises its own code alone
    (about a quarter of the solver's compilation). Should :func:`iterate` call one
    with other types, that callee is compiled again with it: slower, never wrong.

    Parameters
    ----------
    body
        A body's solver (:func:`zone_solver`), any size.
    law
        A slip-weakening law ``[fs, fd, Dc]``.

    Returns
    -------
    list
        Pairs of a callee's name and a tuple of arguments of the types :func:`iterate`
        gives it, or of those types (a callee called with several types comes once
        for each).

    """
    n = body.g0.size
    fl = flat(None, 0.0, 1.0, None, 1.0)
    state = np.full(n, STICK, dtype=np.int8)
    vector = np.zeros(n)
    work = np.zeros((6, n))
    forces = np.zeros(2 * n)
    flags = np.zeros(n, dtype=np.bool_)
    return [
        ("set_base", (body, vector)),
        ("move_to", (body, state, vector)),
        ("solve", (body, fl, forces, forces)),
        ("residual", (body, fl, forces, forces, 0.0, 0.0, vector, vector)),
        ("_classify", (body.g0, body.K, forces, forces, 0.0, 0.0, vector, vector, flags, True,
                       work, state, flags)),
        ("_predict", (state, state, flags, work, flags, True)),
        ("_keep_one_stuck", (state, flags, work)),
        ("_weakened_limits", (state, flags, work, vector, law, 0.5, 0.9)),
        ("_weakening_newton", (body, fl, state, vector, work[1], work[3], vector, vector, law,
                               0.5, 0.9)),
        ("_aitken", (work[:3], 0.5, 0.9)),
        ("_same", (state, state)),
        ("_same", (vector, vector)),
        # iterate's count of seen guesses: numba types it as the literal it starts at
        # and as an integer
        ("_seen", (np.zeros((2, n), dtype=np.int8), work[:2], types.literal(0), state,
                   vector)),
        ("_seen", (np.zeros((2, n), dtype=np.int8), work[:2], 0, state, vector)),
        ("_copy", (state, state)),
        ("_copy", (vector, vector)),
    ]
