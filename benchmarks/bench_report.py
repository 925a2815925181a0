"""Reports (issue 16): a test's HTML + PDF <= 15 s, the campaign report <= 30 s.

Times ``slipwave report`` (HTML and PDF, every section: signals, zooms, space-time,
frames, laws, map, video) on each test of the default campaign, and
``slipwave campaign-report``, from the workflow's results (``make run`` first).

The figures are drawn on 2 processes, as the workflow's rule does
(``REPORT_THREADS=1`` to time one).

Run: make bench  (or python benchmarks/bench_report.py)
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

from targets import check, finish

ROOT = Path(__file__).parents[1]
BIN = Path(sys.executable).parent


def main() -> None:
    results = ROOT / "results"
    campaign = pd.read_csv(ROOT / "config/tests.tsv", sep="\t", comment="#", dtype=str,
                           keep_default_na=False)
    needed = [results / test / "comparison.json" for test in campaign["test_id"]]
    if not all(path.exists() for path in needed):
        print("the workflow's results are missing: run `make run` first", file=sys.stderr)
        sys.exit(1)
    print(f"load before: {os.getloadavg()[0]:.2f}")
    slipwave = str(BIN / "slipwave")
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        for _, test in campaign.iterrows():
            t = test["test_id"]
            r = f"results/{t}"
            command = [slipwave, "report", f"{r}/recording.nc", "--events", f"{r}/events.nc",
                       "--fit", f"{r}/fit.json", "--comparison", f"{r}/comparison.csv",
                       "--comparison-json", f"{r}/comparison.json",
                       "--simulated", f"{r}/simulated/recording.nc",
                       "--simulated-events", f"{r}/simulated/events.csv",
                       "--contact", f"{r}/simulated/contact.nc", "--map",
                       "results/map/map.nc", "-o", str(out / f"{t}.html"),
                       "--pdf", str(out / f"{t}.pdf"),
                       "--threads", os.environ.get("REPORT_THREADS", "2")]
            if test["frames"]:
                command += ["--kymograph", f"{r}/kymograph.nc", "--waves", f"{r}/waves.csv",
                            "--fused", f"{r}/events_video.csv", "--clock", f"{r}/clock.json",
                            "--frames", test["frames"]]
            start = time.perf_counter()
            subprocess.run(command, cwd=ROOT, check=True, capture_output=True)
            seconds = time.perf_counter() - start
            size = (out / f"{t}.pdf").stat().st_size / 1e6
            print(f"{t}: HTML + PDF in {seconds:.1f} s "
                  f"({check(f'{t} report', seconds, 15.0, at_least=False)} the 15 s target; "
                  f"PDF {size:.1f} MB)")
        comparisons = [f"results/{t}/comparison.json" for t in campaign["test_id"]]
        start = time.perf_counter()
        subprocess.run([slipwave, "campaign-report", "--summary", "results/summary.csv",
                        "--fits", "results/fits.csv", "--comparisons", *comparisons,
                        "--map", "results/map/map.nc", "-o", str(out / "campaign.html"),
                        "--pdf", str(out / "campaign.pdf")], cwd=ROOT, check=True,
                       capture_output=True)
        seconds = time.perf_counter() - start
        print(f"campaign report: HTML + PDF in {seconds:.1f} s "
              f"({check('campaign report', seconds, 30.0, at_least=False)} the 30 s target)")
    finish()


if __name__ == "__main__":
    main()
