"""Solver speed: condensation per geometry, and time per case with the matrices cached.

Targets (160 elements along the contact): condensation <= 2 s; one case (normal
loading + tangential loading to gross sliding) <= 40 ms averaged over f in 0.1..1.4.
Run: make bench  (or python benchmarks/bench_solver.py)
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from slipwave.solver import Coulomb, LoadPath, Slab, simulate
from slipwave.solver.slab import assemble_condensed, condense


def condensation(elements: int, repeat: int) -> float:
    slab = Slab(height=40.0, elements=elements)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        assemble_condensed(slab)
        times.append(time.perf_counter() - start)
    return min(times)


def per_case(control: str, frictions: np.ndarray, repeat: int) -> tuple[float, list[int]]:
    slab = Slab(height=40.0, elements=160)
    condense(slab)  # cached from here on
    simulate(slab, Coulomb(fs=1.0), LoadPath())  # warm up imports and caches
    medians, steps = [], []
    for f in frictions:
        times = []
        for _ in range(repeat):
            start = time.perf_counter()
            ds = simulate(slab, Coulomb(fs=float(f)), LoadPath(normal_control=control))
            times.append(time.perf_counter() - start)
        medians.append(statistics.median(times))
        steps.append(ds.sizes["step"])
    return float(np.mean(medians)), steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    for elements in (160, 320):
        seconds = condensation(elements, 1 if elements > 160 else args.repeat)
        print(f"solver: condensation at {elements} elements: {seconds:.2f} s"
              + (" (target <= 2 s)" if elements == 160 else ""))
    frictions = np.round(np.arange(0.10, 1.401, 0.05), 2)
    for control in ("displacement", "force"):
        mean, steps = per_case(control, frictions, args.repeat)
        status = "meets" if mean <= 0.040 else "MISSES"
        print(f"solver: per case, N held by {control}, f = 0.10..1.40 ({frictions.size} values): "
              f"{mean * 1e3:.1f} ms mean ({status} the 40 ms target); steps "
              f"{min(steps)}..{max(steps)}, mean {np.mean(steps):.0f}")


if __name__ == "__main__":
    main()
