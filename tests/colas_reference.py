"""A slip detector in the manner of Colas et al. (2019), to judge ``load_drops`` on their records.

Their published analysis (npusteln/stickslip, CeCILL-B): denoise F/mg by L2-L1
minimisation with a second-difference operator ([1/4, -1/2, 1/4], lambda = 0.8),
compute the slider's velocity v = V - (m g / K) f_a dF, and call a slip every run
where v >= 10 x 40 um/s, extended both ways while v > 40 um/s. Here the L2-L1
problem is solved to a duality gap of 1e-4 by a primal-dual interior-point method (an
earlier ADMM of 1000 steps stopped 1.7 % above the optimum on k168 v42 and took four
times longer); on k168 v42 it gives the authors' 232 published events
(../shared/data/colas2019/reference), onsets on theirs to the sample (median 0, at most
43 samples apart), 215 of them significant as theirs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.io
import scipy.linalg

DATA = Path(__file__).parents[1].parent / "shared" / "data" / "colas2019"
MASS, GRAVITY, RATE = 30.7e-3, 9.81, 2000.0  # kg, m/s^2, Hz
NOISE_SPEED = 40.0  # um/s, the authors' th_noise
SIGNIFICANT = 0.02  # F/mg fall between an event's maximum and its stop


def record(stiffness: int, speed: int) -> tuple[np.ndarray, np.ndarray]:
    """Time (s) and F/mg of the record ``k{stiffness}Nm_v{speed}``."""
    mat = scipy.io.loadmat(DATA / f"k{stiffness}Nm_v{speed}.mat")
    return mat["t"].ravel(), mat["Fnorm"].ravel()


def _second(x: np.ndarray) -> np.ndarray:
    """D x, D the scaled second difference [1/4, -1/2, 1/4]."""
    return 0.25 * x[:-2] - 0.5 * x[1:-1] + 0.25 * x[2:]


def _second_t(v: np.ndarray) -> np.ndarray:
    """D^T v."""
    out = np.zeros(v.size + 2)
    out[:-2] += 0.25 * v
    out[1:-1] -= 0.5 * v
    out[2:] += 0.25 * v
    return out


def denoise(force: np.ndarray, *, penalty: float = 0.8, tolerance: float = 1e-4,
            max_iterations: int = 80) -> np.ndarray:
    """argmin_x 1/2 |x - force|^2 + penalty |D x|_1, D the scaled second difference.

    The primal-dual interior-point method of Kim, Koh, Boyd and Gorinevsky (2009,
    "l1 trend filtering", their ``l1tf.m``) on the dual, max -1/2 |D^T z|^2 + (D y)^T z
    subject to |z| <= penalty: each Newton step is one banded (pentadiagonal) solve, and
    it stops at a duality gap of ``tolerance`` (about 50 steps on a 750 000-sample
    record). The primal is y - D^T z.
    """
    alpha, beta, mu, line_steps = 0.01, 0.5, 2.0, 20  # l1tf.m's
    m = force.size - 2
    dy = _second(force)
    bands = np.zeros((3, m))  # D D^T, upper form: constant diagonals
    bands[2] = 0.25**2 + 0.5**2 + 0.25**2
    bands[1, 1:] = -2 * 0.25 * 0.5
    bands[0, 2:] = 0.25**2
    z, mu1, mu2 = np.zeros(m), np.ones(m), np.ones(m)
    f1, f2 = z - penalty, -z - penalty
    t, step = 1e-10, np.inf

    def residual(z: np.ndarray, mu1: np.ndarray, mu2: np.ndarray, f1: np.ndarray,
                 f2: np.ndarray, t: float) -> float:
        dual = _second(_second_t(z)) - dy + mu1 - mu2
        return float(np.sqrt(dual @ dual + np.sum((mu1 * f1 + 1 / t) ** 2)
                             + np.sum((mu2 * f2 + 1 / t) ** 2)))

    for _ in range(max_iterations):
        dtz = _second_t(z)
        ddtz = _second(dtz)
        primal = 0.5 * dtz @ dtz + penalty * np.abs(dy - ddtz).sum()
        gap = primal - (-0.5 * dtz @ dtz + dy @ z)
        if gap <= tolerance:
            return force - dtz
        if step >= 0.2:
            t = max(2 * m * mu / gap, 1.2 * t)
        system = bands.copy()
        system[2] -= mu1 / f1 + mu2 / f2
        dz = scipy.linalg.solveh_banded(system, -ddtz + dy + (1 / t) / f1 - (1 / t) / f2,
                                        check_finite=False)
        dmu1 = -(mu1 + ((1 / t) + dz * mu1) / f1)
        dmu2 = -(mu2 + ((1 / t) - dz * mu2) / f2)
        before = residual(z, mu1, mu2, f1, f2, t)
        step = 1.0
        for change, value in ((dmu1, mu1), (dmu2, mu2)):
            falling = change < 0
            if falling.any():
                step = min(step, 0.99 * float(np.min(-value[falling] / change[falling])))
        for _ in range(line_steps):
            new = (z + step * dz, mu1 + step * dmu1, mu2 + step * dmu2)
            new_f1, new_f2 = new[0] - penalty, -new[0] - penalty
            if (max(new_f1.max(), new_f2.max()) < 0
                    and residual(*new, new_f1, new_f2, t) <= (1 - alpha * step) * before):
                break
            step *= beta
        (z, mu1, mu2), f1, f2 = new, new_f1, new_f2
    raise RuntimeError(f"l1 trend filtering: duality gap {gap:.3g} after {max_iterations} "
                       "steps")


def slips(force: np.ndarray, stiffness: int, speed: int) -> np.ndarray:
    """(start, stop) sample indices of the slips, the authors' way, on denoised F/mg."""
    velocity = speed - RATE * MASS * GRAVITY * 1e6 / stiffness * np.diff(force)
    fast = np.flatnonzero(velocity >= 10 * NOISE_SPEED)
    if fast.size == 0:
        return np.empty((0, 2), dtype=int)
    breaks = np.flatnonzero(np.diff(fast) > 1)
    events: list[list[int]] = []
    for start, stop in zip(fast[np.r_[0, breaks + 1]], fast[np.r_[breaks, fast.size - 1]],
                           strict=True):
        while start > 0 and velocity[start] > NOISE_SPEED:
            start -= 1
        while stop < velocity.size - 1 and velocity[stop] > NOISE_SPEED:
            stop += 1
        if events and start <= events[-1][1]:
            events[-1][1] = max(events[-1][1], stop)
        else:
            events.append([int(start), int(stop)])
    return np.array(events, dtype=int).reshape(-1, 2)


def significant(force: np.ndarray, events: np.ndarray) -> np.ndarray:
    """Events where the raw F/mg falls by SIGNIFICANT or more from its maximum to the stop."""
    return np.array([force[a : b + 1].max() - force[b] >= SIGNIFICANT for a, b in events],
                    dtype=bool)


def compare(onsets: np.ndarray, events: np.ndarray, important: np.ndarray
            ) -> dict[str, int]:
    """Each reference event claims the first detection whose onset lies in it (0.05 s early
    allowed: the onset is the last sample of the ramp, their start can be later by noise).

    Returns the significant events, those found, the detections, and the extra ones:
    detections no event claimed.
    """
    claimed = np.zeros(onsets.size, dtype=bool)
    found = 0
    for (start, stop), counts in zip(events, important, strict=True):
        inside = np.flatnonzero((onsets >= start - 0.05 * RATE) & (onsets <= stop) & ~claimed)
        if inside.size:
            claimed[inside[0]] = True
            found += int(counts)
    return {"significant": int(important.sum()), "found": found, "detections": onsets.size,
            "extra": int((~claimed).sum())}
