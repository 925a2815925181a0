"""Run every benchmark and write what it measured to ``benchmarks/RESULTS.md``.

Each ``bench_*.py`` runs as its own process, one after the other; its output (the
figures and each target's verdict) goes to the terminal and to the results file, with
when and on which commit it ran, the machine's load before and after it and its speed
(a one-thread matrix-vector product of the 160-element contact's size, and a Python
loop: the same code measures up to twice as fast on one day's machine as on another's,
so figures from different runs compare through these), its wall time and its exit
status. Naming some benchmarks runs those alone and replaces their
sections, keeping the others'. The file is written whole at the end (a run stopped
half-way leaves the previous one), and the run fails when any benchmark missed a
target.

Run: make bench  (or python benchmarks/run_all.py [bench_map.py ...])
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).parent
RESULTS = HERE / "RESULTS.md"


def _commit() -> str:
    found = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=HERE,
                           capture_output=True, text=True, check=False)
    return found.stdout.strip() or "unknown"


def _load() -> str:
    return " ".join(f"{value:.2f}" for value in os.getloadavg())


_SPEED = """
import time
import numpy as np
matrix, vector = np.random.default_rng(0).random((322, 322)), np.ones(322)
start = time.perf_counter()
for _ in range(20000):
    matrix @ vector
products = 20000 * 2 * 322 * 322 / (time.perf_counter() - start) / 1e9
start, total = time.perf_counter(), 0
for k in range(2_000_000):
    total += k
print(f"{products:.1f} {2.0 / (time.perf_counter() - start):.0f}")
"""


def _speed() -> str:
    """The machine's speed now: one-thread matrix-vector GFLOP/s, and Python loop steps per us."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    found = subprocess.run([sys.executable, "-c", _SPEED], capture_output=True, text=True,
                           check=True, env=env)
    products, loops = found.stdout.split()
    return (f"matrix-vector product (322 x 322, one thread) {products} GFLOP/s, Python loop "
            f"{loops} steps per microsecond")


def run(bench: Path) -> tuple[str, bool]:
    """One benchmark's section of the results, and whether it met its targets."""
    started = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    speed = _speed()
    before = _load()
    began = time.perf_counter()
    process = subprocess.Popen([sys.executable, str(bench)], cwd=HERE.parent, text=True,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    lines = []
    assert process.stdout is not None
    for line in process.stdout:
        print(line, end="", flush=True)
        lines.append(line.rstrip("\n"))
    status = process.wait()
    seconds = time.perf_counter() - began
    verdict = "met its targets" if status == 0 else f"MISSED (exit status {status})"
    section = [f"## {bench.name}", "",
               f"{verdict}; run {started} on commit {_commit()}, {seconds:.0f} s wall; load "
               f"average (1, 5, 15 min) {before} before, {_load()} after; machine speed "
               f"before: {speed}.", "", "```",
               *lines, "```", ""]
    return "\n".join(section), status == 0


def kept_sections() -> dict[str, str]:
    """The sections of the results file as it stands, by benchmark file name."""
    if not RESULTS.exists():
        return {}
    sections: dict[str, str] = {}
    name = ""
    for line in RESULTS.read_text().splitlines():
        if line.startswith("## "):
            name = line.removeprefix("## ").strip()
            sections[name] = ""
        if name:
            sections[name] += line + "\n"
    return sections


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("benches", nargs="*", help="bench_*.py files (default: every one)")
    args = parser.parse_args()
    benches = ([HERE / name for name in args.benches] if args.benches
               else sorted(HERE.glob("bench_*.py")))
    header = ["# Benchmark results", "",
              "Written by `make bench` (`benchmarks/run_all.py`); do not edit by hand.", "",
              f"Machine: {os.cpu_count()} cores, {platform.machine()}, Python "
              f"{platform.python_version()}, {platform.platform()}.", ""]
    sections, met = (kept_sections() if args.benches else {}), True
    for bench in benches:
        print(f"== {bench.name}", flush=True)
        sections[bench.name], ok = run(bench)
        met &= ok
    temporary = RESULTS.with_suffix(".md.part")
    ordered = [sections[name].rstrip("\n") + "\n" for name in sorted(sections)]
    temporary.write_text("\n".join(header) + "\n" + "\n".join(ordered))
    temporary.replace(RESULTS)
    print(f"-> {RESULTS}")
    if not met:
        sys.exit(1)


if __name__ == "__main__":
    main()
