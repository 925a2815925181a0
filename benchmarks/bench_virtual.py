"""Virtual bench speed: one 280 s test (H/L = 0.5) with its video, on one core.

Target: <= 60 s for the CSV, the H.264 video (7000 frames, 320 x 160) and the truth.
Run: make bench  (or python benchmarks/bench_virtual.py)
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import tempfile
import time
from pathlib import Path

from slipwave.bench.generate import BenchTest, simulate_test, write_test
from targets import check, finish

TARGET = 60.0


def main() -> None:
    spec = BenchTest("hl050")
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        result = simulate_test(spec, seed=0)
        simulated = time.perf_counter() - start
        paths = write_test(result, Path(folder))
        total = time.perf_counter() - start
        sizes = {key: path.stat().st_size / 1e6 for key, path in paths.items()}
    status = check("virtual bench test, s", total, TARGET, at_least=False)
    print(f"virtual bench: 280 s test, {result.frame_times.size} frames: simulation and "
          f"signals {simulated:.1f} s, total with video and truth {total:.1f} s ({status} the "
          f"{TARGET:.0f} s target)")
    print("virtual bench: sizes (MB): " + ", ".join(f"{k} {v:.2f}" for k, v in sizes.items()))
    finish()


if __name__ == "__main__":
    main()
