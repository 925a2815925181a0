"""Speed targets of the benchmarks: each check prints its verdict, and a miss fails the run."""

from __future__ import annotations

import sys

MISSES: list[str] = []


def check(name: str, value: float, target: float, *, at_least: bool) -> str:
    """Compare a measured figure with its target and remember a miss.

    Parameters
    ----------
    name
        What was measured, for the closing line.
    value
        The figure.
    target
        The target it must reach.
    at_least
        True when the figure must be at least the target (a rate), False when
        at most (a time).

    Returns
    -------
    str
        ``"meets"`` or ``"MISSES"``, for the benchmark's own line.

    """
    met = value >= target if at_least else value <= target
    if not met:
        MISSES.append(f"{name}: {value:.4g} against a target of {'>=' if at_least else '<='} "
                      f"{target:.4g}")
    return "meets" if met else "MISSES"


def finish() -> None:
    """Exit non-zero, listing them, when any target was missed."""
    if MISSES:
        print("targets missed:\n  " + "\n  ".join(MISSES), file=sys.stderr)
        sys.exit(1)
