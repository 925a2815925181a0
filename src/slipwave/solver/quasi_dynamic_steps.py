"""Compiled right-hand side and Jacobian of a contact under rate-and-state friction.

The contact's closed nodes are fixed over a stretch of the integration: the driver
(:mod:`slipwave.solver.quasi_dynamic`) reduces the body onto them
(:class:`Reduction`), and every quantity needed is then an affine map of the closed
nodes' positions s relative to the flat (mm) and of the flat's tangential and normal
positions dx, dy: ``M s + dx m_x + dy m_y + m_0``. The state holds each node's s then
its ln theta (one per state of the law), node after node (:func:`slot`), so that the
Jacobian's entries near its diagonal are a node's own and its neighbours'; an open
node's entries are frozen.

At a closed node of normal force P and shear load tau (the elastic force that
drives it to slip, the flat's force on it with the sign reversed), the slip rate v
balances friction and the radiation damping eta v of the waves it sheds (Rice
1993)::

    |tau| = P a asinh(|v| exp(psi / a) / (2 v0)) + eta |v|,  sign(v) = sign(tau),

solved by Newton's method (:func:`slip_speed`). The system is stiff wherever a node
creeps under a small normal force (its relaxation time a P / (K v) falls to
microseconds as it is about to open), so the driver integrates it implicitly with
the analytic Jacobian (:func:`jacobian`), kept within a band of neighbouring nodes:
the stiffness that sets the steps is a node's own (the condensed stiffness falls off
with distance), and the band's factorisation costs a few hundredths of the dense
one's at 160 elements.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

_NEWTON_ITERATIONS = 80
_NEWTON_TOLERANCE = 1e-13  # on ln|v|: relative on v
_NEGLIGIBLE_LOG = 700.0  # a rate below exp(-700) mm/s: no damping is felt beside friction
# beyond this, exp(-2 x) is below half a double's spacing at 1: 1 + exp(-2 x), tanh(x) and
# 1 - exp(-2 x) are exactly 1, and their transcendentals are skipped
_SATURATED = 20.0
_LOG_TWO = float(np.log(2.0))


class Law(NamedTuple):
    """A rate-and-state law in the steps' units (mm, mm/s) and form.

    Attributes
    ----------
    a
        The direct effect.
    v0
        The reference rate, mm/s.
    mu0
        The steady friction at ``v0``.
    aging
        The aging law (else the slip law).
    b
        Each state's evolution effect.
    log_ratio
        Each state's ln(v0 / Dc).
    dc
        Each state's memory length, mm.
    cutoff_ages
        Each state's ln(Dc / vc), -inf without a cut-off.
    """

    a: float
    v0: float
    mu0: float
    aging: bool
    b: np.ndarray
    log_ratio: np.ndarray
    dc: np.ndarray
    cutoff_ages: np.ndarray


class Reduction(NamedTuple):
    """The body reduced onto its closed nodes, and how the flat moves.

    Each map ``(M, x, y, 0)`` gives ``M s + dx x + dy y + 0`` from the closed nodes'
    positions s relative to the flat: ``loads`` the flat's forces on the closed nodes
    ``[r_x, r_y]`` (per width), ``gaps`` the open nodes' gaps, ``readouts`` T, N (per
    width) and the sensors.

    Attributes
    ----------
    nodes
        The number of contact nodes, n.
    closed
        The closed nodes' indices.
    loads_M, loads_x, loads_y, loads_0
        The loads' map.
    gaps_M, gaps_x, gaps_y, gaps_0
        The gaps' map.
    readouts_M, readouts_x, readouts_y, readouts_0
        The readouts' map; its row 1 sums the normal load.
    flat
        dx at t0, t0, the drive's speed, dy held, the normal load per width, and 1
        under force control (dy then keeps the readouts' row 1 at the load), else 0.
    damping
        Each node's radiation damping, N s/mm per mm of width.
    """

    nodes: int
    closed: np.ndarray
    loads_M: np.ndarray
    loads_x: np.ndarray
    loads_y: np.ndarray
    loads_0: np.ndarray
    gaps_M: np.ndarray
    gaps_x: np.ndarray
    gaps_y: np.ndarray
    gaps_0: np.ndarray
    readouts_M: np.ndarray
    readouts_x: np.ndarray
    readouts_y: np.ndarray
    readouts_0: np.ndarray
    flat: np.ndarray
    damping: np.ndarray


NORMAL_READOUT = 1
"""The readouts' row that sums the normal load."""


@njit(cache=True)
def _log_add_exp(x: float, y: float) -> float:
    """ln(e^x + e^y), with y = -inf for a law without a cut-off."""
    if y == -np.inf:  # no cut-off: the common case, without its two transcendentals
        return x
    m = max(x, y)
    return m + np.log1p(np.exp(-abs(x - y)))


@njit(cache=True)
def slot(node: int, entry: int, law: Law) -> int:
    """Where a node's entry is in the state: 0 its s, 1 + m its m-th ln theta.

    Parameters
    ----------
    node
        The node.
    entry
        0 for s, 1 + m for the m-th state.
    law
        The law (its number of states).

    Returns
    -------
    int
        The index in y.
    """
    return node * (1 + law.b.size) + entry


@njit(cache=True)
def state_part(y: np.ndarray, node: int, law: Law) -> float:
    """Psi at a node: mu0 plus each state's b ln(v0 theta / Dc (+ v0 / vc)).

    Parameters
    ----------
    y
        The state.
    node
        The node.
    law
        The law.

    Returns
    -------
    float
        Psi, as :func:`slipwave.solver.rate_state.state_part` forms it.
    """
    psi = law.mu0
    for k in range(law.b.size):
        psi += law.b[k] * (law.log_ratio[k]
                           + _log_add_exp(y[slot(node, 1 + k, law)], law.cutoff_ages[k]))
    return psi


@njit(cache=True)
def law_friction(log_scaled: float, a: float) -> tuple[float, float]:
    """The law's a asinh(X) and its slope's share X / sqrt(1 + X^2), in logarithms.

    Exact at any psi over a; beyond ln X = 20 both are taken in their limits, exactly
    what doubles hold there.

    Parameters
    ----------
    log_scaled
        ln X, X = abs(v) exp(psi / a) / (2 v0).
    a
        The direct effect.

    Returns
    -------
    tuple
        The friction coefficient, and d asinh(X) / d ln X.
    """
    if log_scaled >= _SATURATED:
        return a * (log_scaled + _LOG_TWO), 1.0
    if log_scaled > 0.0:
        root = np.sqrt(1.0 + np.exp(-2.0 * log_scaled))
        return a * (log_scaled + np.log1p(root)), 1.0 / root
    scaled = np.exp(log_scaled)
    return a * np.arcsinh(scaled), scaled / np.sqrt(1.0 + scaled * scaled)


@njit(cache=True)
def slip_speed(tau: float, pressure: float, psi: float, damping: float, a: float,
               v0: float) -> float:
    """The slip rate at which friction and radiation damping carry a shear load.

    Newton's method on ln abs(v), where the balance is convex: from the smaller of two
    upper bounds (the undamped rate, the damping's alone) it falls to the root without
    overshooting. Everything is formed in logarithms, so that psi / a may be in the
    hundreds (a slab's friction near 1 with a of a few thousandths).

    Parameters
    ----------
    tau
        The shear load, signed.
    pressure
        The normal force P; without compression only the damping holds the node.
    psi
        The states' part of the friction.
    damping
        The radiation damping eta (0: none).
    a
        The direct effect.
    v0
        The reference rate.

    Returns
    -------
    float
        The slip rate, of tau's sign.
    """
    load = abs(tau)
    if load == 0.0:
        return 0.0
    if pressure <= 0.0:
        return tau / damping
    ratio = load / (pressure * a)
    # the undamped rate 2 v0 exp(-psi/a) sinh(ratio), in logarithms
    log_speed = np.log(v0) + ratio - psi / a
    if ratio < _SATURATED:
        log_speed += np.log(-np.expm1(-2.0 * ratio))
    if damping == 0.0 or log_speed <= -_NEGLIGIBLE_LOG:
        return np.exp(log_speed) if tau > 0.0 else -np.exp(log_speed)
    speed = np.exp(log_speed)
    carried = damping * speed
    if carried < load:  # below the rate at which damping alone carries the load
        # Newton's first change from the undamped rate (where friction alone carries the
        # load) is eta v / (P a tanh(ratio) + eta v), taken here; below the tolerance (a
        # node that sticks or creeps) the undamped rate is the root
        slope = pressure * a * (np.tanh(ratio) if ratio < _SATURATED else 1.0)
        change = carried / (slope + carried)
        if change <= _NEWTON_TOLERANCE:
            return speed if tau > 0.0 else -speed
        log_speed -= change
    else:
        log_speed = np.log(load / damping)
    offset = psi / a - np.log(2.0 * v0)  # ln X = ln |v| + offset
    for _ in range(_NEWTON_ITERATIONS):
        speed = np.exp(log_speed)
        friction, share = law_friction(log_speed + offset, a)
        change = (pressure * friction + damping * speed - load) / (
            pressure * a * share + damping * speed)
        log_speed -= change
        # the balance's second derivative in ln|v| is at most its first, so the error
        # left is at most half the change's square
        if change * change <= 2.0 * _NEWTON_TOLERANCE:
            break
    speed = np.exp(log_speed)
    return speed if tau > 0.0 else -speed


@njit(cache=True)
def speed_partials(tau: float, pressure: float, psi: float, damping: float, a: float,
                   v0: float, speed: float) -> tuple[float, float, float]:
    """The slip rate's derivatives in tau, P and psi, at the balance's root.

    From the implicit function: with F_v = P a / sqrt(v^2 + (2 v0 exp(-psi/a))^2) + eta
    (the balance's slope in abs(v)), dv/dtau = 1 / F_v, dv/dP = -sign(tau) mu / F_v and
    dv/dpsi = -sign(tau) P X / (sqrt(1 + X^2) F_v), X = abs(v) exp(psi/a) / (2 v0).

    Parameters
    ----------
    tau, pressure, psi, damping, a, v0
        As :func:`slip_speed`'s.
    speed
        :func:`slip_speed`'s result.

    Returns
    -------
    tuple
        dv/dtau, dv/dP, dv/dpsi.
    """
    if pressure <= 0.0:
        return 1.0 / damping, 0.0, 0.0
    magnitude = abs(speed)
    floor = 2.0 * v0 * np.exp(-psi / a)  # the rate at which X is 1
    spread = np.sqrt(magnitude * magnitude + floor * floor)
    if spread == 0.0:  # stuck beyond what a double holds: nothing moves it
        return 0.0, 0.0, 0.0
    slope = pressure * a / spread + damping
    if magnitude == 0.0:
        return 1.0 / slope, 0.0, 0.0
    sign = 1.0 if tau >= 0.0 else -1.0
    log_scaled = np.log(magnitude) + psi / a - np.log(2.0 * v0)
    friction, share = law_friction(log_scaled, a)
    return 1.0 / slope, -sign * friction / slope, -sign * pressure * share / slope


@njit(cache=True)
def _affine(M: np.ndarray, mx: np.ndarray, my: np.ndarray, m0: np.ndarray,
            s: np.ndarray, dx: float, dy: float, out: np.ndarray) -> None:
    """``out = M s + dx mx + dy my + m0``.

    The product is BLAS's: a loop does not vectorise its sums under strict floating point.
    """
    product = np.dot(M, s) if s.size else np.zeros(out.size)
    for i in range(out.size):
        out[i] = product[i] + dx * mx[i] + dy * my[i] + m0[i]


@njit(cache=True)
def flat_position(t: float, s: np.ndarray, reduction: Reduction) -> tuple[float, float]:
    """The flat's tangential and normal positions at a time.

    Parameters
    ----------
    t
        The time.
    s
        The closed nodes' positions relative to the flat.
    reduction
        The body reduced onto them.

    Returns
    -------
    tuple
        dx, dy: under force control dy is where the normal load is carried.
    """
    flat = reduction.flat
    dx = flat[0] + flat[2] * (t - flat[1])
    if flat[5] == 0.0:
        return dx, flat[3]
    row = reduction.readouts_M[NORMAL_READOUT]
    known = dx * reduction.readouts_x[NORMAL_READOUT] + reduction.readouts_0[NORMAL_READOUT]
    for j in range(s.size):
        known += row[j] * s[j]
    return dx, (flat[4] - known) / reduction.readouts_y[NORMAL_READOUT]


@njit(cache=True)
def _positions(y: np.ndarray, reduction: Reduction, law: Law) -> np.ndarray:
    """The closed nodes' positions s relative to the flat."""
    closed = reduction.closed
    s = np.empty(closed.size)
    for k in range(closed.size):
        s[k] = y[slot(closed[k], 0, law)]
    return s


@njit(cache=True)
def _loads(t: float, y: np.ndarray, reduction: Reduction, law: Law
           ) -> tuple[np.ndarray, float, float]:
    """The closed nodes' ``[r_x, r_y]``, and dx, dy."""
    closed = reduction.closed
    s = _positions(y, reduction, law)
    dx, dy = flat_position(t, s, reduction)
    loads = np.empty(2 * closed.size)
    _affine(reduction.loads_M, reduction.loads_x, reduction.loads_y, reduction.loads_0, s,
            dx, dy, loads)
    return loads, dx, dy


@njit(cache=True)
def rates(t: float, y: np.ndarray, reduction: Reduction, law: Law) -> np.ndarray:
    """The state's time derivative.

    Parameters
    ----------
    t
        The time.
    y
        The state.
    reduction
        The body reduced onto its closed nodes.
    law
        The friction law.

    Returns
    -------
    numpy.ndarray
        dy/dt: the closed nodes' slip rates and state rates, zero at the open ones.
    """
    closed = reduction.closed
    c = closed.size
    loads, _, _ = _loads(t, y, reduction, law)
    out = np.zeros(y.size)
    for k in range(c):
        node = closed[k]
        psi = state_part(y, node, law)
        v = slip_speed(-loads[k], loads[c + k], psi, reduction.damping[node], law.a, law.v0)
        out[slot(node, 0, law)] = v
        for m in range(law.b.size):
            here = slot(node, 1 + m, law)
            rate = abs(v) / law.dc[m]
            if law.aging:
                out[here] = np.exp(-y[here]) - rate
            elif rate > 0.0:
                out[here] = -rate * (np.log(rate) + y[here])
    return out


@njit(cache=True)
def _put(packed: np.ndarray, band: int, row: int, column: int, value: float) -> None:
    """J[row, column] into the packed band, if it falls within it.

    At ``[column, band + row - column]``, so that a column is contiguous.
    """
    if abs(row - column) <= band:
        packed[column, band + row - column] = value


@njit(cache=True)
def jacobian(t: float, y: np.ndarray, reduction: Reduction, law: Law, band: int
             ) -> np.ndarray:
    """The Jacobian of :func:`rates`, analytic, within a band about its diagonal.

    The slip rate's derivatives are :func:`speed_partials`'; the loads' are the reduced
    stiffness's (with the flat's normal position following the closed nodes under
    force control). Entries farther than ``band`` from the diagonal are left out.

    Parameters
    ----------
    t
        The time.
    y
        The state.
    reduction
        The body reduced onto its closed nodes.
    law
        The friction law.
    band
        The half-width kept, in entries of y.

    Returns
    -------
    numpy.ndarray
        (size, 2 band + 1): ``J[i, j]`` at ``[j, band + i - j]``.
    """
    closed = reduction.closed
    c = closed.size
    count = law.b.size
    loads, _, _ = _loads(t, y, reduction, law)
    M, loads_y = reduction.loads_M, reduction.loads_y
    force = reduction.flat[5] != 0.0
    normal_row = reduction.readouts_M[NORMAL_READOUT]
    normal_y = reduction.readouts_y[NORMAL_READOUT]
    packed = np.zeros((y.size, 2 * band + 1))
    by_slip = np.empty(c)
    by_states = np.empty(count)
    for k in range(c):
        node = closed[k]
        row = slot(node, 0, law)
        tau, pressure = -loads[k], loads[c + k]
        psi = state_part(y, node, law)
        eta = reduction.damping[node]
        v = slip_speed(tau, pressure, psi, eta, law.a, law.v0)
        v_tau, v_p, v_psi = speed_partials(tau, pressure, psi, eta, law.a, law.v0, v)
        # closed nodes are distinct and ascending, each taking 1 + count places in y: beyond
        # band // (1 + count) + 1 places in closed, beyond band in y
        reach = band // (1 + count) + 1
        near = range(max(0, k - reach), min(c, k + reach + 1))
        for j in near:
            d_shear, d_normal = M[k, j], M[c + k, j]
            if force:  # the flat's normal position follows the closed nodes' positions
                d_dy = -normal_row[j] / normal_y
                d_shear += loads_y[k] * d_dy
                d_normal += loads_y[c + k] * d_dy
            by_slip[j] = -v_tau * d_shear + v_p * d_normal
            _put(packed, band, row, slot(closed[j], 0, law), by_slip[j])
        for m in range(count):
            # d psi / d ln theta: the cut-off's logaddexp weighs the state's share
            log_theta = y[slot(node, 1 + m, law)]
            share = 1.0 if law.cutoff_ages[m] == -np.inf else 1.0 / (
                1.0 + np.exp(law.cutoff_ages[m] - log_theta))
            by_states[m] = v_psi * law.b[m] * share
            _put(packed, band, row, slot(node, 1 + m, law), by_states[m])
        sign = 1.0 if v >= 0.0 else -1.0
        for m in range(count):
            here = slot(node, 1 + m, law)
            rate = abs(v) / law.dc[m]
            if law.aging:
                by_speed, by_state = -sign / law.dc[m], -np.exp(-y[here])
            elif rate > 0.0:
                by_speed = -sign / law.dc[m] * (np.log(rate) + y[here] + 1.0)
                by_state = -rate
            else:
                by_speed, by_state = 0.0, 0.0
            for j in near:
                _put(packed, band, here, slot(closed[j], 0, law), by_speed * by_slip[j])
            for m2 in range(count):
                _put(packed, band, here, slot(node, 1 + m2, law),
                     by_speed * by_states[m2] + (by_state if m2 == m else 0.0))
    return packed


@njit(cache=True)
def _closed_speeds(loads: np.ndarray, y: np.ndarray, reduction: Reduction, law: Law
                   ) -> np.ndarray:
    """The closed nodes' slip rates under their loads ``[r_x, r_y]`` at state y."""
    closed = reduction.closed
    c = closed.size
    speeds = np.empty(c)
    for k in range(c):
        speeds[k] = slip_speed(-loads[k], loads[c + k], state_part(y, closed[k], law),
                               reduction.damping[closed[k]], law.a, law.v0)
    return speeds


@njit(cache=True)
def step_end(t: float, y: np.ndarray, reduction: Reduction, law: Law, force_scale: float,
             gap_scale: float) -> tuple[float, np.ndarray]:
    """What the driver reads at a step's end: the contact's margin, the slip rates.

    Parameters
    ----------
    t
        The time.
    y
        The state.
    reduction
        The body reduced onto its closed nodes.
    law
        The friction law.
    force_scale, gap_scale
        The normal force and the gap that count as 1 in the margin.

    Returns
    -------
    tuple
        The smallest of the closed nodes' normal forces and the open nodes' gaps, scaled
        (negative where the contact must change: its root is when it does); the closed
        nodes' slip rates, in ``reduction.closed``'s order.
    """
    closed = reduction.closed
    c = closed.size
    loads, dx, dy = _loads(t, y, reduction, law)
    margin = np.inf
    for k in range(c):
        margin = min(margin, loads[c + k] / force_scale)
    speeds = _closed_speeds(loads, y, reduction, law)
    if reduction.gaps_x.size:
        gaps = np.empty(reduction.gaps_x.size)
        _affine(reduction.gaps_M, reduction.gaps_x, reduction.gaps_y, reduction.gaps_0,
                _positions(y, reduction, law), dx, dy, gaps)
        for k in range(gaps.size):
            margin = min(margin, gaps[k] / gap_scale)
    return margin, speeds


@njit(cache=True)
def slip_rates(times: np.ndarray, ys: np.ndarray, reduction: Reduction, law: Law
               ) -> np.ndarray:
    """The closed nodes' slip rates at each of several states, as :func:`step_end`'s.

    Parameters
    ----------
    times
        (k,) the times.
    ys
        (k, size) the states.
    reduction
        The body reduced onto its closed nodes.
    law
        The friction law.

    Returns
    -------
    numpy.ndarray
        (k, closed nodes) the slip rates, in ``reduction.closed``'s order.
    """
    out = np.empty((times.size, reduction.closed.size))
    for m in range(times.size):
        out[m] = _closed_speeds(_loads(times[m], ys[m], reduction, law)[0], ys[m], reduction,
                                law)
    return out


@njit(cache=True)
def readouts(times: np.ndarray, ys: np.ndarray, reduction: Reduction, law: Law
             ) -> np.ndarray:
    """The readouts, then dx and dy, at each time.

    Parameters
    ----------
    times
        The times.
    ys
        (size, times): the state at each.
    reduction
        The body reduced onto its closed nodes.
    law
        The law (the state's layout).

    Returns
    -------
    numpy.ndarray
        (readouts + 2, times).
    """
    closed = reduction.closed
    c = closed.size
    s = np.empty(c)
    count = reduction.readouts_x.size
    rows = np.empty((count + 2, times.size))
    values = np.empty(count)
    for m in range(times.size):
        for k in range(c):
            s[k] = ys[slot(closed[k], 0, law), m]
        dx, dy = flat_position(times[m], s, reduction)
        _affine(reduction.readouts_M, reduction.readouts_x, reduction.readouts_y,
                reduction.readouts_0, s, dx, dy, values)
        rows[:count, m] = values
        rows[count, m] = dx
        rows[count + 1, m] = dy
    return rows
