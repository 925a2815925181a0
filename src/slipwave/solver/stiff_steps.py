"""Compiled implicit steps for the quasi-dynamic contact: scipy's BDF, in numba, banded.

scipy's ``BDF`` (variable order 1 to 5, the numerical differentiation formulas of
Shampine and Reichelt 1997, quasi-constant step size; Byrne and Hindmarsh 1975) ported
to numba, its Newton matrix ``I - c J`` kept within the band of
:func:`slipwave.solver.quasi_dynamic_steps.jacobian`, a step's Python gone. A node's
states touch only its own slip rate, so the Newton matrix's rows of states are
eliminated node by node (each node's block of states inverted) and what is factorised
is the Schur complement on the nodes' positions: a band of nodes, not of entries, by
Gaussian elimination with partial pivoting in band storage (LAPACK's ``dgbtf2`` and
``dgbtrs``): at 160 elements and one state, a band of 8 nodes in place of 17 entries.
One change to scipy's algorithm: the Jacobian is taken again when the Newton matrix's c
has moved by 30 % from the one it was taken for, or after 20 steps (LSODE's rule).
scipy keeps it until Newton fails, and within a step keeps the one taken for a longer
try: on a spring-slider that one, taken where the try predicted a fast slip, made the
corrections small without the equation holding, and a step passed over the slip's
onset (T/N off by 0.0125; scipy's own ``BDF`` does the same there). The interpolant is
scipy's (:func:`interpolate`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from slipwave.solver.quasi_dynamic_steps import Law, Reduction, jacobian, rates

MAX_ORDER = 5
_NEWTON_ITERATIONS = 4
_MIN_FACTOR, _MAX_FACTOR = 0.2, 10.0
_KAPPA = np.array([0.0, -0.1850, -1.0 / 9.0, -0.0823, -0.0415, 0.0])
_GAMMA = np.concatenate((np.zeros(1), np.cumsum(1.0 / np.arange(1, MAX_ORDER + 1))))
_ALPHA = (1.0 - _KAPPA) * _GAMMA
_ERROR_CONSTANT = _KAPPA * _GAMMA + 1.0 / np.arange(1, MAX_ORDER + 2)

OK, TOO_SMALL = 0, 1
"""What :func:`step` returns: a step taken; the step fell below the smallest."""

# the places in Stepper.scalars; the time's, the last step's start's and the end's are read
# outside
T, _H, _ORDER, _EQUAL, T_OLD, _LU_VALID, _JAC_C, _MAX_STEP, BOUND, _RTOL, \
    _NEWTON_TOL, _JAC_AGE = range(12)
_JAC_CHANGE = 0.3  # LSODE's CCMAX: a step's c this far from the Jacobian's takes a new one
_JAC_STEPS = 20  # LSODE's MSBP: steps after which a Jacobian is taken again
# the counters' places in Stepper.counts
STEPS, EVALUATIONS, JACOBIANS, FACTORISATIONS = range(4)


class Factors(NamedTuple):
    """The Newton matrix ``A = I - c J``, each node's states eliminated, factorised.

    With a node's position s and its states q, ``A`` splits into blocks ``A_ss`` (a band
    of nodes), ``A_sq`` and ``A_qq`` (a node's own only) and ``A_qs`` (a band of
    nodes); ``A x = r`` is then ``S x_s = r_s - W r_q`` with ``W = A_sq A_qq^-1`` and the
    Schur complement ``S = A_ss - W A_qs``, and ``x_q = A_qq^-1 (r_q - A_qs x_s)``.

    Attributes
    ----------
    lu
        (nodes, 3 band + 1): S's LU, LAPACK's band storage transposed (:func:`_band_lu`).
    pivots
        (nodes,): its row interchanges.
    coupling
        (nodes, states): W.
    inverse
        (nodes, states, states): each node's ``A_qq^-1``.
    by_position
        (nodes, states, 2 band + 1): ``A_qs``, its entry for node j at ``band + j - k``.
    """

    lu: np.ndarray
    pivots: np.ndarray
    coupling: np.ndarray
    inverse: np.ndarray
    by_position: np.ndarray


class Stepper(NamedTuple):
    """A BDF integration's state (arrays the steps update in place).

    Attributes
    ----------
    D
        (MAX_ORDER + 3, size): the backward differences; ``D[0]`` is the state.
    J
        The Jacobian in band storage (:func:`~slipwave.solver.quasi_dynamic_steps.jacobian`).
    factors
        The factorised Newton matrix (:class:`Factors`).
    scalars
        t, the step, the order, the equal steps taken, the last step's start, whether
        LU is valid, the c that J was taken for, the longest step, the end, rtol, Newton's
        tolerance, the steps since J was taken.
    atol
        (size,): the absolute tolerances.
    counts
        Steps, evaluations of the right-hand side, Jacobians, factorisations.
    error
        (size,): the last step's local error estimate of each entry, in units of its
        tolerance (the step passed with their RMS at most 1), as LSODE's ACOR scaled.
    """

    D: np.ndarray
    J: np.ndarray
    factors: Factors
    scalars: np.ndarray
    atol: np.ndarray
    counts: np.ndarray
    error: np.ndarray


@njit(cache=True)
def _norm(x: np.ndarray) -> float:
    """The RMS norm, scipy's."""
    return np.sqrt(np.sum(x * x) / x.size)


@njit(cache=True)
def _compute_r(order: int, factor: float) -> np.ndarray:
    """The matrix that changes the differences for a step scaled by ``factor``."""
    M = np.zeros((order + 1, order + 1))
    for i in range(1, order + 1):
        for j in range(1, order + 1):
            M[i, j] = (i - 1 - factor * j) / i
    M[0, :] = 1.0
    for i in range(1, order + 1):  # cumulative product down the columns
        for j in range(order + 1):
            M[i, j] *= M[i - 1, j]
    return M


@njit(cache=True)
def _change_d(D: np.ndarray, order: int, factor: float) -> None:
    """Rescale the differences for a step scaled by ``factor``, in place."""
    RU = _compute_r(order, factor) @ _compute_r(order, 1.0)
    changed = RU.T @ D[:order + 1]
    D[:order + 1] = changed


@njit(cache=True)
def _band_lu(LU: np.ndarray, pivots: np.ndarray, band: int) -> None:
    """LU with partial pivoting of a band matrix, in place (LAPACK's ``dgbtf2``).

    Its band storage transposed, so that a column is contiguous: A[i, j] at
    ``LU[j, 2 band + i - j]``, the first ``band`` places of each column for the fill-in
    of the interchanges.
    """
    n = LU.shape[0]
    kl = ku = band
    kv = kl + ku
    multipliers = np.empty(kl)
    ju = 0
    for j in range(n):
        km = min(kl, n - 1 - j)
        best, jp = -1.0, 0
        for k in range(km + 1):
            value = abs(LU[j, kv + k])
            if value > best:
                best, jp = value, k
        pivots[j] = j + jp
        if LU[j, kv + jp] != 0.0:
            ju = max(ju, min(j + ku + jp, n - 1))
            if jp != 0:
                for col in range(j, ju + 1):
                    a, b = kv + j + jp - col, kv + j - col
                    LU[col, a], LU[col, b] = LU[col, b], LU[col, a]
            pivot = LU[j, kv]
            for k in range(km):
                LU[j, kv + 1 + k] /= pivot
                multipliers[k] = LU[j, kv + 1 + k]
            for col in range(j + 1, ju + 1):
                upper = LU[col, kv + j - col]
                if upper != 0.0:
                    # the column's view and the multipliers' copy are different arrays:
                    # the loop vectorises (twice as fast)
                    below = LU[col, kv + j - col + 1:kv + j - col + 1 + km]
                    for k in range(km):
                        below[k] -= multipliers[k] * upper


@njit(cache=True)
def _band_solve(LU: np.ndarray, pivots: np.ndarray, band: int, b: np.ndarray) -> np.ndarray:
    """Solve with :func:`_band_lu`'s factors (LAPACK's ``dgbtrs``)."""
    n = b.size
    kl = band
    kv = 2 * band
    x = b.copy()
    for j in range(n - 1):
        km = min(kl, n - 1 - j)
        p = pivots[j]
        if p != j:
            x[p], x[j] = x[j], x[p]
        xj = x[j]
        below, factors = x[j + 1:j + 1 + km], LU[j, kv + 1:kv + 1 + km]
        for k in range(km):
            below[k] -= factors[k] * xj
    for j in range(n - 1, -1, -1):
        x[j] /= LU[j, kv]
        xj = x[j]
        first = max(0, j - kv)
        above, factors = x[first:j], LU[j, kv + first - j:kv]
        for i in range(j - first):
            above[i] -= factors[i] * xj
    return x


@njit(cache=True)
def node_band(band: int, per: int) -> int:
    """The nodes on each side that a band of ``band`` entries of y couples to a position.

    Parameters
    ----------
    band
        The Jacobian's half-width in entries of y.
    per
        The entries of y per node: its position, then its states.

    Returns
    -------
    int
        The half-width in nodes.
    """
    return (band - (per - 1)) // per


@njit(cache=True)
def factors_for(size: int, band: int, per: int) -> Factors:
    """Room for :func:`_factorise`'s factors.

    Parameters
    ----------
    size
        The state's size.
    band
        The Jacobian's half-width in entries of y.
    per
        The entries of y per node.

    Returns
    -------
    Factors
        Zeros.
    """
    nodes, states, nb = size // per, per - 1, node_band(band, per)
    return Factors(np.zeros((nodes, 3 * nb + 1)), np.zeros(nodes, dtype=np.int64),
                   np.zeros((nodes, states)), np.zeros((nodes, states, states)),
                   np.zeros((nodes, states, 2 * nb + 1)))


@njit(cache=True)
def _entry(J: np.ndarray, band: int, row: int, column: int) -> float:
    """J[row, column] from its packed band (0 outside it)."""
    if abs(row - column) > band:
        return 0.0
    return J[column, band + row - column]


@njit(cache=True)
def _factorise(J: np.ndarray, c: float, band: int, per: int, factors: Factors) -> None:
    """Factorise ``I - c J`` (J packed within ``band``), each node's states eliminated.

    Parameters
    ----------
    J
        The Jacobian, packed (:func:`~slipwave.solver.quasi_dynamic_steps.jacobian`):
        a node's states couple to its own states and position only.
    c
        The step's coefficient.
    band
        J's half-width in entries.
    per
        The entries of y per node.
    factors
        Filled in place (:class:`Factors`).
    """
    nodes, states, nb = J.shape[0] // per, per - 1, node_band(band, per)
    kv = 2 * nb
    S = factors.lu
    S[:, :] = 0.0
    block = np.empty((states, states))
    for k in range(nodes):
        here = k * per
        for m in range(states):
            for m2 in range(states):
                block[m, m2] = (1.0 if m == m2 else 0.0) - c * _entry(
                    J, band, here + 1 + m, here + 1 + m2)
        inverse = factors.inverse[k]
        if states == 1:
            inverse[0, 0] = 1.0 / block[0, 0]
        else:
            inverse[:, :] = np.linalg.inv(block)
        for m2 in range(states):
            total = 0.0
            for m in range(states):
                total += -c * _entry(J, band, here, here + 1 + m) * inverse[m, m2]
            factors.coupling[k, m2] = total
        for j in range(max(0, k - nb), min(nodes, k + nb + 1)):
            value = (1.0 if j == k else 0.0) - c * _entry(J, band, here, j * per)
            for m in range(states):
                by_position = -c * _entry(J, band, here + 1 + m, j * per)
                factors.by_position[k, m, nb + j - k] = by_position
                value -= factors.coupling[k, m] * by_position
            S[j, kv + k - j] = value
    _band_lu(S, factors.pivots, nb)


@njit(cache=True)
def _solve(factors: Factors, per: int, b: np.ndarray) -> np.ndarray:
    """Solve ``(I - c J) x = b`` with :func:`_factorise`'s factors."""
    nodes, states = factors.coupling.shape
    nb = (factors.by_position.shape[2] - 1) // 2
    reduced = np.empty(nodes)
    for k in range(nodes):
        value = b[k * per]
        for m in range(states):
            value -= factors.coupling[k, m] * b[k * per + 1 + m]
        reduced[k] = value
    positions = _band_solve(factors.lu, factors.pivots, nb, reduced)
    x = np.empty(b.size)
    rest = np.empty(states)
    for k in range(nodes):
        here = k * per
        x[here] = positions[k]
        first, last = max(0, k - nb), min(nodes, k + nb + 1)
        near = positions[first:last]
        for m in range(states):
            row = factors.by_position[k, m, nb - k + first:nb - k + last]
            value = b[here + 1 + m]
            for j in range(last - first):
                value -= row[j] * near[j]
            rest[m] = value
        for m in range(states):
            total = 0.0
            for m2 in range(states):
                total += factors.inverse[k, m, m2] * rest[m2]
            x[here + 1 + m] = total
    return x


@njit(cache=True)
def start(t0: float, y0: np.ndarray, t_bound: float, rtol: float, atol: np.ndarray,
          max_step: float, reduction: Reduction, law: Law, band: int) -> Stepper:
    """A stepper at ``(t0, y0)``, its first step chosen as scipy's ``select_initial_step``.

    Parameters
    ----------
    t0, y0
        The start.
    t_bound
        The end: no step goes beyond it.
    rtol, atol
        The tolerances.
    max_step
        The longest step.
    reduction, law
        The contact (:func:`~slipwave.solver.quasi_dynamic_steps.rates`).
    band
        The Jacobian's half-width.

    Returns
    -------
    Stepper
        At order 1, the Jacobian evaluated.
    """
    size = y0.size
    f0 = rates(t0, y0, reduction, law)
    scale = atol + np.abs(y0) * rtol
    d0, d1 = _norm(y0 / scale), _norm(f0 / scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, t_bound - t0)
    f1 = rates(t0 + h0, y0 + h0 * f0, reduction, law)
    d2 = _norm((f1 - f0) / scale) / h0
    h1 = max(1e-6, h0 * 1e-3) if d1 <= 1e-15 and d2 <= 1e-15 else (
        0.01 / max(d1, d2)) ** 0.5
    h = min(100 * h0, h1, t_bound - t0, max_step)
    D = np.zeros((MAX_ORDER + 3, size))
    D[0] = y0
    D[1] = f0 * h
    scalars = np.array([t0, h, 1.0, 0.0, t0, 0.0, np.inf, max_step, t_bound, rtol,
                        max(10 * np.finfo(np.float64).eps / rtol, min(0.03, rtol ** 0.5)),
                        0.0])
    counts = np.zeros(4, dtype=np.int64)
    counts[EVALUATIONS] = 2
    counts[JACOBIANS] = 1
    return Stepper(D, jacobian(t0, y0, reduction, law, band),
                   factors_for(size, band, 1 + law.b.size), scalars, atol, counts,
                   np.zeros(size))


@njit(cache=True)
def step(s: Stepper, reduction: Reduction, law: Law, band: int) -> int:
    """One BDF step, as scipy's ``BDF._step_impl``.

    Parameters
    ----------
    s
        The stepper, updated in place.
    reduction, law
        The contact.
    band
        The Jacobian's half-width.

    Returns
    -------
    int
        :data:`OK`, or :data:`TOO_SMALL` when the step fell below ten times the spacing
        of doubles at t.
    """
    D, sc = s.D, s.scalars
    t = sc[T]
    order = int(sc[_ORDER])
    min_step = 10 * abs(np.nextafter(t, np.inf) - t)
    h_abs = sc[_H]
    lu_valid = sc[_LU_VALID] != 0.0
    if h_abs > sc[_MAX_STEP]:
        _change_d(D, order, sc[_MAX_STEP] / h_abs)
        h_abs = sc[_MAX_STEP]
        sc[_EQUAL] = 0
        lu_valid = False
    elif h_abs < min_step:
        _change_d(D, order, min_step / h_abs)
        h_abs = min_step
        sc[_EQUAL] = 0
        lu_valid = False
    rtol, atol = sc[_RTOL], s.atol
    current_jac = False
    while True:
        if h_abs < min_step:
            return TOO_SMALL
        t_new = t + h_abs
        if t_new > sc[BOUND]:
            t_new = sc[BOUND]
            _change_d(D, order, (t_new - t) / h_abs)
            sc[_EQUAL] = 0
            lu_valid = False
        h = t_new - t
        h_abs = h
        y_predict = D[0].copy()
        for i in range(1, order + 1):
            y_predict += D[i]
        scale = atol + rtol * np.abs(y_predict)
        psi = np.zeros(y_predict.size)
        for i in range(1, order + 1):
            psi += D[i] * _GAMMA[i]
        psi /= _ALPHA[order]
        c = h / _ALPHA[order]
        # scipy keeps a Jacobian until Newton fails, and within a step it keeps the one
        # taken for a longer try: one taken where the try predicted a fast slip then
        # makes the corrections small without the equation holding, and a step passes
        # over a slip's onset. LSODE's rule: a new one when c has moved by 30 % from
        # the Jacobian's, or after 20 steps.
        if abs(c / sc[_JAC_C] - 1.0) > _JAC_CHANGE or sc[_JAC_AGE] >= _JAC_STEPS:
            s.J[:, :] = jacobian(t_new, y_predict, reduction, law, band)
            s.counts[JACOBIANS] += 1
            sc[_JAC_C], sc[_JAC_AGE] = c, 0.0
            lu_valid = False
            current_jac = True
        converged = False
        while not converged:
            if not lu_valid:
                _factorise(s.J, c, band, 1 + law.b.size, s.factors)
                s.counts[FACTORISATIONS] += 1
                lu_valid = True
            converged, iterations, y_new, d = _newton(s, reduction, law, band, t_new,
                                                     y_predict, c, psi, scale)
            if not converged:
                if current_jac:
                    break
                s.J[:, :] = jacobian(t_new, y_predict, reduction, law, band)
                s.counts[JACOBIANS] += 1
                sc[_JAC_C], sc[_JAC_AGE] = c, 0.0
                lu_valid = False
                current_jac = True
        if not converged:
            h_abs *= 0.5
            _change_d(D, order, 0.5)
            sc[_EQUAL] = 0
            lu_valid = False
            continue
        safety = 0.9 * (2 * _NEWTON_ITERATIONS + 1) / (2 * _NEWTON_ITERATIONS + iterations)
        scale = atol + rtol * np.abs(y_new)
        error = _ERROR_CONSTANT[order] * d / scale
        error_norm = _norm(error)
        if error_norm > 1:
            factor = max(_MIN_FACTOR, safety * error_norm ** (-1.0 / (order + 1)))
            h_abs *= factor
            _change_d(D, order, factor)
            sc[_EQUAL] = 0
            lu_valid = False  # scipy keeps it; its c has changed
            continue
        break
    s.error[:] = error
    s.counts[STEPS] += 1
    sc[_JAC_AGE] += 1
    sc[_EQUAL] += 1
    sc[T_OLD] = t
    sc[T] = t_new
    sc[_H] = h_abs
    D[order + 2] = d - D[order + 1]
    D[order + 1] = d
    for i in range(order, -1, -1):
        D[i] += D[i + 1]
    sc[_LU_VALID] = 1.0 if lu_valid else 0.0
    if sc[_EQUAL] < order + 1:
        return OK
    error_m = _norm(_ERROR_CONSTANT[order - 1] * D[order] / scale) if order > 1 else np.inf
    error_p = (_norm(_ERROR_CONSTANT[order + 1] * D[order + 2] / scale)
               if order < MAX_ORDER else np.inf)
    factors = np.empty(3)
    for k, norm in enumerate((error_m, error_norm, error_p)):
        factors[k] = np.inf if norm == 0.0 else norm ** (-1.0 / (order + k))
    order += int(np.argmax(factors)) - 1
    sc[_ORDER] = order
    factor = min(_MAX_FACTOR, safety * np.max(factors))
    sc[_H] = h_abs * factor
    _change_d(D, order, factor)
    sc[_EQUAL] = 0
    sc[_LU_VALID] = 0.0
    return OK


@njit(cache=True)
def _newton(s: Stepper, reduction: Reduction, law: Law, band: int, t_new: float,
            y_predict: np.ndarray, c: float, psi: np.ndarray, scale: np.ndarray
            ) -> tuple[bool, int, np.ndarray, np.ndarray]:
    """The implicit equation by simplified Newton (scipy's ``solve_bdf_system``)."""
    tol = s.scalars[_NEWTON_TOL]
    d = np.zeros(y_predict.size)
    y = y_predict.copy()
    norm_old = -1.0
    converged = False
    k = 0
    for k in range(_NEWTON_ITERATIONS):
        f = rates(t_new, y, reduction, law)
        s.counts[EVALUATIONS] += 1
        if not np.all(np.isfinite(f)):
            break
        dy = _solve(s.factors, 1 + law.b.size, c * f - psi - d)
        norm = _norm(dy / scale)
        rate = -1.0 if norm_old < 0 else norm / norm_old
        if rate >= 0 and (rate >= 1 or rate ** (_NEWTON_ITERATIONS - k) / (1 - rate) * norm
                          > tol):
            break
        y += dy
        d += dy
        if norm == 0 or (rate >= 0 and rate / (1 - rate) * norm < tol):
            converged = True
            break
        norm_old = norm
    return converged, k + 1, y, d


@njit(cache=True)
def interpolate(s: Stepper, times: np.ndarray) -> np.ndarray:
    """The last step's interpolant at these times (scipy's ``BdfDenseOutput``).

    Parameters
    ----------
    s
        The stepper, after a step.
    times
        Times within the last step.

    Returns
    -------
    numpy.ndarray
        (size, times).
    """
    sc, D = s.scalars, s.D
    order = int(sc[_ORDER])
    h = sc[_H]
    t = sc[T]
    out = np.empty((D.shape[1], times.size))
    for m in range(times.size):
        value = D[0].copy()
        p = 1.0
        for i in range(order):
            p *= (times[m] - (t - h * i)) / (h * (1 + i))
            value += D[i + 1] * p
        out[:, m] = value
    return out
