"""Multirate steps for the quasi-dynamic contact (issue 37's time target): two designs, measured.

The 280 s test at 320 elements (the mesh at which its fronts converge) takes 2.5 times the
issue's 10 s with the solver's global BDF steps, and the steps hardly grow with the mesh:
each resolves a front's passage and carries every node. An ideal multirate integrator,
each node at its own pace and its coupling free, would do 22 % of the node-steps
(bench_quasi_dynamic.py). The literature's two ways to step the nodes a front crosses
apart from the rest are built here as prototypes on a contact whose closed nodes do not
change, and raced against the solver's own steps:

1. **Multirate BDF, fastest first** (after Gear and Wells 1984): the solver's BDF step
   over the whole contact, with the nodes whose error the last step found above its
   tolerance (a range of closed nodes, with a buffer) integrated first over the step by a
   BDF of their own (its history the macro step's, rescaled), the others' positions
   moving linearly to their predicted values (folded into the range's reduction as the
   flat's drive is); the macro step then solves the other nodes with the range's end
   values held (BDF evaluates only at the step's end), its error and order judged on them
   alone. Its step is the solver's BDF step (:func:`slipwave.solver.stiff_steps.step`)
   with those three changes, so its code repeats the solver's.
2. **A one-step base** (Savcenco, Hundsdorfer and Verwer 2007): ROS2 (Verwer et al. 1999,
   second order whatever the Jacobian), single-rate, and with the nodes whose error
   exceeds the tolerance stepped again over the macro step (the others' positions from the
   macro step's quadratic).

And, for the record, an explicit pair (scipy's RK45) on the same stretches: its steps.

Measured on every stretch of unchanged contact from 100 to 200 s of the 280 s test (the
settled cycle), each started from the solver's own state there: the time and the steps of
each design against the global BDF's, and the fronts' crossings (a node's slip rate
passing ten times the drive's). On the stretch with the most BDF steps (a fast burst) and
on the one with the most crossings, each design against a reference (the global BDF at
10^-8): the crossing times' error. The multirate designs record crossings at their macro
steps' ends, so a node that starts and stops slipping within one is not counted. Target:
the multirate BDF's time, scaled to the whole 280 s test, at most 10 s.

The runs are deterministic: no seed to choose.
Run: make bench  (or python benchmarks/bench_multirate.py)
"""

from __future__ import annotations

import itertools
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import time
from typing import Any, NamedTuple

import numpy as np
from numba import njit
from scipy.integrate import solve_ivp

from bench_quasi_dynamic import DRIVE, LAW, TIME_TARGET
from slipwave.solver import stiff_steps
from slipwave.solver.quasi_dynamic import record_times, simulate_quasi_dynamic, slab_body
from slipwave.solver.quasi_dynamic_steps import (
    Reduction,
    _positions,
    flat_position,
    jacobian,
    rates,
    slip_speed,
    slot,
    speed_partials,
    state_part,
    step_end,
)
from slipwave.solver.slab import Slab
from slipwave.solver.stiff_steps import (
    _ALPHA,
    _ERROR_CONSTANT,
    _GAMMA,
    _JAC_CHANGE,
    _JAC_STEPS,
    _MAX_FACTOR,
    _MIN_FACTOR,
    _NEWTON_ITERATIONS,
    MAX_ORDER,
    Stepper,
    _change_d,
    _factorise,
    _norm,
    _solve,
    factors_for,
)
from targets import check, finish

ELEMENTS = 320
SETTLED = (100.0, 200.0)  # s: the stretches raced, the cycle settled
TOLERANCE = 1e-5  # the solver's
REFERENCE_TOLERANCE = 1e-8
FRONT_SPEED = 10 * DRIVE.drive_speed  # mm/s, the solver's default
SMALLEST_DC = LAW.dc * 1e3  # mm
CROSSINGS_ROOM = 1_000_000
# the multirate BDF's settings: (buffer nodes, the widest range as a share of the closed
# nodes, the error above which a node joins the range)
MULTIRATE = {"a narrow range": (2, 0.3, 1.0), "a range up to 90 % wide": (2, 0.9, 1.0)}
ROS2_GAMMA = 1.0 + 1.0 / np.sqrt(2.0)
# stiff_steps.Stepper.scalars' places
_T, _H, _ORDER, _EQUAL, _T_OLD, _LU_VALID, _JAC_C, _MAX_STEP, _BOUND, _RTOL, _NEWTON_TOL, \
    _JAC_AGE = range(12)
_STEPS, _EVALUATIONS, _JACOBIANS, _FACTORISATIONS = range(4)


class Stretch(NamedTuple):
    """Where a stretch of unchanged contact starts: its state and contact."""

    t: float
    y: np.ndarray
    reduction: Any
    law: Any
    band: int
    end: float


class Run(NamedTuple):
    """A design's run over a stretch."""

    t: float
    steps: int
    fast_steps: int
    seconds: float
    crossing_node: np.ndarray
    crossing_time: np.ndarray


def capture(elements: int, begin: float, end: float) -> tuple[list[Stretch], float]:
    """The 280 s test, timed, and the starts of its stretches from ``begin`` to ``end``."""
    found: list[dict[str, Any]] = []
    start_steps = stiff_steps.start

    def start(t0: float, y0: np.ndarray, t_bound: float, rtol: float, atol: np.ndarray,
              max_step: float, reduction: Any, law: Any, band: int) -> Any:
        if begin <= t0 < end:
            found.append({"t": t0, "y": y0.copy(), "reduction": reduction, "law": law,
                          "band": band})
        return start_steps(t0, y0, t_bound, rtol, atol, max_step, reduction, law, band)

    stiff_steps.start = start  # type: ignore[assignment]
    try:
        began = time.process_time()
        simulate_quasi_dynamic(slab_body(Slab(elements=elements)), LAW, DRIVE, duration=280.0,
                               sample_rate=100.0, field_times=record_times(280.0, 10.0))
        seconds = time.process_time() - began
    finally:
        stiff_steps.start = start_steps
    stretches = [Stretch(**here, end=after["t"]) for here, after in itertools.pairwise(found)]
    return [s for s in stretches if s.end - s.t > 1e-5], seconds


@njit(cache=True)
def _record_crossings(before: np.ndarray, after: np.ndarray, closed: np.ndarray, lo: int,
                      hi: int, begin: float, end: float, front_speed: float,
                      nodes: np.ndarray, times: np.ndarray, count: int) -> int:
    """The closed nodes in [lo, hi) whose slip rate crossed the front speed in a step."""
    for k in range(lo, hi):
        was, now = abs(before[k]), abs(after[k])
        if (was < front_speed) != (now < front_speed):
            share = np.log(front_speed / was) / np.log(now / was)
            nodes[count] = closed[k]
            times[count] = begin + share * (end - begin)
            count += 1
        before[k] = after[k]
    return count


@njit(cache=True)
def _atol(size: int, per: int, tolerance: float, smallest_dc: float) -> np.ndarray:
    """The solver's absolute tolerances: positions in units of D_c, states as they are."""
    atol = np.full(size, tolerance)
    atol[::per] = tolerance * smallest_dc
    return atol


@njit(cache=True)
def global_bdf(t: float, y: np.ndarray, t_end: float, tolerance: float, reduction: Any,
               law: Any, band: int, margin_scales: tuple[float, float], front_speed: float,
               nodes: np.ndarray, times: np.ndarray, spread: np.ndarray
               ) -> tuple[float, np.ndarray, int, int]:
    """The solver's own steps over a stretch; ``spread`` tallies the nodes' paces in fronts.

    spread: [steps in a front (a node above 1 mm/s), then summed over those steps the nodes
    whose own step (err^(-1/(q+1)) of this one) would have been within twice, and within ten
    times, the shortest node's]; empty, none is tallied (a timed run).
    """
    per = 1 + law.b.size
    atol = _atol(y.size, per, tolerance, SMALLEST_DC)
    s = stiff_steps.start(t, y, t_end, tolerance, atol, 0.1, reduction, law, band)
    before = step_end(t, y, reduction, law, margin_scales[0], margin_scales[1])[1]
    closed = reduction.closed
    count = 0
    paces = np.empty(closed.size)
    while s.scalars[_T] < t_end:
        order = s.scalars[_ORDER]
        if stiff_steps.step(s, reduction, law, band) != stiff_steps.OK:
            break
        margin, after = step_end(s.scalars[_T], s.D[0], reduction, law, margin_scales[0],
                                 margin_scales[1])
        if spread.size and np.abs(after).max() > 1.0:
            for k in range(closed.size):
                square = 0.0
                for m in range(per):
                    square += s.error[closed[k] * per + m] ** 2
                paces[k] = (square / per) ** (0.5 / (order + 1.0))
            spread[0] += 1
            spread[1] += np.sum(paces >= 0.5 * paces.max())
            spread[2] += np.sum(paces >= 0.1 * paces.max())
        count = _record_crossings(before, after, closed, 0, closed.size, s.scalars[_T_OLD],
                                  s.scalars[_T], front_speed, nodes, times, count)
        if margin < -1.0:
            break
    return s.scalars[_T], s.D[0].copy(), int(s.counts[_STEPS]), count


# --- the multirate BDF, fastest first ----------------------------------------------------


@njit(cache=True)
def _range_reduction(reduction: Any, lo: int, hi: int, y_a: np.ndarray, y_b: np.ndarray,
                     t_a: float, t_b: float, per: int) -> Any:
    """Closed nodes [lo, hi) as a contact of their own, the others' positions linear in t.

    The others' part of the range's loads, M_rs s_s(t) with s_s linear from y_a to y_b, is
    affine in t and so in the flat's travel dx: it is folded into the range's loads_x and
    loads_0 (the flat's normal position held).
    """
    closed = reduction.closed
    c = closed.size
    first, last = closed[lo], closed[hi - 1]
    width = hi - lo
    M = reduction.loads_M
    flat = reduction.flat
    speed = flat[2]
    dx_a = flat[0] + speed * (t_a - flat[1])
    loads_M = np.empty((2 * width, width))
    by_x, by_y, fixed = np.empty(2 * width), np.empty(2 * width), np.empty(2 * width)
    for r in range(2 * width):
        row = lo + r if r < width else c + lo + r - width
        at_start, rate = 0.0, 0.0
        for k in range(c):
            if lo <= k < hi:
                loads_M[r, k - lo] = M[row, k]
            else:
                i = closed[k] * per
                at_start += M[row, k] * y_a[i]
                rate += M[row, k] * (y_b[i] - y_a[i]) / (t_b - t_a)
        by_x[r] = reduction.loads_x[row] + rate / speed
        by_y[r] = reduction.loads_y[row]
        fixed[r] = reduction.loads_0[row] + at_start - dx_a / speed * rate
    none = np.zeros(0)
    return Reduction(last - first + 1, closed[lo:hi] - first, loads_M, by_x, by_y, fixed,
                     np.zeros((0, width)), none, none, none, np.zeros((2, width)),
                     np.zeros(2), np.zeros(2), np.zeros(2), flat.copy(),
                     reduction.damping[first:last + 1].copy())


@njit(cache=True)
def _fast_range(reduction: Any, law: Any, band: int, lo: int, hi: int, t_a: float,
                t_b: float, y_a: np.ndarray, y_b: np.ndarray, rtol: float, atol: np.ndarray,
                D: np.ndarray, order: int, step: float, work: np.ndarray) -> np.ndarray:
    """The range [lo, hi) from t_a to t_b by a BDF of its own, from the macro history."""
    per = 1 + law.b.size
    closed = reduction.closed
    i0, i1 = closed[lo] * per, (closed[hi - 1] + 1) * per
    sub = _range_reduction(reduction, lo, hi, y_a, y_b, t_a, t_b, per)
    sub_band = min(band, i1 - i0 - 1)
    history = np.ascontiguousarray(D[:, i0:i1]).copy()
    span = t_b - t_a
    if span != step:
        _change_d(history, order, span / step)
    scalars = np.array([t_a, span, float(order), 0.0, t_a, 0.0, np.inf, span, t_b, rtol,
                        max(10 * np.finfo(np.float64).eps / rtol, min(0.03, rtol ** 0.5)),
                        0.0])
    fast = Stepper(history, jacobian(t_a, history[0], sub, law, sub_band),
                   factors_for(i1 - i0, sub_band, per), scalars, atol[i0:i1].copy(),
                   np.zeros(4, dtype=np.int64), np.zeros(i1 - i0))
    while fast.scalars[_T] < t_b:
        if stiff_steps.step(fast, sub, law, sub_band) != stiff_steps.OK:
            break
    work[0] += fast.counts[_STEPS]
    return fast.D[0].copy()


@njit(cache=True)
def _newton_held(s: Any, reduction: Any, law: Any, band: int, t_new: float,
                 y_start: np.ndarray, d_start: np.ndarray, c: float, psi: np.ndarray,
                 scale: np.ndarray, i0: int, i1: int) -> tuple[bool, int, np.ndarray,
                                                             np.ndarray]:
    """stiff_steps._newton with the entries [i0, i1) held at their start."""
    tol = s.scalars[_NEWTON_TOL]
    d, y = d_start.copy(), y_start.copy()
    norm_old = -1.0
    converged = False
    k = 0
    for k in range(_NEWTON_ITERATIONS):
        f = rates(t_new, y, reduction, law)
        s.counts[_EVALUATIONS] += 1
        if not np.all(np.isfinite(f)):
            break
        residual = c * f - psi - d
        residual[i0:i1] = 0.0
        dy = _solve(s.factors, 1 + law.b.size, residual)
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
def _rows_held(J: np.ndarray, band: int, i0: int, i1: int) -> np.ndarray:
    """The packed Jacobian with the rows [i0, i1) zero (their Newton rows the identity)."""
    out = J.copy()
    for row in range(i0, i1):
        for column in range(max(0, row - band), min(J.shape[0], row + band + 1)):
            out[column, band + row - column] = 0.0
    return out


@njit(cache=True)
def _multirate_step(s: Any, reduction: Any, law: Any, band: int, fast: np.ndarray,
                    settings: tuple[int, float, float], work: np.ndarray) -> int:
    """stiff_steps.step, the range ``fast`` ([lo, hi, changed]) first; the next range chosen.

    The changes to the solver's step: the range integrated first and its rows held in
    Newton's iterations; the error and the next order judged on the other nodes.
    """
    buffer, widest, threshold = settings
    D, sc = s.D, s.scalars
    t = sc[_T]
    order = int(sc[_ORDER])
    min_step = 10 * abs(np.nextafter(t, np.inf) - t)
    h_abs = sc[_H]
    per = 1 + law.b.size
    closed = reduction.closed
    c = closed.size
    lo, hi = fast[0], fast[1]
    i0 = closed[lo] * per if hi > lo else 0
    i1 = (closed[hi - 1] + 1) * per if hi > lo else 0
    lu_valid = sc[_LU_VALID] != 0.0 and fast[2] == 0
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
    judged = np.ones(D.shape[1])
    judged[i0:i1] = 0.0
    count = judged.sum()
    while True:
        if h_abs < min_step:
            return stiff_steps.TOO_SMALL
        t_new = t + h_abs
        if t_new > sc[_BOUND]:
            t_new = sc[_BOUND]
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
        c_step = h / _ALPHA[order]
        y_start, d_start = y_predict.copy(), np.zeros(y_predict.size)
        if hi > lo:
            y_fast = _fast_range(reduction, law, band, lo, hi, t, t_new, D[0], y_predict,
                                 rtol, atol, D, order, h, work)
            y_start[i0:i1] = y_fast
            d_start[i0:i1] = y_fast - y_predict[i0:i1]
        if abs(c_step / sc[_JAC_C] - 1.0) > _JAC_CHANGE or sc[_JAC_AGE] >= _JAC_STEPS:
            s.J[:, :] = jacobian(t_new, y_predict, reduction, law, band)
            s.counts[_JACOBIANS] += 1
            sc[_JAC_C], sc[_JAC_AGE] = c_step, 0.0
            lu_valid = False
            current_jac = True
        converged = False
        while not converged:
            if not lu_valid:
                _factorise(_rows_held(s.J, band, i0, i1), c_step, band, per, s.factors)
                s.counts[_FACTORISATIONS] += 1
                lu_valid = True
            converged, iterations, y_new, d = _newton_held(
                s, reduction, law, band, t_new, y_start, d_start, c_step, psi, scale, i0, i1)
            if not converged:
                if current_jac:
                    break
                s.J[:, :] = jacobian(t_new, y_predict, reduction, law, band)
                s.counts[_JACOBIANS] += 1
                sc[_JAC_C], sc[_JAC_AGE] = c_step, 0.0
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
        error_norm = np.sqrt(np.sum((error * judged) ** 2) / count)
        if error_norm > 1:
            factor = max(_MIN_FACTOR, safety * error_norm ** (-1.0 / (order + 1)))
            h_abs *= factor
            _change_d(D, order, factor)
            sc[_EQUAL] = 0
            lu_valid = False
            continue
        break
    # the next range: the nodes whose error (the range's as the macro step would have had
    # it) is above the threshold, with a buffer, unless it is wider than the widest
    new_lo, new_hi = c, 0
    for k in range(c):
        square = 0.0
        for m in range(per):
            square += error[closed[k] * per + m] ** 2
        if np.sqrt(square / per) > threshold:
            new_lo, new_hi = min(new_lo, k), max(new_hi, k + 1)
    new_lo, new_hi = max(0, new_lo - buffer), min(c, new_hi + buffer)
    if new_hi <= new_lo or new_hi - new_lo > widest * c:
        new_lo, new_hi = 0, 0
    fast[2] = 1 if (new_lo != lo or new_hi != hi) else 0
    fast[0], fast[1] = new_lo, new_hi
    s.error[:] = error
    s.counts[_STEPS] += 1
    sc[_JAC_AGE] += 1
    sc[_EQUAL] += 1
    sc[_T_OLD] = t
    sc[_T] = t_new
    sc[_H] = h_abs
    D[order + 2] = d - D[order + 1]
    D[order + 1] = d
    for i in range(order, -1, -1):
        D[i] += D[i + 1]
    sc[_LU_VALID] = 1.0 if lu_valid else 0.0
    if sc[_EQUAL] < order + 1:
        return stiff_steps.OK
    error_m = np.sqrt(np.sum((_ERROR_CONSTANT[order - 1] * D[order] / scale * judged) ** 2)
                      / count) if order > 1 else np.inf
    error_p = np.sqrt(np.sum((_ERROR_CONSTANT[order + 1] * D[order + 2] / scale * judged) ** 2)
                      / count) if order < MAX_ORDER else np.inf
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
    return stiff_steps.OK


@njit(cache=True)
def multirate_bdf(t: float, y: np.ndarray, t_end: float, tolerance: float, reduction: Any,
                  law: Any, band: int, margin_scales: tuple[float, float], front_speed: float,
                  settings: tuple[int, float, float], nodes: np.ndarray, times: np.ndarray,
                  ranges: np.ndarray) -> tuple[float, np.ndarray, int, int, int]:
    """The multirate BDF over a stretch: the end, its state, macro steps, fast steps, crossings.

    ``ranges`` tallies the steps with a fast range, its widths, and the changes of range.
    """
    atol = _atol(y.size, 1 + law.b.size, tolerance, SMALLEST_DC)
    s = stiff_steps.start(t, y, t_end, tolerance, atol, 0.1, reduction, law, band)
    before = step_end(t, y, reduction, law, margin_scales[0], margin_scales[1])[1]
    closed = reduction.closed
    count = 0
    work = np.zeros(1, dtype=np.int64)
    fast = np.zeros(3, dtype=np.int64)
    while s.scalars[_T] < t_end:
        width = fast[1] - fast[0]
        if _multirate_step(s, reduction, law, band, fast, settings, work) != stiff_steps.OK:
            break
        if width > 0:
            ranges[0] += 1
            ranges[1] += width
            ranges[2] += fast[2]
        margin, after = step_end(s.scalars[_T], s.D[0], reduction, law, margin_scales[0],
                                 margin_scales[1])
        count = _record_crossings(before, after, closed, 0, closed.size, s.scalars[_T_OLD],
                                  s.scalars[_T], front_speed, nodes, times, count)
        if margin < -1.0:
            break
    return s.scalars[_T], s.D[0].copy(), int(s.counts[_STEPS]), int(work[0]), count


# --- ROS2, single-rate and multirate -------------------------------------------------------


@njit(cache=True)
def _rates_range(t: float, y: np.ndarray, reduction: Any, law: Any, lo: int, hi: int,
                 out: np.ndarray, speeds: np.ndarray) -> None:
    """:func:`rates` of the closed nodes [lo, hi) into ``out``, their slip rates into ``speeds``."""
    closed = reduction.closed
    c = closed.size
    s = _positions(y, reduction, law)
    dx, dy = flat_position(t, s, reduction)
    shear = np.dot(reduction.loads_M[lo:hi], s)
    normal = np.dot(reduction.loads_M[c + lo:c + hi], s)
    for k in range(lo, hi):
        r_x = (shear[k - lo] + dx * reduction.loads_x[k] + dy * reduction.loads_y[k]
               + reduction.loads_0[k])
        r_y = (normal[k - lo] + dx * reduction.loads_x[c + k] + dy * reduction.loads_y[c + k]
               + reduction.loads_0[c + k])
        node = closed[k]
        v = slip_speed(-r_x, r_y, state_part(y, node, law), reduction.damping[node], law.a,
                       law.v0)
        speeds[k] = v
        out[slot(node, 0, law)] = v
        for m in range(law.b.size):
            here = slot(node, 1 + m, law)
            rate = abs(v) / law.dc[m]
            if law.aging:
                out[here] = np.exp(-y[here]) - rate
            else:
                out[here] = -rate * (np.log(rate) + y[here]) if rate > 0.0 else 0.0


@njit(cache=True)
def _jacobian_range(t: float, y: np.ndarray, reduction: Any, law: Any, band: int, lo: int,
                    hi: int, i0: int) -> np.ndarray:
    """:func:`jacobian`'s rows and columns of the closed nodes [lo, hi), packed from ``i0``.

    Laws without a cut-off (the benchmark's).
    """
    closed = reduction.closed
    c = closed.size
    count = law.b.size
    s = _positions(y, reduction, law)
    dx, dy = flat_position(t, s, reduction)
    M = reduction.loads_M
    packed = np.zeros(((closed[hi - 1] + 1) * (1 + count) - i0, 2 * band + 1))
    reach = band // (1 + count) + 1
    by_slip = np.empty(c)
    by_states = np.empty(count)
    for k in range(lo, hi):
        node = closed[k]
        tau = -(np.dot(M[k], s) + dx * reduction.loads_x[k] + dy * reduction.loads_y[k]
                + reduction.loads_0[k])
        pressure = (np.dot(M[c + k], s) + dx * reduction.loads_x[c + k]
                    + dy * reduction.loads_y[c + k] + reduction.loads_0[c + k])
        psi = state_part(y, node, law)
        eta = reduction.damping[node]
        v = slip_speed(tau, pressure, psi, eta, law.a, law.v0)
        v_tau, v_p, v_psi = speed_partials(tau, pressure, psi, eta, law.a, law.v0, v)
        row = slot(node, 0, law) - i0
        near_lo, near_hi = max(lo, k - reach), min(hi, k + reach + 1)
        for j in range(near_lo, near_hi):
            by_slip[j] = -v_tau * M[k, j] + v_p * M[c + k, j]
            column = slot(closed[j], 0, law) - i0
            if abs(row - column) <= band:
                packed[column, band + row - column] = by_slip[j]
        for m in range(count):
            by_states[m] = v_psi * law.b[m]
            packed[row + 1 + m, band - 1 - m] = by_states[m]
        sign = 1.0 if v >= 0.0 else -1.0
        for m in range(count):
            here = row + 1 + m
            log_theta = y[slot(node, 1 + m, law)]
            rate = abs(v) / law.dc[m]
            if law.aging:
                by_speed, by_state = -sign / law.dc[m], -np.exp(-log_theta)
            else:
                by_speed = -sign / law.dc[m] * (np.log(rate) + log_theta + 1.0) if rate else 0.0
                by_state = -rate
            for j in range(near_lo, near_hi):
                column = slot(closed[j], 0, law) - i0
                if abs(here - column) <= band:
                    packed[column, band + here - column] = by_speed * by_slip[j]
            for m2 in range(count):
                column = row + 1 + m2
                packed[column, band + here - column] = by_speed * by_states[m2] + (
                    by_state if m2 == m else 0.0)
    return packed


@njit(cache=True)
def _node_errors(estimate: np.ndarray, y0: np.ndarray, y1: np.ndarray, atol: np.ndarray,
                 rtol: float, closed: np.ndarray, per: int, lo: int, hi: int,
                 out: np.ndarray) -> float:
    """Each closed node's error (the RMS of its entries' in tolerances); the largest."""
    worst = 0.0
    for k in range(lo, hi):
        square = 0.0
        for m in range(per):
            i = closed[k] * per + m
            square += (estimate[i] / (atol[i] + rtol * max(abs(y0[i]), abs(y1[i])))) ** 2
        out[k] = np.sqrt(square / per)
        worst = max(worst, out[k])
    return worst


@njit(cache=True)
def _others_at(y: np.ndarray, t: float, closed: np.ndarray, per: int, lo: int, hi: int,
               quadratic: np.ndarray, t0: float, span: float) -> None:
    """The closed positions outside [lo, hi) at t, from the macro step's quadratic."""
    share = (t - t0) / span
    for k in range(closed.size):
        if not lo <= k < hi:
            i = closed[k] * per
            y[i] = quadratic[0, i] + share * (quadratic[1, i] + share * quadratic[2, i])


@njit(cache=True)
def _ros2_step(t: float, h: float, y: np.ndarray, f0: np.ndarray, reduction: Any, law: Any,
               band: int, lo: int, hi: int, quadratic: np.ndarray, t0: float, span: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """ROS2 over the closed nodes [lo, hi); the others from ``quadratic`` (span 0: frozen)."""
    closed = reduction.closed
    per = 1 + law.b.size
    i0, i1 = closed[lo] * per, (closed[hi - 1] + 1) * per
    factors = factors_for(i1 - i0, band, per)
    _factorise(_jacobian_range(t, y, reduction, law, band, lo, hi, i0), ROS2_GAMMA * h, band,
               per, factors)
    k1 = _solve(factors, per, f0[i0:i1])
    y1 = y.copy()
    if span > 0.0:
        _others_at(y1, t + h, closed, per, lo, hi, quadratic, t0, span)
    y1[i0:i1] += h * k1
    f1 = np.zeros(y.size)
    _rates_range(t + h, y1, reduction, law, lo, hi, f1, np.empty(closed.size))
    k2 = _solve(factors, per, f1[i0:i1] - 2.0 * k1)
    y1[i0:i1] = y[i0:i1] + 1.5 * h * k1 + 0.5 * h * k2
    estimate = np.zeros(y.size)
    estimate[i0:i1] = 0.5 * h * (k1 + k2)
    return y1, estimate


@njit(cache=True)
def ros2(t: float, y: np.ndarray, t_end: float, tolerance: float, reduction: Any, law: Any,
         band: int, margin_scales: tuple[float, float], front_speed: float, multirate: bool,
         nodes: np.ndarray, times: np.ndarray) -> tuple[float, np.ndarray, int, int, int]:
    """ROS2 over a stretch, single-rate or multirate (the nodes above the tolerance again).

    Returns the end, its state, macro steps, the multirate's steps of the refined range, and
    the crossings.
    """
    closed = reduction.closed
    c = closed.size
    per = 1 + law.b.size
    atol = _atol(y.size, per, tolerance, SMALLEST_DC)
    f0 = np.zeros(y.size)
    speeds = np.empty(c)
    _rates_range(t, y, reduction, law, 0, c, f0, speeds)
    before = speeds.copy()
    errors = np.empty(c)
    macro, fine, count = 0, 0, 0
    h = 1e-6
    quadratic = np.zeros((3, y.size))
    while t < t_end:
        h = min(h, t_end - t)
        y1, estimate = _ros2_step(t, h, y, f0, reduction, law, band, 0, c, quadratic, t, 0.0)
        worst = _node_errors(estimate, y, y1, atol, tolerance, closed, per, 0, c, errors)
        lo, hi = c, 0
        if worst > 1.0:
            for k in range(c):
                if errors[k] > 1.0:
                    lo, hi = min(lo, k), max(hi, k + 1)
            lo, hi = max(0, lo - 4), min(c, hi + 4)
        if worst > 1.0 and (not multirate or hi - lo > c // 2):
            h *= max(0.2, 0.9 * worst ** -0.5)
            continue
        slow = 0.0
        for k in range(c):
            if not lo <= k < hi:
                slow = max(slow, errors[k])
        if hi > lo:  # the range again over the macro step, the others from its quadratic
            quadratic[0], quadratic[1] = y, h * f0
            quadratic[2] = y1 - y - h * f0
            i0, i1 = closed[lo] * per, (closed[hi - 1] + 1) * per
            y_fine, f_fine, t_fine = y.copy(), f0.copy(), t
            h_fine = h * max(0.05, 0.9 * worst ** -0.5)
            while t_fine < t + h:
                h_fine = min(h_fine, t + h - t_fine)
                _others_at(y_fine, t_fine, closed, per, lo, hi, quadratic, t, h)
                y2, estimate = _ros2_step(t_fine, h_fine, y_fine, f_fine, reduction, law, band,
                                          lo, hi, quadratic, t, h)
                worst_fine = _node_errors(estimate, y_fine, y2, atol, tolerance, closed, per,
                                          lo, hi, errors)
                if worst_fine > 1.0:
                    h_fine *= max(0.2, 0.9 * worst_fine ** -0.5)
                    continue
                fine += 1
                t_fine += h_fine
                y_fine = y2
                _rates_range(t_fine, y_fine, reduction, law, lo, hi, f_fine, speeds)
                count = _record_crossings(before, speeds, closed, lo, hi, t_fine - h_fine,
                                          t_fine, front_speed, nodes, times, count)
                h_fine *= min(5.0, max(0.2, 0.9 * max(worst_fine, 1e-10) ** -0.5))
            y1[i0:i1] = y_fine[i0:i1]
        macro += 1
        t += h
        y = y1
        margin = step_end(t, y, reduction, law, margin_scales[0], margin_scales[1])[0]
        _rates_range(t, y, reduction, law, 0, c, f0, speeds)
        count = _record_crossings(before, speeds, closed, 0, lo if hi > lo else c, t - h, t,
                                  front_speed, nodes, times, count)
        if hi > lo:
            count = _record_crossings(before, speeds, closed, hi, c, t - h, t, front_speed,
                                      nodes, times, count)
        if margin < -1.0:
            break
        h = min(0.1, h * min(5.0, max(0.2, 0.9 * max(slow, 1e-10) ** -0.5)))
    return t, y, macro, fine, count


# --- the race ---------------------------------------------------------------------------


def race(design: str, stretch: Stretch, end: float, tolerance: float,
         margin_scales: tuple[float, float], option: Any = None,
         ranges: np.ndarray | None = None) -> Run:
    """One design over a stretch, timed (``ranges``: :func:`multirate_bdf`'s tally)."""
    nodes = np.zeros(CROSSINGS_ROOM, dtype=np.int64)
    times = np.zeros(CROSSINGS_ROOM)
    arguments = (stretch.t, stretch.y.copy(), end, tolerance, stretch.reduction, stretch.law,
                 stretch.band, margin_scales, FRONT_SPEED)
    began = time.process_time()
    if design == "bdf":
        t, _, steps, count = global_bdf(*arguments, nodes, times, np.zeros(0, dtype=np.int64))
        fast = 0
    elif design == "multirate bdf":
        tally = np.zeros(3, dtype=np.int64) if ranges is None else ranges
        t, _, steps, fast, count = multirate_bdf(*arguments, option, nodes, times, tally)
    else:
        t, _, steps, fast, count = ros2(*arguments, option, nodes, times)
    return Run(t, steps, fast, time.process_time() - began, nodes[:count], times[:count])


def crossing_errors(reference: Run, other: Run) -> tuple[float, float, int, int]:
    """Each node's crossing times against the reference's, in order: median, largest, counts."""
    differences: list[float] = []
    for node in np.unique(reference.crossing_node):
        mine = reference.crossing_time[reference.crossing_node == node]
        theirs = other.crossing_time[other.crossing_node == node]
        common = min(mine.size, theirs.size)
        differences.extend(np.abs(mine[:common] - theirs[:common]))
    found = np.array(differences) if differences else np.zeros(1)
    return (float(np.median(found)), float(found.max()), other.crossing_node.size,
            reference.crossing_node.size)


def against_reference(name: str, candidates: list[Stretch],
                      margin_scales: tuple[float, float]) -> Stretch:
    """Each design against the global BDF at 10^-8 on the first candidate it runs through.

    A stretch that starts at a contact's change can end at once at the reference's tolerance
    (a node's margin then within the steps' error): the next candidate is taken.
    """
    for stretch in candidates:
        end = stretch.end - 2e-5
        reference = race("bdf", stretch, end, REFERENCE_TOLERANCE, margin_scales)
        if reference.t >= end:
            break
    print(f"multirate: {name}, {stretch.t:.4f} to {end:.4f} s: the reference (global BDF at "
          f"{REFERENCE_TOLERANCE:g}) {reference.steps} steps, {reference.crossing_node.size} "
          f"crossings")
    runs = [("global BDF", "bdf", TOLERANCE, None),
            ("global BDF at 1e-4", "bdf", 1e-4, None)]
    runs += [(f"multirate BDF, {label}", "multirate bdf", TOLERANCE, settings)
             for label, settings in MULTIRATE.items()]
    runs += [(f"ROS2 at {tol:g}", "ros2", tol, False) for tol in (1e-5, 1e-4, 1e-3)]
    runs += [("multirate ROS2 at 1e-4", "ros2", 1e-4, True)]
    with np.errstate(all="ignore"):  # a trial step far too long overflows; RK45 rejects it
        explicit = solve_ivp(rates, (stretch.t, end), stretch.y, method="RK45",
                             rtol=TOLERANCE, atol=_atol(stretch.y.size, 1 + stretch.law.b.size,
                                                        TOLERANCE, SMALLEST_DC),
                             args=(stretch.reduction, stretch.law))
    print(f"    explicit (scipy's RK45, Dormand-Prince 5(4), at {TOLERANCE:g}): "
          f"{explicit.t.size - 1} steps")
    for label, design, tolerance, option in runs:
        run = race(design, stretch, end, tolerance, margin_scales, option)
        median, largest, count, expected = crossing_errors(reference, run)
        fast = f" + {run.fast_steps} of the fast range" if design != "bdf" else ""
        print(f"    {label}: {run.steps} steps{fast}, {run.seconds:.3f} s, to {run.t:.4f} s; "
              f"crossings {count} of {expected}, their times off by {median:.1e} s (median), "
              f"{largest:.1e} s at most")
    return stretch


def main() -> None:
    print(f"multirate: load average {os.getloadavg()[0]:.2f} before")
    body = slab_body(Slab(elements=ELEMENTS))
    normal_w = DRIVE.normal_load / body.width

    def scales_at(tolerance: float) -> tuple[float, float]:
        return tolerance * normal_w / body.nodes, tolerance * SMALLEST_DC

    stretches, whole_test = capture(ELEMENTS, *SETTLED)
    print(f"multirate: the 280 s test at {ELEMENTS} elements, global BDF: {whole_test:.1f} s; "
          f"{len(stretches)} stretches of unchanged contact from {SETTLED[0]:.0f} to "
          f"{SETTLED[1]:.0f} s raced")
    designs = [("global BDF", "bdf", None)] + [
        (f"multirate BDF, {label}", "multirate bdf", settings)
        for label, settings in MULTIRATE.items()]
    first = stretches[0]
    for design, option in [(design, option) for _, design, option in designs] + [
            ("ros2", False), ("ros2", True)]:  # compiled before the races
        race(design, first, first.t + 1e-3, TOLERANCE, scales_at(TOLERANCE), option)
    totals = {label: np.zeros(4) for label, _, _ in designs}
    ranges = {label: np.zeros(3, dtype=np.int64) for label, _, _ in designs}
    spread = np.zeros(3, dtype=np.int64)
    steps_of: dict[float, int] = {}
    crossings_of: dict[float, int] = {}
    for stretch in stretches:
        for label, design, option in designs:
            run = race(design, stretch, stretch.end, TOLERANCE, scales_at(TOLERANCE), option,
                       ranges[label])
            totals[label] += (run.seconds, run.steps, run.fast_steps, run.crossing_node.size)
            if design == "bdf":
                steps_of[stretch.t], crossings_of[stretch.t] = run.steps, run.crossing_node.size
        # the nodes' paces, tallied apart: a timed run does no more than the solver's steps
        global_bdf(stretch.t, stretch.y.copy(), stretch.end, TOLERANCE, stretch.reduction,
                   stretch.law, stretch.band, scales_at(TOLERANCE), FRONT_SPEED,
                   np.zeros(CROSSINGS_ROOM, dtype=np.int64), np.zeros(CROSSINGS_ROOM), spread)
    closed = int(np.median([s.reduction.closed.size for s in stretches]))
    print(f"multirate: in a front (a node above 1 mm/s; {spread[0]} of the global BDF's "
          f"steps), of the about {closed} closed nodes, {spread[1] / max(spread[0], 1):.0f} "
          f"on average could have stepped alone at most twice as long as the node that "
          f"needed the shortest step (err^(-1/(q+1)) of the step), and "
          f"{spread[2] / max(spread[0], 1):.0f} at most ten times as long")
    base = totals["global BDF"]
    for label, (seconds, steps, fast, crossings) in totals.items():
        print(f"multirate: {label}: {seconds:.2f} s ({seconds / base[0]:.2f} of the global "
              f"BDF's), {steps:.0f} steps ({steps / base[1]:.2f})"
              f"{f' + {fast:.0f} of the fast range' if fast else ''}, {crossings:.0f} "
              f"crossings")
        with_range, widths, changes = ranges[label]
        if with_range:
            print(f"    the fast range in {with_range} steps, {widths / with_range:.0f} closed "
                  f"nodes wide on average, changed (its BDF started again) after "
                  f"{100 * changes / with_range:.0f} % of them")
    best = min(totals[label][0] for label, _, _ in designs[1:])
    projected = whole_test * best / base[0]
    status = check("280 s test at 320 elements with multirate BDF steps (scaled), s",
                   projected, TIME_TARGET, at_least=False)
    fewest = min(totals[label][1] for label, _, _ in designs[1:])
    print(f"multirate: the multirate BDF scaled to the whole test: {projected:.1f} s ({status} "
          f"the {TIME_TARGET:.0f} s target); with its fast range free and its macro steps at "
          f"today's cost, at best {whole_test * fewest / base[1]:.1f} s")
    # the contact's margin in the solver's units whatever the steps' tolerance
    by_steps = sorted(stretches, key=lambda s: -steps_of[s.t])
    taken = against_reference("the stretch with the most steps", by_steps,
                              scales_at(TOLERANCE))
    by_crossings = sorted((s for s in stretches if s is not taken),
                          key=lambda s: -crossings_of[s.t])
    against_reference("the stretch with the most crossings of the others", by_crossings,
                      scales_at(TOLERANCE))
    finish()


if __name__ == "__main__":
    main()
