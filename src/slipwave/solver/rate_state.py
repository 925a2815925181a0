"""Rate-and-state friction (Dieterich 1979; Ruina 1983), regularised at vanishing slip rate.

The friction coefficient depends on the slip rate v and a state theta (the
contacts' age, a time):

    mu = mu0 + a ln(v / v0) + b ln(v0 theta / Dc)

and theta evolves by the aging law, d theta / dt = 1 - v theta / Dc, or the slip
law, d theta / dt = -(v theta / Dc) ln(v theta / Dc). At vanishing rate the
logarithm has no limit; the regularised form (Rice and Ben-Zion 1996; Lapusta et
al. 2000)

    mu = a asinh(v / (2 v0) exp(psi / a)),  psi = mu0 + b ln(v0 theta / Dc)

equals it to within exp(-2 psi / a) (below 1e-20 here) wherever v is not minute,
and is odd in v, so that a slider at rest carries no friction but what holds it.
The state is carried as its logarithm, which the aging law sends over tens of
decades in a long stick.

A second state theta2, with its own memory length Dc2 and effect b2 (of either sign),
adds b2 ln(v0 theta2 / Dc2) to psi and evolves by the same law (Ruina 1983; Blanpied
and Tullis 1986 for b2 < 0). A two-state law's ``log_state`` carries the two
logarithms on its last axis.

A cut-off speed vc bounds the state's effect for young contacts: each state's term
becomes b ln(v0 theta / Dc + v0 / vc), the logarithm's argument plus a constant (the
form of Okubo 1989's cut-off velocity, QDYN's ``RNS_LAW = 1``, and of the heuristic
law with a cut-off time Dc / vc that Heslot et al. 1994 fitted to paper on paper).
Well below vc the law is the one above; well above it the state's effect is spent and
the steady friction rises as a ln(v): steady sliding strengthens with speed, and fast
slips meet more friction than slow ones.

>>> law = RateState(a=0.01, b=0.015, dc=1e-6, mu0=0.4)
>>> round(float(steady_friction(law, 1e-5)), 6)  # 10 v0: (a - b) ln 10 below mu0
0.388487
>>> round(critical_stiffness(law, normal_load=0.3), 1)  # N/m
1500.0
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from slipwave.errors import SlipwaveError

REFERENCE_SPEED = 1e-6
"""The reference slip rate v0 at which ``mu0`` is the steady friction, m/s."""

EXPONENT_CAP = 300.0
"""Largest argument given to exp(): a trial state of an integrator may ask for absurd
speeds, and exp(300) times any factor of the spring-slider's equations stays finite. The
law is exact while psi / a stays below it (a above 0.002 for friction up to 0.6)."""

EVOLUTION_LAWS = ("aging", "slip")
"""The state's evolution laws: Dieterich's aging law and Ruina's slip law."""


@dataclass(frozen=True)
class RateState:
    """A rate-and-state friction law.

    Attributes
    ----------
    a
        The direct effect: the step in friction per e-fold of the slip rate at fixed state.
    b
        The evolution effect: the step in steady friction per e-fold of the state.
    dc
        The memory length over which the state renews by slip, m.
    mu0
        The steady friction coefficient at the reference rate ``v0``.
    v0
        The reference slip rate, m/s.
    evolution
        ``"aging"`` (Dieterich) or ``"slip"`` (Ruina).
    b2
        The second state's evolution effect (0 with no second state).
    dc2
        The second state's memory length, m (None: a one-state law).
    cutoff_speed
        The cut-off speed vc above which the states' effect is spent, m/s (None: no
        cut-off).

    """

    a: float
    b: float
    dc: float
    mu0: float
    v0: float = REFERENCE_SPEED
    evolution: Literal["aging", "slip"] = "aging"
    b2: float = 0.0
    dc2: float | None = None
    cutoff_speed: float | None = None

    def __post_init__(self) -> None:
        if not (self.a > 0 and self.b >= 0 and self.dc > 0 and self.v0 > 0
                and np.isfinite([self.a, self.b, self.dc, self.mu0, self.v0, self.b2]).all()):
            raise SlipwaveError(
                "rate-and-state friction needs a > 0, b >= 0, dc > 0 and v0 > 0, got "
                f"a={self.a}, b={self.b}, dc={self.dc}, v0={self.v0}")
        if (self.dc2 is None and self.b2 != 0.0) or (
                self.dc2 is not None and not (np.isfinite(self.dc2) and self.dc2 > 0)):
            raise SlipwaveError(
                f"a second state needs a memory length dc2 > 0, got b2={self.b2}, "
                f"dc2={self.dc2}")
        if self.cutoff_speed is not None and not (np.isfinite(self.cutoff_speed)
                                                  and self.cutoff_speed > 0):
            raise SlipwaveError(f"a cut-off speed must be > 0, got {self.cutoff_speed}")
        if self.evolution not in EVOLUTION_LAWS:
            raise SlipwaveError(
                f"unknown state evolution {self.evolution!r}: one of {', '.join(EVOLUTION_LAWS)}")


def states(law: RateState) -> tuple[tuple[float, float], ...]:
    """Each state's evolution effect and memory length, (b, dc) then (b2, dc2).

    Parameters
    ----------
    law
        The friction law.

    Returns
    -------
    tuple
        One (b, dc) pair per state variable, m for dc.
    """
    return ((law.b, law.dc),) if law.dc2 is None else ((law.b, law.dc), (law.b2, law.dc2))


def cutoff_log_ages(law: RateState) -> tuple[float, ...] | None:
    """Each state's cut-off age ln(Dc / vc), below which its effect is spent.

    Parameters
    ----------
    law
        The friction law.

    Returns
    -------
    tuple or None
        ln(Dc / vc) per state (Dc / vc in s); None for a law without a cut-off.
    """
    if law.cutoff_speed is None:
        return None
    return tuple(float(np.log(dc / law.cutoff_speed)) for _, dc in states(law))


def state_part(law: RateState, log_state: np.ndarray | float) -> np.ndarray:
    """The states' part of the friction, psi: mu0 plus each state's term.

    Parameters
    ----------
    law
        The friction law.
    log_state
        The natural logarithm of the state theta (theta in s); a two-state law's two on
        the last axis.

    Returns
    -------
    numpy.ndarray
        psi = mu0 + sum of b ln(v0 theta / Dc) (b ln(v0 theta / Dc + v0 / vc) with a
        cut-off).
    """
    log_state = np.asarray(log_state, dtype=float)
    logs = [log_state] if law.dc2 is None else [log_state[..., i] for i in range(2)]
    ages = cutoff_log_ages(law)
    if ages is not None:
        logs = [np.logaddexp(log, age) for log, age in zip(logs, ages, strict=True)]
    return law.mu0 + sum(b * (np.log(law.v0 / dc) + log)
                         for (b, dc), log in zip(states(law), logs, strict=True))


def friction(law: RateState, speed: np.ndarray | float,
             log_state: np.ndarray | float) -> np.ndarray:
    """The (regularised) friction coefficient.

    Parameters
    ----------
    law
        The friction law.
    speed
        The slip rate, m/s (signed: the friction takes its sign).
    log_state
        The natural logarithm of the state theta (theta in s); a two-state law's two on
        the last axis.

    Returns
    -------
    numpy.ndarray
        The friction coefficient.
    """
    scale = np.exp(np.minimum(state_part(law, log_state) / law.a, EXPONENT_CAP)) / (2.0 * law.v0)
    return law.a * np.arcsinh(np.asarray(speed, dtype=float) * scale)


def slip_rate(law: RateState, friction_coefficient: np.ndarray | float,
              log_state: np.ndarray | float) -> np.ndarray:
    """The slip rate at which the law gives a friction coefficient: :func:`friction`'s inverse.

    Parameters
    ----------
    law
        The friction law.
    friction_coefficient
        The friction the interface carries (the spring's force over the normal load).
    log_state
        The natural logarithm of the state theta (theta in s); a two-state law's two on
        the last axis.

    Returns
    -------
    numpy.ndarray
        The slip rate, m/s.
    """
    mu = np.asarray(friction_coefficient, dtype=float)
    # 2 v0 exp(-psi/a) sinh(mu/a), formed in logarithms: both exponents reach hundreds
    exponent = np.minimum((np.abs(mu) - state_part(law, log_state)) / law.a, EXPONENT_CAP)
    magnitude = law.v0 * np.exp(exponent)
    return np.sign(mu) * magnitude * -np.expm1(-2.0 * np.abs(mu) / law.a)


def state_rate(law: RateState, speed: np.ndarray | float,
               log_state: np.ndarray | float) -> np.ndarray:
    """The time derivative of the state's logarithm, d ln(theta) / dt, 1/s.

    Parameters
    ----------
    law
        The friction law (its ``evolution`` chooses the law).
    speed
        The slip rate, m/s (its magnitude renews the state).
    log_state
        The natural logarithm of the state theta (theta in s); a two-state law's two on
        the last axis.

    Returns
    -------
    numpy.ndarray
        d ln(theta) / dt (each state's, on the last axis, for a two-state law).
    """
    speed = np.asarray(speed, dtype=float)
    log_state = np.asarray(log_state, dtype=float)
    if law.dc2 is None:
        return _one_state_rate(law.evolution, speed, log_state, law.dc)
    return np.stack([_one_state_rate(law.evolution, speed, log_state[..., i], dc)
                     for i, (_, dc) in enumerate(states(law))], axis=-1)


def _one_state_rate(evolution: str, speed: np.ndarray, log_state: np.ndarray, dc: float
                    ) -> np.ndarray:
    """D ln(theta) / dt of one state of memory length dc."""
    rate = np.abs(speed) / dc
    if evolution == "aging":
        return np.exp(-log_state) - rate
    # slip law: -(v theta / dc) ln(v theta / dc) / theta; at v = 0 the state is frozen
    with np.errstate(divide="ignore", invalid="ignore"):
        log_ratio = np.log(np.abs(speed) * np.exp(log_state) / dc)
        return np.where(rate > 0, -rate * log_ratio, 0.0)


def steady_state(law: RateState, speed: np.ndarray | float) -> np.ndarray:
    """The logarithm of the steady state at a slip rate, ln(dc / v).

    Parameters
    ----------
    law
        The friction law.
    speed
        The steady slip rate, m/s (> 0).

    Returns
    -------
    numpy.ndarray
        ln(theta_ss) (each state's, on the last axis, for a two-state law).
    """
    speed = np.asarray(speed, dtype=float)
    if law.dc2 is None:
        return np.log(law.dc / speed)
    return np.stack([np.log(dc / speed) for _, dc in states(law)], axis=-1)


def steady_friction(law: RateState, speed: np.ndarray | float) -> np.ndarray:
    """The friction in steady sliding, about mu0 + (a - b - b2) ln(v / v0) well below vc.

    Parameters
    ----------
    law
        The friction law.
    speed
        The steady slip rate, m/s (> 0).

    Returns
    -------
    numpy.ndarray
        The steady friction coefficient.
    """
    return friction(law, speed, steady_state(law, speed))


def critical_stiffness(law: RateState, normal_load: float, *, mass: float = 0.0,
                       drive_speed: float = 0.0) -> float:
    """The stiffness below which steady sliding is unstable (stick-slip), N/m.

    K_c = N (b - a) / Dc [1 + M V^2 / (N a Dc)] (Ruina 1983; Rice and Ruina 1983, for
    a slider of mass M under a normal load N driven at V): the Routh-Hurwitz bound of
    the law linearised about steady sliding, the same for the aging and the slip law.
    Negative (never unstable) when b < a. With a cut-off speed vc, the state's effect
    about steady sliding at V is b vc / (vc + V) (the derivative of psi in ln(theta)),
    which takes b's place.

    Parameters
    ----------
    law
        The friction law.
    normal_load
        The normal load N, newtons.
    mass
        The slider's mass M, kg (0: quasi-static).
    drive_speed
        The steady sliding speed V, m/s.

    Returns
    -------
    float
        K_c, N/m.

    Raises
    ------
    SlipwaveError
        For a two-state law, whose bound this formula is not (Gu et al. 1984 give it).
    """
    if law.dc2 is not None:
        raise SlipwaveError("the critical stiffness here is a one-state law's; this law has "
                            f"a second state (b2={law.b2}, dc2={law.dc2})")
    inertia = mass * drive_speed**2 / (normal_load * law.a * law.dc)
    effect = law.b if law.cutoff_speed is None else (
        law.b * law.cutoff_speed / (law.cutoff_speed + drive_speed))
    return normal_load * (effect - law.a) / law.dc * (1.0 + inertia)
