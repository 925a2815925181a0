"""Solver speed (issue 33): the compiled contact solver against its targets, one core.

1. A map case at 160 elements (H/L 0.5, N held, frictionless approach; normal loading
   and tangential loading to gross sliding, the slab condensed once; the variables the
   map keeps): <= 4 ms, averaged over f = 0.10..1.40.
2. A 280 s virtual-bench test (Coulomb fs 0.9, fd 0.6, H/L 0.5, N held, the actuator
   through the machine's spring): <= 0.1 s at 80 elements, 0.4 s at 160, 2 s at 320;
   the same test under slip-weakening (Dc 0.1 mm) <= 3 times Coulomb's time.
3. The compilation: <= 30 s once, from an empty numba cache, in a fresh process; a
   second process then loads it from disk (its first increment is timed). The
   workflow's compile stage (``slipwave compile --processes 2``, the solver and the
   detection) from an empty cache: wall time on two cores, no target of its own.
4. Peak memory (the process's maximum resident set) of the 320-element test <= 300 MB.
5. The time of the 280 s test against elements, 40 to 640, and its growth exponent.
6. The slab's condensation at 160, 320 and 640 elements: time and peak memory (no
   target; the test times above start from a condensed slab).

Times are the best of ``--repeat`` runs (the slab condensed beforehand), CPU time of one
process with OpenBLAS on one thread.
Run: make bench  (or python benchmarks/bench_solver.py)
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import json
import subprocess
import sys
import tempfile
import time

import numpy as np

from slipwave.bench.generate import BenchTest
from slipwave.map import MAP_CASE_VARIABLES
from slipwave.solver import Coulomb, LoadPath, Slab, SolverCache, simulate
from slipwave.solver.slab import condense
from targets import check, finish

MAP_CASE_TARGET = 0.004
TEST_TARGETS = {80: 0.1, 160: 0.4, 320: 2.0}
WEAKENING_RATIO = 3.0
COMPILATION_TARGET = 30.0
MEMORY_TARGET_MB = 300.0


def best_time(run, repeat: int) -> float:
    """Best CPU time of ``repeat`` calls of ``run``."""
    times = []
    for _ in range(repeat):
        start = time.process_time()
        run()
        times.append(time.process_time() - start)
    return min(times)


def map_cases(repeat: int) -> tuple[float, int]:
    slab = Slab(height=40.0, elements=160)
    path = LoadPath(normal_control="force", normal_friction=False)
    cache = SolverCache()
    simulate(slab, Coulomb(fs=1.0), path, cache=cache)  # condensed, approach kept
    frictions = np.round(np.arange(0.10, 1.401, 0.05), 2)
    seconds = [best_time(lambda f=f: simulate(slab, Coulomb(fs=float(f)), path, cache=cache,
                                              variables=MAP_CASE_VARIABLES),
                         repeat) for f in frictions]
    return float(np.mean(seconds)), frictions.size


def test_spec(elements: int, *, weakening: bool = False) -> BenchTest:
    law = {"fs": 0.9, "fd": 0.6, "fs_final": None}
    return BenchTest("hl050", elements=elements, video="none",
                     **law, **({"dc": 0.1} if weakening else {}))


def test_time(elements: int, repeat: int, *, weakening: bool = False) -> tuple[float, int]:
    spec = test_spec(elements, weakening=weakening)
    slab, path, cache = spec.slab(), spec.load_path(), SolverCache()
    condense(slab, cache=cache)
    steps = simulate(slab, spec.friction(), path, cache=cache).sizes["step"]  # warm
    return best_time(lambda: simulate(slab, spec.friction(), path, cache=cache), repeat), steps


_CHILD = """
import json, sys, time
start = time.perf_counter()
from slipwave.bench.generate import BenchTest
from slipwave.map import MAP_CASE_VARIABLES
from slipwave.solver import Coulomb, Slab, LoadPath, simulate
imported = time.perf_counter()
elements = int(sys.argv[1])
if not elements:  # the first simulation: the kernels compiled, or loaded from the disk
    simulate(Slab(elements=8), Coulomb(fs=0.9, fd=0.6), LoadPath(normal_load=76.0,
             machine_stiffness=40.0, max_travel=0.3, travel_step=0.05))
first = time.perf_counter()
if elements:  # as `slipwave simulate` does: condensed, then simulated
    spec = BenchTest("hl050", elements=elements, video="none", fs=0.9, fd=0.6, fs_final=None)
    simulate(spec.slab(), spec.friction(), spec.load_path())
# the high-water mark of this process's own memory (getrusage's ru_maxrss would keep
# the parent's, which it inherits across the exec)
peak = next(int(line.split()[1]) for line in open("/proc/self/status")
            if line.startswith("VmHWM:"))
print(json.dumps({"import": imported - start, "first_run": first - imported,
                  "peak_mb": peak / 1024}))
"""


_CONDENSATION = """
import json, sys, time
from slipwave.solver.slab import Slab, assemble_condensed
def rss(key):
    return next(int(line.split()[1]) for line in open("/proc/self/status")
                if line.startswith(key)) / 1024
assemble_condensed(Slab(elements=8))
start, before = time.perf_counter(), rss("VmRSS:")
assemble_condensed(Slab(height=0.5 * 80.0, elements=int(sys.argv[1])))
print(json.dumps({"seconds": time.perf_counter() - start, "peak_mb": rss("VmHWM:") - before}))
"""


def condensation(elements: int) -> dict[str, float]:
    """A fresh process condenses the H/L 0.5 slab: its time and peak memory above its start."""
    out = subprocess.run([sys.executable, "-c", _CONDENSATION, str(elements)], check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def child(elements: int, cache_dir: str) -> dict[str, float]:
    """A fresh process: its import, then its first small simulation (``elements`` 0) or
    the 280 s test at ``elements``; its peak memory."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir}
    out = subprocess.run([sys.executable, "-c", _CHILD, str(elements)], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def compile_stage(cache_dir: str) -> float:
    """Wall time of the workflow's compile stage on two processes, from ``cache_dir``."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir}
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "slipwave.cli", "compile", "-o",
                    os.path.join(cache_dir, "solver.json"), "--processes", "2"], env=env,
                   check=True, capture_output=True)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    load = os.getloadavg()[0]
    print(f"solver: load average {load:.2f} before")

    with tempfile.TemporaryDirectory() as cache_dir:
        cold = child(0, cache_dir)
        warm = child(0, cache_dir)
    status = check("compilation, s", cold["first_run"], COMPILATION_TARGET, at_least=False)
    print(f"solver: compilation from an empty cache {cold['first_run']:.1f} s ({status} the "
          f"{COMPILATION_TARGET:.0f} s target); a second process's first simulation "
          f"{warm['first_run']:.2f} s (loaded from the disk cache; imports "
          f"{warm['import']:.1f} s)")
    with tempfile.TemporaryDirectory() as cache_dir:
        stage = compile_stage(cache_dir)
    print(f"solver: the compile stage on two processes (slipwave compile --processes 2, the "
          f"solver and the detection) from an empty cache: {stage:.1f} s wall")

    for elements in (160, 320, 640):
        condensed = condensation(elements)
        print(f"solver: condensation of the slab (H/L 0.5), {elements} elements: "
              f"{condensed['seconds']:.2f} s, peak memory {condensed['peak_mb']:.0f} MB above "
              f"the process's start")

    mean, cases = map_cases(args.repeat)
    status = check("map case at 160 elements, s", mean, MAP_CASE_TARGET, at_least=False)
    print(f"solver: map case at 160 elements (H/L 0.5, N held), mean of {cases} frictions "
          f"0.10..1.40: {mean * 1e3:.1f} ms ({status} the {MAP_CASE_TARGET * 1e3:.0f} ms "
          f"target)")

    rows = []
    for elements in (40, 80, 160, 320, 640):
        seconds, steps = test_time(elements, args.repeat if elements <= 160 else 1)
        rows.append((elements, seconds, steps))
        verdict = ""
        if elements in TEST_TARGETS:
            status = check(f"280 s test at {elements} elements, s", seconds,
                           TEST_TARGETS[elements], at_least=False)
            verdict = f" ({status} the {TEST_TARGETS[elements]:g} s target)"
        print(f"solver: 280 s test, Coulomb fs 0.9 fd 0.6, {elements} elements: "
              f"{seconds:.3f} s, {steps} steps{verdict}", flush=True)
    elements = np.array([row[0] for row in rows], dtype=float)
    seconds = np.array([row[1] for row in rows])
    exponent = float(np.polyfit(np.log(elements), np.log(seconds), 1)[0])
    upper = float(np.polyfit(np.log(elements[-3:]), np.log(seconds[-3:]), 1)[0])
    print("solver: elements | s | s per step\n" + "\n".join(
        f"         {int(e):4d} | {s:7.3f} | {s / n * 1e3:6.2f} ms" for e, s, n in rows))
    print(f"solver: time grows as elements^{exponent:.2f} over 40-640 "
          f"(^{upper:.2f} over 160-640)")

    coulomb = dict((row[0], row[1]) for row in rows)[80]
    weakening, _ = test_time(80, args.repeat, weakening=True)
    ratio = weakening / coulomb
    status = check("slip-weakening / Coulomb at 80 elements", ratio, WEAKENING_RATIO,
                   at_least=False)
    print(f"solver: the same test under slip-weakening (Dc 0.1 mm), 80 elements: "
          f"{weakening:.3f} s, {ratio:.2f} times Coulomb's ({status} the 3x target)")

    with tempfile.TemporaryDirectory() as cache_dir:
        child(0, cache_dir)  # compiled first, in a process of its own
        peak = child(320, cache_dir)["peak_mb"]
    status = check("peak memory at 320 elements, MB", peak, MEMORY_TARGET_MB, at_least=False)
    print(f"solver: peak memory of a process simulating the test at 320 elements: "
          f"{peak:.0f} MB ({status} the {MEMORY_TARGET_MB:.0f} MB target)")
    finish()


if __name__ == "__main__":
    main()
