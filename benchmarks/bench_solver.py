"""Solver speed: condensation per geometry, and time per case with the matrices cached.

Targets (160 elements along the contact): condensation <= 2 s; one case (normal
loading + tangential loading to gross sliding) <= 40 ms averaged over f in 0.1..1.4.
Measured as CPU time on one core: OpenBLAS is limited to one thread (its threads
otherwise spin on these small matrices and double the CPU time). Cases that do not
slide before the load cap (they jam, or slide only beyond it) are reported apart: they
have no path to gross sliding within the load path.
Run: make bench  (or python benchmarks/bench_solver.py)
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import statistics
import time

import numpy as np

from slipwave.solver import Coulomb, LoadPath, Slab, SolverCache, simulate
from slipwave.solver.slab import assemble_condensed
from targets import check, finish

TARGET = 0.040


def condensation(elements: int, repeat: int) -> float:
    slab = Slab(height=40.0, elements=elements)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        assemble_condensed(slab)
        times.append(time.perf_counter() - start)
    return min(times)


def per_case(control: str, frictions: np.ndarray, repeat: int) -> list[tuple[float, int, bool]]:
    """(median seconds, steps, reached gross sliding) per friction coefficient."""
    slab = Slab(height=40.0, elements=160)
    cache = SolverCache()  # the slab condensed once, as a map row does
    simulate(slab, Coulomb(fs=1.0), LoadPath(), cache=cache)  # warm up imports and caches
    rows = []
    for f in frictions:
        times = []
        for _ in range(repeat):
            start = time.process_time()
            ds = simulate(slab, Coulomb(fs=float(f)), LoadPath(normal_control=control),
                          cache=cache)
            times.append(time.process_time() - start)
        rows.append((statistics.median(times), ds.sizes["step"],
                     ds.attrs["gross_sliding"] == "reached"))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    for elements in (160, 320):
        seconds = condensation(elements, 1 if elements > 160 else args.repeat)
        verdict = (f" ({check('condensation at 160 elements, s', seconds, 2.0, at_least=False)}"
                   " the 2 s target)" if elements == 160 else "")
        print(f"solver: condensation at {elements} elements: {seconds:.2f} s{verdict}")
    frictions = np.round(np.arange(0.10, 1.401, 0.05), 2)
    for control in ("displacement", "force"):
        rows = per_case(control, frictions, args.repeat)
        times = np.array([r[0] for r in rows])
        steps = np.array([r[1] for r in rows])
        slid = np.array([r[2] for r in rows])
        mean = float(times[slid].mean())
        status = check(f"solver s per case ({control})", mean, TARGET, at_least=False)
        print(f"solver: N held by {control}: {slid.sum()} of {frictions.size} cases "
              f"(f = 0.10..1.40) reach gross sliding: {mean * 1e3:.1f} ms CPU per case on one "
              f"core ({status} the 40 ms target), {steps[slid].mean():.0f} steps on average")
        if (~slid).any():
            print(f"solver: N held by {control}: {(~slid).sum()} cases (f = "
                  f"{frictions[~slid].min():.2f}..{frictions[~slid].max():.2f}) do not slide "
                  f"before the load cap (they jam, or slide later) and run to it in "
                  f"{steps[~slid].mean():.0f} steps: {times[~slid].mean() * 1e3:.1f} ms each; "
                  f"all {frictions.size} cases: {times.mean() * 1e3:.1f} ms")
    finish()


if __name__ == "__main__":
    main()
