"""A spring-slider with inertia under rate-and-state friction: the classical friction bench.

A slider of mass M under a normal load N is pulled through a spring of
stiffness K whose far end moves at the drive speed V (Heslot et al. 1994;
Colas et al. 2019). With f the spring's force over the normal load (the
records' F / N), v the slider's speed and theta the interface's state:

    df/dt = (K / N) (V - v)
    M dv/dt = N (f - mu(v, theta))
    d ln(theta)/dt  by the law's evolution (each state's, for a two-state law)

Stick is the regularised law's slow creep, so the system is stiff: at a creep
of 1e-14 m/s the slider's inertia relaxes in under a picosecond, and an arrest
asks an integrator for steps that small. Below a thousandth of the drive's speed
(``INERTIA_SPEED_FRACTION``) the slider is therefore taken as massless (mu = f
at every instant; its inertial time M v / (N a) is then under a microsecond),
and above it inertia is kept, the switch made where the speed crosses that
bound (scipy's event location). Each stretch is integrated by scipy's LSODA,
which switches between Adams and BDF steps as the stiffness changes, with the
analytic Jacobian; a stretch LSODA gives up on is integrated again by Radau,
and the record's ``integrators`` attribute says which ran. With M = 0 the
slider is massless throughout, the form of rsfmodel's velocity steps.

>>> from slipwave.solver.rate_state import RateState
>>> law = RateState(a=0.01, b=0.015, dc=1e-6, mu0=0.4)
>>> bench = SpringSlider(mass=0.0307, stiffness=5000.0, drive_speed=1e-5, normal_load=0.301)
>>> ds = simulate_spring_slider(bench, law, duration=1.0, sample_rate=100.0)
>>> round(float(ds.friction_ratio[-1]), 4)  # stiffer than K_c: it keeps sliding steadily
0.3885
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr
from scipy.integrate import solve_ivp

from slipwave import __version__
from slipwave.defaults import CONVENTIONS
from slipwave.errors import SlipwaveError
from slipwave.solver.quasi_dynamic_steps import slip_speed
from slipwave.solver.rate_state import (
    EXPONENT_CAP,
    RateState,
    cutoff_log_ages,
    slip_rate,
    state_part,
    state_rate,
    states,
    steady_friction,
    steady_state,
)

RELATIVE_TOLERANCE = 1e-8
"""The integrator's relative tolerance on each state variable."""

ABSOLUTE_TOLERANCE = 1e-10
"""The integrator's absolute tolerance on the force ratio and ln(theta)."""

SHORTFALL_TOLERANCE = 1e-12
"""The integrator's absolute tolerance on the friction's shortfall on the spring's force
(M dv/dt / N): LSODA gave up more often with 1e-10 and with 1e-14."""

INTEGRATORS = ("LSODA", "Radau")
"""scipy's methods, in the order tried on each stretch of the integration."""

MAX_STALLED_SWITCHES = 8
"""Switches between the massless and the inertial slider allowed at one instant."""

INERTIA_SPEED_FRACTION = 1e-3
"""Below this fraction of the drive's speed the slider's inertia is left out (M = 0): its
relaxation time M v / (N a) is then under a microsecond at the Colas bench's slowest
drive, and with it an arrest would take the integrator picosecond steps."""


@dataclass(frozen=True)
class SpringSlider:
    """A spring-slider bench.

    Attributes
    ----------
    mass
        The slider's mass M, kg (0: quasi-static).
    stiffness
        The spring's stiffness K, N/m.
    drive_speed
        The speed V of the spring's far end, m/s.
    normal_load
        The normal load N, newtons (M g for a slider lying on a flat).
    damping
        Radiation damping eta, N s/m: a massless slider's resistance to its speed, the
        quasi-dynamic approximation of inertia (Rice 1993), so that the spring's force
        is N mu + eta v. Only with ``mass`` 0.

    """

    mass: float
    stiffness: float
    drive_speed: float
    normal_load: float
    damping: float = 0.0

    def __post_init__(self) -> None:
        if not (self.mass >= 0 and self.stiffness > 0 and self.drive_speed >= 0
                and self.normal_load > 0 and self.damping >= 0):
            raise SlipwaveError(
                "a spring-slider needs mass >= 0, stiffness > 0, drive speed >= 0, normal "
                f"load > 0 and damping >= 0, got {asdict(self)}")
        if self.damping > 0 and self.mass > 0:
            raise SlipwaveError("radiation damping stands for a massless slider's inertia: "
                                f"give mass 0 with damping {self.damping} N s/m")


def _inertial(bench: SpringSlider, law: RateState, drive_speed: float):  # type: ignore[no-untyped-def]
    """Right-hand side and Jacobian of (f, f - mu, ln theta...) for a slider with mass.

    The slider's speed is carried by the friction mu it raises, v = 2 v0 exp(-psi/a)
    sinh(mu / a), and mu by its shortfall on the spring's force, e = f - mu, which
    is M dv/dt / N: in a stick v is a creep of 1e-14 m/s or less that no absolute
    tolerance resolves and e is nothing, while the slip's e is of order 0.1.
    """
    a, v0 = law.a, law.v0
    pairs = states(law)
    lengths = [dc for _, dc in pairs]
    loading, push = bench.stiffness / bench.normal_load, bench.normal_load / bench.mass
    offset = law.mu0 + sum(b * math.log(v0 / dc) for b, dc in pairs)
    aging = law.evolution == "aging"
    count = len(pairs)
    ages = cutoff_log_ages(law)
    # unrolled for one state and an optional second: loops over one or two floats cost
    # more than the arithmetic in this, the integration's innermost call
    first_weight, first_length = pairs[0]
    second_weight, second_length = pairs[-1]

    def state_rate_slope(log_state: float, length: float, magnitude: float
                         ) -> tuple[float, float]:
        """A state's d ln(theta)/dt and its derivative in |v|."""
        if aging:
            return math.exp(min(-log_state, EXPONENT_CAP)) - magnitude / length, -1.0 / length
        if magnitude == 0.0:
            return 0.0, 0.0
        log_ratio = math.log(magnitude / length) + log_state
        return -magnitude / length * log_ratio, -(log_ratio + 1.0) / length

    def term(weight: float, log_state: float, index: int) -> tuple[float, float, float]:
        """A state's term in psi and its first and second derivatives in ln(theta)."""
        if ages is None:
            return weight * log_state, weight, 0.0
        excess = log_state - ages[index]  # ln(theta vc / Dc)
        share = 1.0 / (1.0 + math.exp(min(-excess, EXPONENT_CAP)))
        lifted = (log_state + math.log1p(math.exp(-excess)) if excess > 0
                  else ages[index] + math.log1p(math.exp(excess)))
        return weight * lifted, weight * share, weight * share * (1.0 - share)

    def parts(y: np.ndarray) -> tuple[float, float, float, float, float, list[float],
                                      list[float], list[float], list[float], list[float]]:
        """Shortfall, speed, mu'(v), v'(mu), tanh(mu/a), ln theta, rates, rates'(|v|), psi', psi''.

        The last two: each state's term's derivatives in its ln(theta).
        """
        f, shortfall, *logs = y.tolist()  # plain floats: numpy's scalars are slow here
        mu = f - shortfall
        part, effect, bend = term(first_weight, logs[0], 0)
        psi, effects, bends = offset + part, [effect], [bend]
        if count == 2:
            part, effect, bend = term(second_weight, logs[1], 1)
            psi += part
            effects.append(effect)
            bends.append(bend)
        level = abs(mu) / a
        speed = math.copysign(v0 * math.exp(min(level - psi / a, EXPONENT_CAP))
                              * -math.expm1(-2.0 * level), mu)
        stiffness = a / v0 * math.exp(min(psi / a - level, EXPONENT_CAP)) / (
            1.0 + math.exp(-2.0 * level))
        compliance = v0 / a * math.exp(min(level - psi / a, EXPONENT_CAP)) * (
            1.0 + math.exp(-2.0 * level))
        magnitude = abs(speed)
        rate, slope = state_rate_slope(logs[0], first_length, magnitude)
        rates, slopes = [rate], [slope]
        if count == 2:
            rate, slope = state_rate_slope(logs[1], second_length, magnitude)
            rates.append(rate)
            slopes.append(slope)
        return (shortfall, speed, stiffness, compliance, math.tanh(mu / a), logs, rates,
                slopes, effects, bends)

    def rhs(_: float, y: np.ndarray) -> np.ndarray:
        (shortfall, speed, stiffness, _compliance, direction, _logs, rates, _slopes,
         effects, _bends) = parts(y)
        loading_rate = loading * (drive_speed - speed)
        evolution = effects[0] * rates[0]
        if count == 2:
            evolution += effects[1] * rates[1]
        friction_rate = push * stiffness * shortfall + direction * evolution
        return np.array([loading_rate, loading_rate - friction_rate, *rates])

    def jacobian(_: float, y: np.ndarray) -> np.ndarray:
        (shortfall, speed, stiffness, dv_dmu, direction, logs, rates, slopes, effects,
         bends) = parts(y)
        sign = math.copysign(1.0, speed)
        dv_dstate = [-effect / a * speed for effect in effects]
        # each state's rate in mu and in every ln theta
        drate_dmu = [slope * sign * dv_dmu for slope in slopes]
        drate_dstate = [[slope * sign * dv for dv in dv_dstate] for slope in slopes]
        for i in range(count):
            drate_dstate[i][i] += (-math.exp(min(-logs[i], EXPONENT_CAP)) if aging
                                   else -abs(speed) / lengths[i])
        weighted_rate = sum(e * rate for e, rate in zip(effects, rates, strict=True))
        # the friction's rate, push stiffness e + tanh(mu/a) sum psi' rate, in mu, e, ln theta
        friction_dmu = (-push * stiffness * direction / a * shortfall
                        + (1.0 - direction**2) / a * weighted_rate
                        + direction * sum(e * d for e, d in zip(effects, drate_dmu,
                                                                strict=True)))
        friction_de = push * stiffness
        friction_dstate = [push * stiffness * effects[j] / a * shortfall + direction * (sum(
            effects[i] * drate_dstate[i][j] for i in range(count)) + bends[j] * rates[j])
            for j in range(count)]
        loading_row = [-loading * dv_dmu, loading * dv_dmu, *(-loading * d for d in dv_dstate)]
        friction_row = [friction_dmu, friction_de - friction_dmu, *friction_dstate]
        return np.array([loading_row,
                         [x - z for x, z in zip(loading_row, friction_row, strict=True)],
                         *([d, -d, *row] for d, row in zip(drate_dmu, drate_dstate,
                                                           strict=True))])

    return rhs, jacobian


def _quasi_static(bench: SpringSlider, law: RateState, drive_speed: float):  # type: ignore[no-untyped-def]
    """Right-hand side of (f, ln theta...) for a massless slider (mu = f at every instant)."""
    loading = bench.stiffness / bench.normal_load
    one = law.dc2 is None

    def rhs(_: float, y: np.ndarray) -> np.ndarray:
        log_state = y[1] if one else y[1:]
        v = float(_massless_speed(bench, law, np.array([y[0]]), log_state)[0])
        return np.concatenate([[loading * (drive_speed - v)],
                               np.atleast_1d(state_rate(law, v, log_state))])

    return rhs, None


def _massless_speed(bench: SpringSlider, law: RateState, ratio: np.ndarray,
                    log_state: np.ndarray | float) -> np.ndarray:
    """A massless slider's speed when the spring pulls with ``ratio`` times the load.

    Without damping the law's inverse; with it, the speed at which friction and damping
    together carry the spring's force.
    """
    if bench.damping == 0.0:
        return slip_rate(law, ratio, log_state)
    psi = np.broadcast_to(state_part(law, log_state), ratio.shape)
    load = bench.normal_load
    return np.array([slip_speed(f * load, load, p, bench.damping, law.a, law.v0)
                     for f, p in zip(ratio, psi, strict=True)])


def simulate_spring_slider(
    bench: SpringSlider,
    law: RateState,
    *,
    duration: float,
    sample_rate: float,
    speed_steps: Sequence[tuple[float, float]] = (),
    initial_ratio: float | None = None,
    initial_log_state: float | Sequence[float] | None = None,
    max_evaluations: int | None = None,
) -> xr.Dataset:
    """Drive a spring-slider and record it at a constant sampling rate.

    Parameters
    ----------
    bench
        The slider, its spring and its drive.
    law
        The interface's friction law.
    duration
        The recorded time, s (the record starts at 0).
    sample_rate
        Samples per second.
    speed_steps
        ``(time, speed)`` pairs: from each time on, the drive moves at that speed (m/s)
        instead of ``bench.drive_speed`` (a velocity-step test).
    initial_ratio
        The spring's force over the normal load at time 0; steady sliding at the drive
        speed by default.
    initial_log_state
        ln(theta) at time 0 (theta in s; a two-state law's two); the steady state at the
        drive speed by default.
    max_evaluations
        Evaluations of the right-hand side allowed over the whole integration (all
        integrators and stretches together); ``None``: as many as it takes. A search over
        laws sets it: an integrator can crawl for many minutes on one law.

    Returns
    -------
    xarray.Dataset
        ``friction_ratio`` (the spring's force over the normal load), ``slider_speed``,
        ``log_state`` (and ``log_state_2`` for a two-state law), ``friction`` (the law's
        coefficient), ``slip`` and ``drive_displacement`` over ``time``, with the bench
        and the law as attributes.

    Raises
    ------
    SlipwaveError
        When the bench's numbers are out of range, when both integrators fail (the
        message says why and when), or when the integration needs more than
        ``max_evaluations``.
    """
    if not (duration > 0 and sample_rate > 0):
        raise SlipwaveError(f"duration and sample rate must be > 0, got {duration}, {sample_rate}")
    times = np.arange(int(np.floor(duration * sample_rate + 1e-9)) + 1) / sample_rate
    pieces = _drive_pieces(bench.drive_speed, speed_steps, float(times[-1]))
    start_speed = pieces[0][2]
    steady_speed = start_speed if start_speed > 0 else law.v0
    log_state = np.atleast_1d(steady_state(law, steady_speed) if initial_log_state is None
                              else np.asarray(initial_log_state, dtype=float))
    if log_state.size != len(states(law)):
        raise SlipwaveError(f"the law has {len(states(law))} state(s), the initial state "
                            f"{log_state.size}")
    # steady sliding: the spring carries the law's steady friction and the damping
    steady = float(steady_friction(law, steady_speed)) + (
        bench.damping * steady_speed / bench.normal_load)
    ratio = steady if initial_ratio is None else initial_ratio
    # the slider starts at the speed at which the law carries the spring's force
    state = np.concatenate([[ratio], log_state])
    start_slip = float(slip_rate(law, ratio, log_state[0] if law.dc2 is None else log_state))
    inertial = bench.mass > 0 and start_slip > _slow(law, start_speed)
    columns, used = [], set()
    budget = _Budget(max_evaluations)
    for number, (begin, end, drive_speed) in enumerate(pieces):
        last = number == len(pieces) - 1
        inside = times[(times >= begin) & ((times <= end) if last else (times < end))]
        start, stretch, stalled = begin, inside, 0
        while True:
            state, inertial, reached, rows, method = _integrate(
                bench, law, drive_speed, state, inertial, start, end, stretch, budget)
            stalled = stalled + 1 if reached <= start else 0
            if stalled > MAX_STALLED_SWITCHES:
                raise SlipwaveError(
                    f"the slider's speed keeps crossing {_slow(law, drive_speed):.3g} m/s at "
                    f"t = {start:.6g} s without the integration moving on")
            start = reached
            used.add(method)
            columns.append(rows)
            stretch = stretch[rows.shape[1]:]
            if start >= end:
                break
    values = np.concatenate(columns, axis=1)
    bad = np.flatnonzero(~np.all(np.isfinite(values), axis=0))
    if bad.size:
        raise SlipwaveError(f"the spring-slider's integration gave a non-finite state at "
                            f"t = {times[bad[0]]:.6g} s")
    ds = _to_dataset(bench, law, times, values, pieces)
    ds.attrs["integrators"] = " ".join(sorted(used))
    return ds


class _OverBudgetError(Exception):
    """Raised by a counted right-hand side past its budget."""


class _Budget:
    """The right-hand side's evaluations left to an integration (``None``: no limit)."""

    def __init__(self, evaluations: int | None) -> None:
        self.limit = evaluations
        self.used = 0

    def counted(self, rhs):  # type: ignore[no-untyped-def]
        """``rhs``, raising :class:`_OverBudgetError` once the budget is spent."""
        if self.limit is None:
            return rhs

        def counted_rhs(t: float, y: np.ndarray) -> np.ndarray:
            self.used += 1
            if self.used > self.limit:  # type: ignore[operator]
                raise _OverBudgetError
            return rhs(t, y)

        return counted_rhs


def _slow(law: RateState, drive_speed: float) -> float:
    """The speed below which the slider's inertia is left out, m/s."""
    return INERTIA_SPEED_FRACTION * (drive_speed if drive_speed > 0 else law.v0)


def _integrate(bench: SpringSlider, law: RateState, drive_speed: float, state: np.ndarray,
               inertial: bool, begin: float, end: float, samples: np.ndarray,
               budget: _Budget) -> tuple[np.ndarray, bool, float, np.ndarray, str]:
    """Integrate from ``begin`` until ``end`` or until the slider crosses the slow speed.

    Returns the (f, ln theta...) state where it stopped, whether inertia is kept from
    there, the time it stopped, the rows (f, f - mu, ln theta...) at the samples passed,
    and the method that ran.
    """
    slow = _slow(law, drive_speed)
    count = state.size - 1
    if inertial:
        rhs, jacobian = _inertial(bench, law, drive_speed)
        start = np.concatenate([[state[0], 0.0], state[1:]])
        tolerance = [ABSOLUTE_TOLERANCE, SHORTFALL_TOLERANCE] + [ABSOLUTE_TOLERANCE] * count

        def crossing(_: float, y: np.ndarray) -> float:
            return _log_speed_above(law, y[0] - y[1], y[2:], slow)
    else:
        rhs, jacobian = _quasi_static(bench, law, drive_speed)
        start, tolerance = state, [ABSOLUTE_TOLERANCE] * (1 + count)

        def crossing(_: float, y: np.ndarray) -> float:
            return _log_speed_above(law, y[0], y[1:], slow)
    crossing.terminal = True  # type: ignore[attr-defined]
    # with inertia, a slider slowing down leaves it; without, one speeding up takes it
    crossing.direction = -1.0 if inertial else 1.0  # type: ignore[attr-defined]
    events = crossing if bench.mass > 0 else None
    evaluated = np.append(samples, end) if samples.size == 0 or samples[-1] < end else samples
    failures = []
    for method in INTEGRATORS:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # LSODA's complaints: its status says it all
                solution = solve_ivp(budget.counted(rhs), (begin, end), start, method=method,
                                     jac=jacobian, t_eval=evaluated, events=events,
                                     rtol=RELATIVE_TOLERANCE, atol=tolerance)
        except _OverBudgetError:
            raise SlipwaveError(f"the spring-slider's integration used its {budget.limit} "
                                f"evaluations in the stretch from t = {begin:.6g} s ({method})"
                                ) from None
        except ValueError as error:  # the event's root lost between a step's two ends
            failures.append(f"{method}: {error}")
            continue
        if solution.status >= 0:
            break
        reached = solution.t[-1] if len(solution.t) else begin
        failures.append(f"{method} at t = {reached:.6g} s: {solution.message}")
    else:
        raise SlipwaveError(f"the spring-slider's integration over [{begin:.6g}, {end:.6g}] s "
                            f"failed: {'; '.join(failures)}")
    # an event before the first sample leaves solve_ivp's t and y as empty lists
    passed = np.asarray(solution.t, dtype=float)
    values = np.asarray(solution.y, dtype=float).reshape(start.size, passed.size)
    rows = values[:, :min(samples.size, passed.size)]
    if solution.status == 1:  # the slider crossed the slow speed
        stop, last = float(solution.t_events[0][0]), solution.y_events[0][0]
        rows = rows[:, passed[:rows.shape[1]] <= stop]
    else:
        stop, last = end, values[:, -1]
    if not inertial:
        rows = np.vstack([rows[:1], np.zeros((1, rows.shape[1])), rows[1:]])
    # the state carried on: the spring's force and the states; a slider that slows below
    # the slow speed gives up its (picosecond-scale) inertial shortfall
    carried = np.concatenate([[last[0]], last[-count:]])
    return carried, (not inertial) if solution.status == 1 else inertial, stop, rows, method


def _log_speed_above(law: RateState, mu: float, log_state: np.ndarray, bound: float) -> float:
    """ln(v / bound) for the speed at which the law carries mu (-700 at rest or backwards).

    In logarithms the event is linear in the state between a step's ends, so that its
    root-finder sees the sign change the step saw.
    """
    if mu <= 0.0:
        return -700.0
    psi = float(state_part(law, log_state if law.dc2 is not None else log_state[0]))
    return (math.log(law.v0 / bound) + (mu - psi) / law.a
            + math.log(-math.expm1(-2.0 * mu / law.a)))


def _drive_pieces(drive_speed: float, speed_steps: Sequence[tuple[float, float]],
                  end: float) -> list[tuple[float, float, float]]:
    """(begin, end, drive speed) of each stretch of constant drive speed."""
    steps = sorted((float(t), float(v)) for t, v in speed_steps)
    if any(v < 0 for _, v in steps):
        raise SlipwaveError(f"a drive speed must be >= 0, got the steps {steps}")
    edges = [0.0] + [t for t, _ in steps if 0.0 < t < end] + [end]
    speeds = [drive_speed] + [v for t, v in steps if 0.0 < t < end]
    if steps and steps[0][0] <= 0.0:
        speeds[0] = [v for t, v in steps if t <= 0.0][-1]
    return list(zip(edges[:-1], edges[1:], speeds, strict=True))


def _to_dataset(bench: SpringSlider, law: RateState, times: np.ndarray, values: np.ndarray,
                pieces: list[tuple[float, float, float]]) -> xr.Dataset:
    """The record as a Dataset with CF attributes."""
    ratio, log_state = values[0], values[2]
    state = log_state if law.dc2 is None else values[2:].T
    if bench.damping > 0:
        speed = _massless_speed(bench, law, ratio, state)
        mu = ratio - bench.damping * speed / bench.normal_load
    else:
        mu = ratio - values[1]
        speed = slip_rate(law, mu, state)
    drive = np.zeros_like(times)
    for begin, end, drive_speed in pieces:
        inside = times > begin
        drive[inside] += drive_speed * (np.minimum(times[inside], end) - begin)
    # the slider moved by what the drive moved less what the spring took up
    slip = drive - bench.normal_load / bench.stiffness * (ratio - ratio[0])
    variables = {
        "friction_ratio": (ratio, "1", "the spring's force over the normal load"),
        "slider_speed": (speed, "m s-1", "the slider's speed"),
        "log_state": (log_state, "1", "natural logarithm of the state theta in seconds"),
        **({} if law.dc2 is None else {"log_state_2": (
            values[3], "1", "natural logarithm of the second state theta2 in seconds")}),
        "friction": (mu, "1", "the law's friction coefficient"),
        "slip": (slip, "m", "the slider's displacement"),
        "drive_displacement": (drive, "m", "the displacement of the spring's far end"),
    }
    ds = xr.Dataset(
        {name: ("time", data, {"units": units, "long_name": meaning})
         for name, (data, units, meaning) in variables.items()},
        coords={"time": ("time", times, {"units": "s", "long_name": "time", "axis": "T"})},
    )
    ds.attrs = {
        "Conventions": CONVENTIONS,
        "title": "spring-slider under rate-and-state friction",
        "source": f"slipwave {__version__} spring_slider",
        **{f"bench_{name}": value for name, value in asdict(bench).items()},
        **{f"law_{name}": value for name, value in asdict(law).items()
           if value is not None},  # a one-state law's dc2 is None, which netCDF cannot hold
        "speed_steps": np.array([speed for _, _, speed in pieces]),
        "speed_step_times": np.array([begin for begin, _, _ in pieces]),
    }
    return ds
