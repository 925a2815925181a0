"""The compile stage: the solvers' and the detection's kernels, built once per machine.

numba compiles a kernel on its first call and caches it on disk; the workflow's first
rule builds them all (:func:`compile_kernels`) so that the jobs after it load them.
On two processes, the solver's callees are compiled side by side first, then its
increment (which loads them) beside the detection's kernels.
"""

from __future__ import annotations

import multiprocessing
import time
from collections.abc import Mapping
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from slipwave.events.compiled import compile_detection
from slipwave.solver.compiled import (
    CALLEE_GROUPS,
    compile_callees,
    compile_quasi_dynamic,
    compile_solver,
)


def compile_kernels(processes: int = 1) -> dict[str, Any]:
    """Compile the solver and the detection, or load them from numba's disk cache.

    Parameters
    ----------
    processes
        Processes to compile on; more than 2 gain nothing (the solver's compilation
        splits in two shares, then its increment, beside the detection) and count as 2.

    Returns
    -------
    dict
        :func:`~slipwave.solver.compiled.compile_solver`'s report, its ``seconds`` the
        whole stage's wall time, with ``detection``
        (:func:`~slipwave.events.compiled.compile_detection`'s), ``quasi_dynamic``
        (:func:`~slipwave.solver.compiled.compile_quasi_dynamic`'s) and ``processes``.

    """
    start = time.perf_counter()
    if processes < 2:
        report = compile_solver()
        report["detection"] = compile_detection()
        report["quasi_dynamic"] = compile_quasi_dynamic()
    else:
        # fork where there is one: a worker then needs no imports of its own
        methods = multiprocessing.get_all_start_methods()
        context = multiprocessing.get_context("fork" if "fork" in methods else None)
        with ProcessPoolExecutor(max_workers=2, mp_context=context) as pool:
            callees = [pool.submit(compile_callees, group) for group in CALLEE_GROUPS]
            detection = pool.submit(compile_detection)  # in the first worker free
            quasi_dynamic = pool.submit(compile_quasi_dynamic)
            shares = [share.result() for share in callees]
            report = compile_solver()
            report["detection"] = detection.result()
            report["quasi_dynamic"] = quasi_dynamic.result()
        for share in shares:
            _count_share(report["kernels"], share)
    report["seconds"] = round(time.perf_counter() - start, 3)
    report["processes"] = min(max(processes, 1), 2)
    return report


def _count_share(kernels: dict[str, dict[str, Any]],
                 share: Mapping[str, Mapping[str, Any]]) -> None:
    """Add a worker's cache report to the main process's, in place.

    A kernel the worker compiled was then loaded by the main process from the cache it
    had just written: counted once, as compiled.
    """
    for name, counts in share.items():
        kernel = kernels.setdefault(name, {"cache_path": counts["cache_path"],
                                           "loaded": 0, "compiled": 0})
        kernel["loaded"] = max(kernel["loaded"] - counts["compiled"], 0) + counts["loaded"]
        kernel["compiled"] += counts["compiled"]
