"""Ingest throughput: read_acquisition on a canonical CSV of 2 million rows x 6 columns.

Target: >= 1 million rows per second on the project's 2-core machine.
Run: make bench  (or python benchmarks/bench_ingest.py [--rows N])
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

from slipwave.bench.sawtooth import SawtoothBench, sawtooth_recording
from slipwave.io import read_acquisition, write_acquisition
from targets import check, finish

TARGET_ROWS_PER_S = 1e6


def make_csv(path: Path, rows: int) -> None:
    rate = 10_000.0
    base = sawtooth_recording(SawtoothBench(sample_rate=rate, duration=rows / rate))
    assert base.sizes["time"] == rows
    write_acquisition(base, path, float_format="%.7g")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rows", type=int, default=2_000_000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "big.csv"
        make_csv(path, args.rows)
        size_mb = path.stat().st_size / 1e6
        times = []
        for _ in range(args.repeat):
            start = time.perf_counter()
            ds: xr.Dataset = read_acquisition(path)
            times.append(time.perf_counter() - start)
        assert ds.sizes["time"] == args.rows and np.isfinite(ds["T"].values).all()
    best, median = min(times), statistics.median(times)
    print(f"ingest: {args.rows} rows x 6 columns, {size_mb:.0f} MB CSV")
    print(f"ingest: best {best:.3f} s ({args.rows / best / 1e6:.2f} M rows/s), "
          f"median {median:.3f} s ({args.rows / median / 1e6:.2f} M rows/s)")
    status = check("ingest rows/s", args.rows / median, TARGET_ROWS_PER_S, at_least=True)
    print(f"ingest: {status} the target of {TARGET_ROWS_PER_S / 1e6:.0f} M rows/s (median)")
    finish()


if __name__ == "__main__":
    main()
