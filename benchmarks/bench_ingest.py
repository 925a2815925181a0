"""Ingest throughput and memory: read_acquisition on a canonical CSV of 6 columns.

Targets (issue 12): >= 1 million rows per second on the project's 2-core machine, and
a peak memory (resident set, above what the process held before reading) under 1.5
times the arrays the file becomes. The default is 10 million rows (a 616 MB CSV, as a
lab's long recording at a high rate); the file is written once and read --repeat times.
Run: make bench  (or python benchmarks/bench_ingest.py [--rows N] [--repeat K])
"""

from __future__ import annotations

import argparse
import multiprocessing
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from slipwave.bench.sawtooth import SawtoothBench, sawtooth_recording
from slipwave.io import read_acquisition, write_acquisition
from targets import check, finish

TARGET_ROWS_PER_S = 1e6
TARGET_MEMORY_RATIO = 1.5


def make_csv(path: Path, rows: int) -> None:
    rate = 10_000.0
    base = sawtooth_recording(SawtoothBench(sample_rate=rate, duration=rows / rate))
    assert base.sizes["time"] == rows
    write_acquisition(base, path, float_format="%.7g")


def _status_kib(field: str) -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    raise RuntimeError(f"no {field} in /proc/self/status")


def _read_once(path: str, queue: multiprocessing.Queue) -> None:
    """In a fresh process: time one read, and its peak resident memory above the start."""
    before = _status_kib("VmRSS")
    start = time.perf_counter()
    ds = read_acquisition(path)
    took = time.perf_counter() - start
    peak = _status_kib("VmHWM")
    arrays = sum(variable.values.nbytes for variable in ds.variables.values())
    assert np.isfinite(ds["T"].values).all()
    queue.put((took, (peak - before) * 1024, arrays, ds.sizes["time"]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rows", type=int, default=10_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    context = multiprocessing.get_context("spawn")  # each read starts from a clean process
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "big.csv"
        make_csv(path, args.rows)
        size_mb = path.stat().st_size / 1e6
        results = []
        for _ in range(args.repeat):
            queue = context.Queue()
            process = context.Process(target=_read_once, args=(str(path), queue))
            process.start()
            results.append(queue.get())
            process.join()
    times = [r[0] for r in results]
    peak = max(r[1] for r in results)
    arrays = results[0][2]
    assert all(r[3] == args.rows for r in results)
    best, median = min(times), statistics.median(times)
    print(f"ingest: {args.rows} rows x 6 columns, {size_mb:.0f} MB CSV")
    print(f"ingest: best {best:.3f} s ({args.rows / best / 1e6:.2f} M rows/s), "
          f"median {median:.3f} s ({args.rows / median / 1e6:.2f} M rows/s)")
    status = check("ingest rows/s", args.rows / median, TARGET_ROWS_PER_S, at_least=True)
    print(f"ingest: {status} the target of {TARGET_ROWS_PER_S / 1e6:.0f} M rows/s (median)")
    ratio = peak / arrays
    status = check("ingest peak memory / arrays", ratio, TARGET_MEMORY_RATIO, at_least=False)
    print(f"ingest: peak memory {peak / 1e6:.0f} MB above the process's start for "
          f"{arrays / 1e6:.0f} MB of arrays: {ratio:.2f} times ({status} the "
          f"{TARGET_MEMORY_RATIO} target)")
    finish()


if __name__ == "__main__":
    main()
