"""The compiled solver built once, before the jobs that need it.

The solver's kernels are compiled by numba on their first call and cached on disk
(beside :mod:`slipwave.solver.active_set`, or in numba's user cache where that is
read-only), once per installation. Jobs started together on an empty cache would each
compile them (every job of a cluster's first run): :func:`compile_solver` compiles
them once, so that the workflow's first rule does it and the others load them.
"""

from __future__ import annotations

import time
from typing import Any

import numba

from slipwave.kernels import cache_report
from slipwave.solver import active_set
from slipwave.solver.simulate import Coulomb, LoadPath, SlipWeakening, simulate
from slipwave.solver.slab import Slab


def compile_solver() -> dict[str, Any]:
    """Compile every kernel of the solver, or load it from the disk cache.

    Small cases (8 elements) take each path of the solver: a test driven through the
    machine's spring under Coulomb's law and under slip-weakening, the map's load
    path with and without friction during the approach, and a held normal
    displacement.

    Returns
    -------
    dict
        ``seconds`` (wall), ``numba`` (its version), and per kernel (the solver's
        functions called from Python) its ``cache_path``, ``loaded`` (cache hits)
        and ``compiled`` (misses).

    Examples
    --------
    >>> report = compile_solver()
    >>> report["kernels"]["iterate"]["loaded"] + report["kernels"]["iterate"]["compiled"] >= 1
    True
    """
    start = time.perf_counter()
    slab = Slab(elements=8)
    drive = LoadPath(normal_load=76.0, machine_stiffness=40.0, max_travel=0.3,
                     travel_step=0.05)
    simulate(slab, Coulomb(fs=0.9, fd=0.6), drive)
    simulate(slab, SlipWeakening(fs=0.9, fd=0.6, dc=0.05), drive)
    for friction in (False, True):
        simulate(slab, Coulomb(fs=0.5), LoadPath(normal_control="force",
                                                 normal_friction=friction))
    simulate(slab, Coulomb(fs=0.5), LoadPath(normal_control="displacement", max_travel=0.2))
    return {"seconds": round(time.perf_counter() - start, 3), "numba": numba.__version__,
            "kernels": cache_report(active_set)}
