"""The detection's compiled kernels built once, before the jobs that need them.

As the solver's (:mod:`slipwave.solver.compiled`): numba compiles them on their first
call and caches them on disk, and jobs started together on an empty cache (a fit's
members, the workflow's first fits) would each compile them; the workflow's compile
rule builds them first.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from slipwave.events import steps
from slipwave.events.steps import edge_jumps, load_drops
from slipwave.kernels import cache_report


def compile_detection() -> dict[str, Any]:
    """Compile every kernel of the detection, or load it from the disk cache.

    A saw-tooth load with a spike and the edge displacement that jumps with it take
    each kernel's path: the spike filter, the swing lows, the hinge fits and the
    straight lines of the load's drops, the window medians of the edge's jumps.

    Returns
    -------
    dict
        ``seconds`` (wall), and per kernel its ``cache_path``, ``loaded`` (cache hits)
        and ``compiled`` (misses).

    Examples
    --------
    >>> report = compile_detection()
    >>> sorted(report["kernels"])[:2]
    ['_best_hinge', '_despiked']
    """
    start = time.perf_counter()
    time_s = np.arange(4000) / 100.0
    rng = np.random.default_rng(0)
    load = 2.0 * (time_s % 10.0) + rng.normal(0.0, 0.04, time_s.size)
    load[1500] += 30.0
    edge = 0.1 * np.floor(time_s / 10.0) + rng.normal(0.0, 1e-4, time_s.size)
    drops = load_drops(time_s, load)
    edge_jumps(time_s, edge, at=drops)
    return {"seconds": round(time.perf_counter() - start, 3), "kernels": cache_report(steps)}
