"""Fast changes of one signal: load drops and displacement jumps.

Detection runs in three composable stages, in the manner of a seismic
trigger:

1. a characteristic signal: :func:`despike` (block medians that remove
   spikes) and :func:`noise_level` (the robust white-noise level that sets the
   default thresholds);
2. thresholds: :func:`fall_candidates` marks where the signal falls by more
   than a threshold within a short window, on a pyramid of time scales, and
   keeps the falls that are much faster than the rise before them (a
   saw-tooth, not an oscillation);
3. events: :func:`refine_step` places each fall's onset and end on the
   full-rate samples with two-segment (hinge) fits, and :func:`load_drops` /
   :func:`edge_jumps` return them as a table.

Everything is vectorised over samples; the only Python loops run over
candidate events and pyramid levels.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from numba import njit

from slipwave.defaults import MAX_DURATION_S, MAX_SPIKE, MIN_ASYMMETRY, MIN_FALL_RATE, THRESHOLD
from slipwave.errors import SlipwaveError

STEP_COLUMNS = ("i_start", "t_start", "i_end", "t_end", "peak", "trough", "drop", "duration")
"""Columns of :func:`load_drops`; :func:`edge_jumps` adds ``before``, ``after`` and ``jump``."""

_MAD_TO_SIGMA = 1.4826  # median absolute deviation of a Gaussian -> its standard deviation
_NOISE_SAMPLE = 200_000  # differences used for the noise estimate (strided subsample)
_LAG = 4  # blocks over which a pyramid level measures a fall, at most
_LAGS = (1, 2, _LAG)


def noise_level(values: np.ndarray) -> float:
    """Standard deviation of the white noise on a signal, robustly.

    From the median absolute deviation of first differences (divided by
    sqrt 2): ramps, steps and rare spikes do not move it. A quantised signal
    whose differences are mostly zero falls back on the standard deviation of
    the differences inside their central 90 %.

    Parameters
    ----------
    values
        The signal (NaN ignored).

    Returns
    -------
    float
        Its white-noise standard deviation, in its own unit.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> ramp = np.linspace(0, 50, 100_000) + rng.normal(0, 0.04, 100_000)
    >>> round(noise_level(ramp), 3)
    0.04
    """
    values = np.asarray(values, dtype=float)
    if values.size < 3:
        return 0.0
    step = max(1, (values.size - 1) // _NOISE_SAMPLE)
    first = np.arange(0, values.size - 1, step)
    differences = values[first + 1] - values[first]
    differences = differences[np.isfinite(differences)]
    if differences.size < 2:
        return 0.0
    centred = differences - np.median(differences)
    sigma = _MAD_TO_SIGMA * float(np.median(np.abs(centred))) / np.sqrt(2.0)
    if sigma == 0.0:
        low, high = np.quantile(centred, [0.05, 0.95])
        core = centred[(centred >= low) & (centred <= high)]
        sigma = float(core.std()) / np.sqrt(2.0) if core.size else 0.0
    return float(sigma)


def despike(values: np.ndarray, max_spike: int = MAX_SPIKE) -> np.ndarray:
    """Medians of consecutive blocks of ``2 * max_spike + 1`` samples.

    A spike of up to ``max_spike`` samples that comes back to the level it
    left cannot hold the majority of a block, so it is gone from the result,
    whatever its height. The result is ``values.size // block`` long (the
    last incomplete block is dropped).

    Parameters
    ----------
    values
        The signal.
    max_spike
        Longest spike removed, samples.

    Returns
    -------
    numpy.ndarray
        One median per block.

    Examples
    --------
    >>> despike(np.array([1.0, 1.0, 9.0, 1.0, 1.0, 2.0, 2.0, 2.0, -7.0, 2.0]))
    array([1., 2.])
    """
    block = 2 * max_spike + 1
    count = values.size // block
    blocks = values[: count * block].reshape(count, block)
    if block == 5:  # the default: a median-of-5 network, without partition's copy
        a, b, c, d, e = (blocks[:, k] for k in range(5))
        low = np.maximum(np.minimum(a, b), np.minimum(d, e))
        high = np.minimum(np.maximum(a, b), np.maximum(d, e))
        return np.maximum(np.minimum(low, high), np.minimum(np.maximum(low, high), c))
    return np.partition(blocks, max_spike, axis=1)[:, max_spike]


def _fill_gaps(values: np.ndarray) -> np.ndarray:
    """Linear interpolation across NaNs (the detection needs a complete signal)."""
    finite = np.isfinite(values)
    if finite.all():
        return values
    index = np.arange(values.size)
    return np.interp(index, index[finite], values[finite])


def fall_candidates(
    smooth: np.ndarray,
    threshold: float,
    *,
    block: int,
    max_duration: int,
    min_asymmetry: float | None = None,
    min_fall_rate: float | None = None,
) -> np.ndarray:
    """Coarse falls of a despiked signal: (peak sample, trough sample) pairs.

    Parameters
    ----------
    smooth
        The signal from :func:`despike`, one value per block of ``block``
        samples.
    threshold
        A fall is kept when the signal decreases by more than this within 1, 2
        or 4 blocks of one pyramid level (levels average pairs of blocks, so
        each sees falls about twice as long as the one below).
    block
        Samples per value of ``smooth``, to express the result in samples.
    max_duration
        The longest fall looked for, in samples: it sets the pyramid's depth.
    min_asymmetry
        For steps: a fall is kept if it is at least this many times faster
        (in rate or in time) than the rise before it (from the previous swing
        low, a low the signal had risen from by more than ``threshold``).
    min_fall_rate
        For slips (takes precedence): a fall is kept if it is at least this
        many times faster than the drive's loading rate, the median rate of
        the rises before every candidate fall (from its swing low). What tells
        a slip is how fast the load falls against how fast the drive loads,
        not how long the stick before it lasted: the descending half of an
        oscillation falls as fast as it rose, and is not kept.

    Returns
    -------
    numpy.ndarray
        Shape (k, 2): the sample indices of the top and bottom of each fall,
        sorted, not overlapping.
    """
    return _fall_pairs(smooth, threshold, block=block, max_duration=max_duration,
                       min_asymmetry=min_asymmetry, min_fall_rate=min_fall_rate)[0]


def _fall_pairs(smooth: np.ndarray, threshold: float, *, block: int, max_duration: int,
                min_asymmetry: float | None, min_fall_rate: float | None
                ) -> tuple[np.ndarray, float]:
    """:func:`fall_candidates`, and the drive's loading rate per sample (0 if unknown)."""
    levels: list[tuple[int, int]] = []
    seen = np.zeros(smooth.size, dtype=bool)
    level = smooth
    scale = 1
    while level.size > _LAG:
        for lag in _LAGS:  # a short lag sees drops that a fast ramp would hide from a long one
            wholes = _level_falls(level, smooth, seen, scale, lag, threshold)
            levels.extend((int(top), int(bottom)) for top, bottom in wholes)
        if _LAG * scale * 2 * block > max_duration or level.size < 2 * (_LAG + 1):
            break
        even = level.size // 2 * 2
        level = 0.5 * (level[0:even:2] + level[1:even:2])
        scale *= 2
    # finest first; a coarser fall replaces finer pieces of itself (it falls further
    # without rebounding on the way) and is dropped where it spans several falls
    falls: dict[int, tuple[int, int]] = {}
    owner = np.full(smooth.size, -1)  # which kept fall covers each value
    loading = 0.0  # the drive's loading rate, per block (the slip rule only)
    rates: dict[tuple[int, int], tuple[float, float]] = {}
    if min_fall_rate is not None:
        rates = {pair: _rates(smooth, *pair, threshold) for pair in dict.fromkeys(levels)}
        rises = np.array([rise for _, rise in rates.values()])
        rises = rises[np.isfinite(rises) & (rises > 0)]
        loading = float(np.median(rises)) if rises.size else 0.0
    for label, (top, bottom) in enumerate(dict.fromkeys(levels)):
        inside = [falls[k] for k in set(owner[top : bottom + 1].tolist()) - {-1}]
        if inside:
            segment = smooth[top : bottom + 1]
            rebound = float(np.max(segment - np.minimum.accumulate(segment)))
            further = smooth[top] - smooth[bottom] - max(smooth[a] - smooth[b] for a, b in inside)
            if rebound > threshold or further <= threshold:
                continue
        if min_fall_rate is not None:  # a slip: much faster than the drive loads
            fall_rate, rise_rate = rates[(top, bottom)]
            # blocks blur a fall shorter than a few of them: a first screen at a quarter of the
            # rate here, the exact rate on the samples once the fall is refined (_falls)
            fast = (loading > 0 and rise_rate != 0.0
                    and fall_rate >= 0.25 * min_fall_rate * loading)
        else:  # a step: faster than the rise before it
            fast = _asymmetry(smooth, top, bottom, threshold) >= (min_asymmetry or 0.0)
        if fast:
            for a, b in inside:
                owner[a : b + 1] = -1
            falls = {k: pair for k, pair in falls.items() if pair not in inside}
            falls[label] = (top, bottom)
            owner[top : bottom + 1] = label
    kept = sorted(falls.values())
    merged: list[tuple[int, int]] = []
    for top, bottom in kept:
        # pieces of one fall (noise broke its run): close together, no rebound between
        if (merged and top - merged[-1][1] <= max(merged[-1][1] - merged[-1][0], bottom - top)
                and smooth[top] - smooth[merged[-1][1]] < threshold):
            first_top = merged[-1][0]
            merged[-1] = (first_top, first_top + int(np.argmin(smooth[first_top:bottom + 1])))
        else:
            merged.append((top, bottom))
    pairs = np.array(merged, dtype=np.int64).reshape(-1, 2) * block + block // 2
    return pairs, loading / block


@njit(cache=True)
def _lowest_before_rise(values: np.ndarray, swing: float) -> tuple[int, bool]:
    """Where ``values`` are lowest before they first rise by more than ``swing``.

    A rise is measured from their lowest value so far; the lowest place is the first
    one, and the second value says whether they rise so at all. Compiled: the
    detection of a fit's every member asks it of every fall.
    """
    lowest = values[0]
    end = values.size
    for k in range(values.size):
        lowest = min(lowest, values[k])
        if values[k] > lowest + swing:
            end = k
            break
    best = 0
    for k in range(1, end):
        if values[k] < values[best]:
            best = k
    return best, end < values.size


@njit(cache=True)
def _level_falls(level: np.ndarray, smooth: np.ndarray, seen: np.ndarray, scale: int,
                 lag: int, threshold: float) -> np.ndarray:
    """The whole falls that one level of the pyramid sees over ``lag`` blocks.

    A fall is a run of positions where the level falls by more than ``threshold``
    over the lag (gaps shorter than the lag bridged), from its highest value to its
    lowest within the lag after it; one that is not a piece of a fall already
    ``seen`` (in the signal's blocks, marked here) is extended to its whole
    (:func:`_whole_fall`). Compiled: a fit's every member runs it on every level.

    Parameters
    ----------
    level
        The level: the signal averaged over ``scale`` blocks.
    smooth
        The signal, in blocks.
    seen
        Which blocks a fall already covers; updated.
    scale
        Blocks per value of the level.
    lag
        Values of the level over which a fall is measured.
    threshold
        The smallest fall, and the swing that ends a fall's whole.

    Returns
    -------
    numpy.ndarray
        (falls, 2): each whole fall's first and last block, in the order found.

    """
    wholes = np.empty((level.size, 2), dtype=np.int64)  # at most a fall per position
    count = 0
    first = -1
    last = -1
    for k in range(level.size - lag + 1):
        marked = k < level.size - lag and level[k] - level[k + lag] > threshold
        if marked and first >= 0 and k - last <= lag:
            last = k
            continue
        if first >= 0 and (marked or k == level.size - lag):
            top = first
            for j in range(first, last + 1):
                if level[j] > level[top]:
                    top = j
            bottom = top
            for j in range(top, min(last + lag + 1, level.size)):
                if level[j] < level[bottom]:
                    bottom = j
            bottom = max(bottom, top + 1) * scale
            top *= scale
            if not seen[top : bottom + 1].all():  # not a piece of a fall seen already
                start, end = _whole_fall(smooth, top, bottom, threshold)
                seen[start : end + 1] = True
                wholes[count, 0] = start
                wholes[count, 1] = end
                count += 1
            first = -1
        if marked:
            first = last = k
    return wholes[:count]


@njit(cache=True)
def _whole_fall(smooth: np.ndarray, top: int, bottom: int, swing: float) -> tuple[int, int]:
    """The whole fall a piece ``(top, bottom)`` belongs to.

    Back to where the signal was highest before it turned down, on to where it
    was lowest before it rose again (turns are rises or falls of more than
    ``swing``): a short window can catch a piece of a long, slow fall, which
    must be judged whole.
    """
    span = max(bottom - top, 1)
    reach = 4 * span
    while True:
        start = max(0, top - reach)
        back = _lowest_before_rise(-smooth[start : top + 1][::-1], swing)[0]
        if back < top - start or start == 0:
            break
        reach *= 4
    reach = 4 * span
    while True:
        stop = min(smooth.size, bottom + reach)
        on = _lowest_before_rise(smooth[bottom:stop], swing)[0]
        if on < stop - bottom - 1 or stop == smooth.size:
            break
        reach *= 4
    return top - back, bottom + on


def _rise_before(smooth: np.ndarray, top: int, span: int, swing: float
                 ) -> tuple[float, int, bool]:
    """The rise that ends at ``top``: its height, length (blocks) and whether a swing low starts it.

    The rise starts at the previous swing low: going back from ``top`` while the
    signal keeps within ``swing`` of its lowest value so far (or back to the start
    of the signal); ``span`` sets how far to look first.
    """
    reach = 4 * span
    while True:
        start = max(0, top - reach)
        backwards = smooth[start : top + 1][::-1]
        low, turned = _lowest_before_rise(backwards, swing)
        if turned or start == 0:
            return float(backwards[0] - backwards[low]), int(low), bool(turned)
        reach *= 4


def _rates(smooth: np.ndarray, top: int, bottom: int, swing: float) -> tuple[float, float]:
    """(fall rate, rate of the rise before it) of the fall from ``top`` to ``bottom``, per block.

    The rise is :func:`_rise_before`'s (from the signal's start if no swing low
    comes before). Its rate is 0 where there is no real rise: the fall continues
    an earlier one.
    """
    span = max(bottom - top, 1)
    rise, length, _ = _rise_before(smooth, top, span, swing)
    fall_rate = float((smooth[top] - smooth[bottom]) / span)
    return fall_rate, rise / max(length, 1) if rise > swing else 0.0


def _asymmetry(smooth: np.ndarray, top: int, bottom: int, swing: float) -> float:
    """How many times faster the fall from ``top`` to ``bottom`` is than the rise before it.

    Faster in rate or in duration, whichever is larger: a small drop after a
    long ramp and a large drop after a short rise are both saw-tooth drops (the
    rise: :func:`_rise_before`).
    """
    span = max(bottom - top, 1)
    fall_rate = (smooth[top] - smooth[bottom]) / span
    rise, length, at_swing_low = _rise_before(smooth, top, span, swing)
    if not at_swing_low:  # no swing low since the start: only the time is known
        return length / span
    if rise <= swing:  # no real rise before: the middle of a longer fall
        return 0.0
    # faster: steeper than the rise, or over in a fraction of its time
    return float(max(fall_rate * length / rise, length / span))


def _hinge(values: np.ndarray, candidates: np.ndarray) -> int:
    """Breakpoint of the best continuous two-segment line through ``values`` (least squares).

    ``values[i] = a + b i + c max(i - k, 0)`` for each breakpoint ``k`` of
    ``candidates`` (each below ``values.size``); returns the best ``k``.
    """
    if candidates.size == 0 or candidates.min() < 0 or candidates.max() >= values.size:
        raise ValueError(f"hinge breakpoints must lie in [0, {values.size})")
    return int(_best_hinge(np.asarray(values, dtype=np.float64),
                           np.asarray(candidates, dtype=np.int64)))


@njit(cache=True)
def _best_hinge(values: np.ndarray, candidates: np.ndarray) -> int:
    """:func:`_hinge`, compiled: every fall of every ensemble member places two.

    The ramp ``max(i - k, 0)`` is projected off the straight line's basis, and the
    sums this needs come from suffix sums: every breakpoint together costs O(n).
    """
    n = values.size
    centre = 0.5 * (n - 1)  # centred: 1 and i are orthogonal
    ii = 0.0
    iv = 0.0
    total = 0.0
    for j in range(n):
        i = j - centre
        ii += i * i
        iv += i * values[j]
        total += values[j]
    mean, slope = total / n, iv / ii
    # sums over the samples past each index of i, i^2, and of the residual r the
    # straight line leaves and i r
    after_i, after_ii = np.zeros(n + 1), np.zeros(n + 1)
    after_r, after_ir = np.zeros(n + 1), np.zeros(n + 1)
    for j in range(n - 1, -1, -1):
        i = j - centre
        r = values[j] - (mean + slope * i)
        after_i[j] = after_i[j + 1] + i
        after_ii[j] = after_ii[j + 1] + i * i
        after_r[j] = after_r[j + 1] + r
        after_ir[j] = after_ir[j + 1] + i * r
    best, best_gain = candidates[0], -np.inf
    for candidate in candidates:
        k = candidate - centre
        s0 = n - 1.0 - candidate
        s1, s2 = after_i[candidate + 1], after_ii[candidate + 1]
        ramp_sum, ramp_i = s1 - k * s0, s2 - k * s1
        ramp_norm = s2 - 2 * k * s1 + k * k * s0 - ramp_sum**2 / n - ramp_i**2 / ii
        ramp_residual = after_ir[candidate + 1] - k * after_r[candidate + 1]
        gain = ramp_residual**2 / ramp_norm if ramp_norm > 1e-9 else 0.0
        if gain > best_gain:  # the first of equal gains, as argmax
            best, best_gain = candidate, gain
    return best


def refine_step(
    values: np.ndarray,
    top: int,
    bottom: int,
    *,
    low: int,
    high: int,
    max_spike: int = MAX_SPIKE,
) -> tuple[int, int, float, float]:
    """Onset and end of one fall on the full-rate samples.

    Parameters
    ----------
    values
        The whole signal (falls downwards).
    top, bottom
        Coarse top and bottom samples of the fall (:func:`fall_candidates`).
    low, high
        The fall's neighbourhood, free of other falls: fits use samples in
        ``[low, high)``.
    max_spike
        Spikes up to this many samples are median-filtered out of the fits.

    Returns
    -------
    tuple
        ``(onset, end, peak, trough)``: the onset is the last sample on the
        line followed before the fall (a hinge fit of the ramp and the fall's
        first half), the end the first sample of the line followed after it
        (a hinge fit of the fall's second half and what comes next); ``peak``
        and ``trough`` are the fitted values there, free of the noise of
        single samples.
    """
    span = max(bottom - top, 2 * max_spike + 1)
    start = max(low, top - max(span, 24))
    stop = min(high, bottom + max(span, 24))
    window = without_spikes(values[start:stop], max_spike)
    top_local = int(np.argmax(window[: max(top - start, 0) + span // 2 + 1]))
    rest = window[top_local:]
    bottom_local = top_local + int(np.argmin(rest[: bottom - start - top_local + span + 1]))
    middle_level = 0.5 * (window[top_local] + window[bottom_local])
    below = np.flatnonzero(window[top_local:bottom_local + 1] <= middle_level)
    middle = top_local + (int(below[0]) if below.size else (bottom_local - top_local) // 2)
    middle = min(max(middle, top_local + 1), bottom_local)
    # onset: a hinge between the ramp before and the fall, breakpoints up to the middle
    head = window[: middle + 1]
    onset = _hinge(head, np.arange(1, max(middle, 2)))
    # end: a hinge between the fall and what follows, breakpoints after the middle
    first = middle - 1
    tail = window[first:]
    end = _hinge(tail, np.arange(1, max(tail.size - 2, 2)))
    end += first
    # levels from the straight lines before the onset and after the end (the hinges'
    # continuity would pull them towards the fall)
    peak = _line_at(window[: onset + 1], onset)
    # the end sample may still be on the fall when the kink lies just after it
    trough = _line_at(window[end + 1 :], -1) if end + 1 < window.size else float(window[-1])
    return start + onset, start + end, peak, trough


@njit(cache=True)
def _line_at(values: np.ndarray, at: int) -> float:
    """The least-squares straight line through ``values``, evaluated at index ``at``."""
    n = values.size
    if n < 3:
        return values[min(max(at, 0), n - 1)]
    centre = 0.5 * (n - 1)
    total = 0.0
    for j in range(n):
        total += values[j]
    mean = total / n
    ii = 0.0
    iv = 0.0
    for j in range(n):
        i = j - centre
        ii += i * i
        iv += i * (values[j] - mean)
    return mean + iv / ii * (at - centre)


def without_spikes(values: np.ndarray, max_spike: int = MAX_SPIKE) -> np.ndarray:
    """A signal with its spikes replaced by its running median, at its own rate.

    Only samples further than a robust 5 sigma from the median of their
    ``2 * max_spike`` neighbours are replaced, by the running median of
    ``2 * max_spike + 1`` samples (any departure, where most samples lie on their
    neighbours' median and sigma is nothing): the others, kinks included, stay as
    recorded, so the fits that place onsets are not blurred (where :func:`despike`'s
    block medians lower the rate).

    Parameters
    ----------
    values
        The signal.
    max_spike
        Longest spike replaced, samples.

    Returns
    -------
    numpy.ndarray
        The signal, spikes replaced (as long as ``values``).

    Examples
    --------
    >>> without_spikes(np.array([2.0, 2.0, 9.0, 2.0, 2.0, 2.0, -5.0, 2.0, 2.0]))
    array([2., 2., 2., 2., 2., 2., 2., 2., 2.])
    """
    values = np.asarray(values, dtype=float)
    if max_spike < 1 or values.size < 2 * max_spike + 1:
        return values
    return _despiked(values, max_spike, _MAD_TO_SIGMA)


@njit(cache=True)
def _despiked(values: np.ndarray, half: int, mad_to_sigma: float) -> np.ndarray:
    """:func:`without_spikes`, compiled: a fit's members call it for every fall.

    The running medians repeat the end samples beyond the ends (as
    ``scipy.ndimage.median_filter``'s ``"nearest"``). A sample is judged against the
    median of its ``2 * half`` neighbours, itself left out: on a steep or quantised
    stretch a sample is often the median of a window that holds it, and the spread of
    the departures from that median collapsed to nothing (a Colas record at 1100 um/s
    had 44 % of its samples replaced); a spike's replacement is the median of the
    window with it, which leaves a step's edge as it was.
    """
    n = values.size
    median = np.empty(n)
    around = np.empty(n)
    window = np.empty(2 * half + 1)
    for i in range(n):
        for k in range(-half, half + 1):  # sorted as it is filled (a few samples)
            value = values[min(max(i + k, 0), n - 1)]
            j = k + half
            while j > 0 and window[j - 1] > value:
                window[j] = window[j - 1]
                j -= 1
            window[j] = value
        median[i] = window[half]
        # the neighbours' median: the sorted window's middle pair once the sample is out
        if values[i] < window[half]:
            around[i] = 0.5 * (window[half] + window[half + 1])
        elif values[i] > window[half]:
            around[i] = 0.5 * (window[half - 1] + window[half])
        else:
            around[i] = 0.5 * (window[half - 1] + window[half + 1])
    deviation = values - around
    spread = mad_to_sigma * np.median(np.abs(deviation))
    out = values.copy()
    for i in range(n):
        spike = abs(deviation[i]) > 5.0 * spread if spread > 0 else deviation[i] != 0
        if spike:
            out[i] = median[i]
    return out


def _prepare(time: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, float,
                                                               float]:
    """Checked arrays, NaNs bridged, noise level and sample interval of one signal."""
    time = np.asarray(time, dtype=float)
    values = np.asarray(values, dtype=float)
    if time.shape != values.shape or values.ndim != 1:
        raise SlipwaveError(f"time and signal must be 1-D of one length, got shapes "
                            f"{time.shape} and {values.shape}")
    finite = np.isfinite(values)
    if not finite.any():
        raise SlipwaveError("the signal has no finite value (all NaN or empty)")
    if not finite.all():
        values = _fill_gaps(values)
    step = max(1, (time.size - 1) // _NOISE_SAMPLE)
    interval = float(np.median(np.diff(time[::step]))) / step if time.size > 1 else 0.0
    return time, values, noise_level(values), interval


def _falls(
    values: np.ndarray,
    smooth: np.ndarray,
    *,
    size: float,
    max_spike: int,
    longest: int,
    min_asymmetry: float | None = None,
    min_fall_rate: float | None = None,
) -> list[tuple[int, int, float, float]]:
    """(onset, end, peak, trough) of each fall of ``values`` larger than ``size``."""
    block = 2 * max_spike + 1
    if size <= 0.0 or smooth.size < 2 * _LAG or np.ptp(smooth) < 0.5 * size:
        return []
    pairs, loading = _fall_pairs(smooth, 0.5 * size, block=block, max_duration=longest,
                                 min_asymmetry=min_asymmetry, min_fall_rate=min_fall_rate)
    falls = []
    previous_end = 0
    for k, (top, bottom) in enumerate(pairs):
        following = int(pairs[k + 1, 0]) if k + 1 < len(pairs) else values.size
        onset, end, peak, trough = refine_step(values, int(top), int(bottom),
                                               low=previous_end, high=following,
                                               max_spike=max_spike)
        fast = min_fall_rate is None or (
            end > onset and (peak - trough) / (end - onset) >= min_fall_rate * loading)
        if peak - trough >= size and end > onset and fast:
            falls.append((onset, end, peak, trough))
            previous_end = end
    return falls


def _step_table(time: np.ndarray, falls: list[tuple[int, int, float, float]],
                **attrs: float) -> pd.DataFrame:
    onset = np.array([f[0] for f in falls], dtype=np.int64)
    end = np.array([f[1] for f in falls], dtype=np.int64)
    peak = np.array([f[2] for f in falls], dtype=float)
    trough = np.array([f[3] for f in falls], dtype=float)
    table = pd.DataFrame({
        "i_start": onset, "t_start": time[onset], "i_end": end, "t_end": time[end],
        "peak": peak, "trough": trough, "drop": peak - trough,
        "duration": time[end] - time[onset],
    })
    table.attrs.update(attrs)
    return table


def _longest(values: np.ndarray, max_duration: float | None, interval: float) -> int:
    if max_duration is None or interval <= 0:
        return values.size // 10
    return int(max_duration / interval)


def load_drops(
    time: np.ndarray,
    load: np.ndarray,
    *,
    min_drop: float | None = None,
    threshold: float = THRESHOLD,
    max_spike: int = MAX_SPIKE,
    max_duration: float | None = MAX_DURATION_S,
    min_fall_rate: float = MIN_FALL_RATE,
) -> pd.DataFrame:
    """Drops of a load-like signal: one row per fast decrease.

    Parameters
    ----------
    time
        Sample times (s).
    load
        The signal (T, or any load that rises slowly and falls fast); NaNs are
        bridged by linear interpolation.
    min_drop
        Smallest drop kept, in the signal's unit. ``None``: ``threshold``
        times the signal's own noise level (:func:`noise_level`).
    threshold
        Default ``min_drop`` in units of the noise level.
    max_spike
        Excursions of up to this many samples that come back to their level
        are spikes, not drops, whatever their height.
    max_duration
        Longest drop looked for (s); ``None``: a tenth of the recording.
    min_fall_rate
        A drop must fall at least this many times faster than the drive loads
        the signal (the median rate of the rises before the candidate drops):
        the slider then moves at ``1 + min_fall_rate`` times the drive's speed
        or more. A slow oscillation (falling as fast as it rose) or a drift
        is no drop; a slip after a short stick, or after creep, is.

    Returns
    -------
    pandas.DataFrame
        ``i_start, t_start`` (the onset: the last sample on the ramp before
        the fast decrease), ``i_end, t_end`` (where the decrease ends),
        ``peak, trough`` (fitted values there), ``drop = peak - trough``,
        ``duration``. ``attrs`` holds ``noise``, ``min_size`` and
        ``sample_interval``. Empty if there is none; a constant signal gives
        an empty table.

    Raises
    ------
    SlipwaveError
        If the signal has no finite value, or time and signal do not match.

    Examples
    --------
    A saw-tooth with white noise and a tall one-sample spike (not a drop):

    >>> rng = np.random.default_rng(1)
    >>> t = np.arange(6000) * 0.01
    >>> load = 2.0 * (t % 20.0) + rng.normal(0, 0.04, t.size)
    >>> load[1500] += 30.0
    >>> drops = load_drops(t, load)
    >>> drops[["i_start", "i_end"]].values.tolist()
    [[1999, 2000], [3999, 4000]]
    >>> drops["drop"].round().tolist()
    [40.0, 40.0]
    """
    time, values, sigma, interval = _prepare(time, load)
    size = threshold * sigma if min_drop is None else float(min_drop)
    falls = _falls(values, despike(values, max_spike), size=size, max_spike=max_spike,
                   longest=_longest(values, max_duration, interval),
                   min_fall_rate=min_fall_rate)
    return _step_table(time, falls, noise=sigma, min_size=size, sample_interval=interval)


def window_median(values: np.ndarray, first: int, last: int) -> float:
    """Median of ``values[first:last]`` (clipped to the signal), NaN if empty.

    Long windows are thinned to about 1000 evenly spaced samples.

    Parameters
    ----------
    values
        The signal.
    first, last
        The window, as slice bounds.

    Returns
    -------
    float
        The median, NaN for an empty window.

    """
    first, last = max(first, 0), min(last, values.size)
    # contiguous: a thinned window would otherwise compile a second kernel
    return float(_finite_median(np.ascontiguousarray(
        values[first:last:max(1, (last - first) // 1000)], dtype=np.float64)))


@njit(cache=True)
def _finite_median(segment: np.ndarray) -> float:
    """The median of the finite values of ``segment``, NaN if there are none."""
    finite = segment[np.isfinite(segment)]
    return np.median(finite) if finite.size else np.nan


def _changes_at(time: np.ndarray, values: np.ndarray, drops: pd.DataFrame, *, size: float,
                max_spike: int) -> pd.DataFrame:
    """How a signal changed across each of ``drops`` (one row per drop)."""
    rows = []
    for start, end in zip(drops["i_start"].to_numpy(dtype=np.int64),
                          drops["i_end"].to_numpy(dtype=np.int64), strict=True):
        width = max(int(end - start), 5)  # levels over windows as long as the event
        before = window_median(values, start - width, start + 1)
        after = window_median(values, end, end + width)
        jump = after - before
        # when the signal had made half its change: which edge moved first
        low = max(start - width, 0)
        window = without_spikes(values[low : end + width], max_spike)
        crossed = np.flatnonzero(np.sign(jump) * (window - before) >= 0.5 * abs(jump))
        middle = low + int(crossed[0]) if crossed.size and jump != 0 else int(start)
        rows.append((middle, time[middle], end, time[end], max(before, after),
                     min(before, after), abs(jump), time[end] - time[middle], before, after,
                     jump, abs(jump) >= size))
    columns = [*STEP_COLUMNS, "before", "after", "jump", "significant"]
    kinds = {"i_start": np.int64, "i_end": np.int64, "significant": bool}
    # made with their types (a table's astype costs more than the table)
    by_column = list(zip(*rows, strict=True)) if rows else [()] * len(columns)
    return pd.DataFrame({name: np.array(column, dtype=kinds.get(name, np.float64))
                         for name, column in zip(columns, by_column, strict=True)})


def edge_jumps(
    time: np.ndarray,
    displacement: np.ndarray,
    *,
    at: pd.DataFrame | None = None,
    min_jump: float | None = None,
    threshold: float = THRESHOLD,
    max_spike: int = MAX_SPIKE,
    max_duration: float | None = MAX_DURATION_S,
    min_asymmetry: float = MIN_ASYMMETRY,
) -> pd.DataFrame:
    """Steps of a displacement signal (DG, DD), of either sign.

    Parameters
    ----------
    time, displacement
        Sample times (s) and the edge displacement.
    at
        T drops (:func:`load_drops`): measure the step across each of them
        (median levels over windows as long as the drop, before its onset and
        after its end) instead of looking for steps anywhere. This is how
        :func:`~slipwave.events.detect_events` reads the edges: it sees steps
        as slow as the drop and below the search's threshold.
    min_jump, threshold, max_spike, max_duration, min_asymmetry
        As in :func:`load_drops` (``min_jump`` standing for ``min_drop``).

    Returns
    -------
    pandas.DataFrame
        The columns of :func:`load_drops` (``peak`` and ``trough`` are the
        higher and the lower level) plus ``before``, ``after`` and ``jump =
        after - before`` (signed), sorted by onset. With ``at``: one row per
        drop, in its order, ``i_start``/``t_start`` being when the edge had
        made half its step, and a column ``significant`` (``|jump| >=
        min_jump``).

    Examples
    --------
    >>> rng = np.random.default_rng(2)
    >>> t = np.arange(4000) * 0.01
    >>> dg = np.where(t < 10, 0.0, -0.2) + np.where(t < 30, 0.0, 0.1)
    >>> dg = dg + rng.normal(0, 0.0015, t.size)
    >>> jumps = edge_jumps(t, dg)
    >>> jumps[["i_start", "jump"]].round(2).values.tolist()
    [[999.0, -0.2], [2999.0, 0.1]]

    The same edge read across two given drops, the second without a step:

    >>> drops = pd.DataFrame({"i_start": [999, 1999], "i_end": [1005, 2005]})
    >>> at = edge_jumps(t, dg, at=drops)
    >>> at["jump"].round(2).tolist(), at["significant"].tolist()
    ([-0.2, 0.0], [True, False])
    """
    time, values, sigma, interval = _prepare(time, displacement)
    size = threshold * sigma if min_jump is None else float(min_jump)
    if at is not None:
        table = _changes_at(time, values, at, size=size, max_spike=max_spike)
        table.attrs.update(noise=sigma, min_size=size, sample_interval=interval)
        return table
    smooth = despike(values, max_spike)
    parts = []
    for sign in (1.0, -1.0):  # falls of the signal, then of its opposite (rises)
        if sign < 0:
            values, smooth = -values, -smooth
        falls = _falls(values, smooth, size=size, max_spike=max_spike,
                       longest=_longest(values, max_duration, interval),
                       min_asymmetry=min_asymmetry)
        found = _step_table(time, falls)
        found["peak"] *= sign
        found["trough"] *= sign
        parts.append(found.assign(before=found["peak"], after=found["trough"],
                                  jump=found["trough"] - found["peak"]))
    table = pd.concat(parts, ignore_index=True).sort_values("i_start", ignore_index=True)
    table.attrs.update(noise=sigma, min_size=size, sample_interval=interval)
    return table
