"""The compiled solver built once, before the jobs that need it.

The solver's kernels are compiled by numba on their first call and cached on disk
(beside :mod:`slipwave.solver.active_set`, or in numba's user cache where that is
read-only), once per installation. Jobs started together on an empty cache would each
compile them (every job of a cluster's first run): :func:`compile_solver` compiles
them once, so that the workflow's first rule does it and the others load them.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numba
import numpy as np

from slipwave.kernels import cache_report
from slipwave.solver import active_set, quasi_dynamic_steps, quasi_dynamic_stretch, stiff_steps
from slipwave.solver.quasi_dynamic import Drive, simulate_quasi_dynamic, slab_body
from slipwave.solver.rate_state import RateState
from slipwave.solver.simulate import Coulomb, LoadPath, SlipWeakening, simulate
from slipwave.solver.slab import Slab

CALLEE_GROUPS = (("move_to",), ("solve", "_weakening_newton", "set_base", "residual",
                                 "_classify", "_predict", "_keep_one_stuck",
                                 "_weakened_limits", "_aitken", "_same", "_seen", "_copy"))
"""The callees of :func:`slipwave.solver.active_set.iterate` in two shares of about equal
compilation time (the kept inverse's updates; the solves, the weakening and the rest),
for two processes to compile side by side before ``iterate`` is."""


def compile_callees(names: Sequence[str]) -> dict[str, dict[str, Any]]:
    """Compile these callees of ``iterate`` with the types it calls them with.

    One process's share (:data:`CALLEE_GROUPS`) of the solver's compilation, cached on
    disk for the process that compiles ``iterate`` (:func:`compile_solver`) to load.

    Parameters
    ----------
    names
        Functions of :mod:`slipwave.solver.active_set`.

    Returns
    -------
    dict
        The :func:`~slipwave.kernels.cache_report` of the kernels this call compiled or
        loaded (their callees among them).

    Examples
    --------
    >>> from slipwave.solver import active_set
    >>> report = compile_callees(["_same"])
    >>> len(active_set._same.signatures)  # for the zone states, and for the signs
    2
    >>> all(kernel["loaded"] + kernel["compiled"] > 0 for kernel in report.values())
    True
    """
    before = cache_report(active_set)
    body = active_set.zone_solver(np.eye(16), np.zeros(8))
    for name, arguments in active_set.callee_examples(body, np.array([0.9, 0.6, 0.05])):
        if name in names:
            signature = tuple(a if isinstance(a, numba.types.Type) else numba.typeof(a)
                              for a in arguments)
            getattr(active_set, name).compile(signature)
    # this call's part (a process may take several shares)
    after = cache_report(active_set)
    for name, kernel in after.items():
        for count in ("loaded", "compiled"):
            kernel[count] -= before.get(name, {}).get(count, 0)
    return {name: kernel for name, kernel in after.items()
            if kernel["loaded"] or kernel["compiled"]}


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


def compile_quasi_dynamic() -> dict[str, Any]:
    """Compile the quasi-dynamic contact's kernels, or load them from the disk cache.

    A slab of 8 elements pressed and driven for two seconds under a law that slips then
    (the steps, the stretches' contact changes and the crossings' records).

    Returns
    -------
    dict
        ``seconds`` (wall), and per kernel its ``cache_path``, ``loaded`` (cache hits)
        and ``compiled`` (misses).

    Examples
    --------
    >>> report = compile_quasi_dynamic()
    >>> all(k["loaded"] + k["compiled"] >= 1 for k in report["kernels"].values())
    True
    """
    start = time.perf_counter()
    law = RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.9, v0=1e-6)
    simulate_quasi_dynamic(slab_body(Slab(elements=8)), law,
                           Drive(normal_load=85.0, drive_speed=0.048, normal_control="force"),
                           duration=2.0, sample_rate=10.0)
    kernels: dict[str, Any] = {}
    for module in (stiff_steps, quasi_dynamic_steps, quasi_dynamic_stretch):
        kernels |= cache_report(module)
    return {"seconds": round(time.perf_counter() - start, 3), "kernels": kernels}
