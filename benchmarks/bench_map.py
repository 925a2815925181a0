"""The behaviour map (issue 14): wall time of the workflow, and what the map must be.

1. Time: ``snakemake --cores 2 results/map/map.nc`` builds the full 1572-case map (160
   elements, N held: the rows dealt to ``map.row_jobs`` jobs, then joined) from a clean
   ``results/map/`` and an empty condensation cache, in a copy of the repository (the
   compiled solver already on disk). Target <= 10 s wall (issue 33); the mean per case is reported.
   The figures (``map.png``, ``zones.png``, which need the campaign summary, built
   first and not timed) are timed apart.
2. Zero failed cases; the largest residual is reported.
3. Contiguous: >= 95 % of the cases share their behaviour with one of their four
   neighbours.
4. Stable: >= 95 % of a quarter of the grid (every other f and H/L) keeps its
   succession of events from 160 to 320 elements.
5. The bench's geometry, H/L 0.5 with f 0.9-1.1: first opening at the right edge (L)
   and ZD.

Run: make bench  (or python benchmarks/bench_map.py [--skip-stability])
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import xarray as xr

from slipwave.io import read_dataset
from slipwave.map import (
    PAPER_FRICTIONS,
    PAPER_HEIGHT_RATIOS,
    contiguity,
    map_agreement,
    map_row,
)
from slipwave.solver import LoadPath
from targets import check, finish

ROOT = Path(__file__).parents[1]
BIN = Path(sys.executable).parent


def mean_case_seconds(logs: Path) -> float:
    """Mean wall time per case, from the row jobs' logs (the map holds no timings)."""
    total = cases = 0.0
    for line in (line for log in logs.glob("job*.log") for line in log.read_text().splitlines()):
        found = re.search(r": (\d+) cases in ([\d.]+) s", line)
        if found:
            cases += int(found.group(1))
            total += float(found.group(2))
    return total / cases if cases else float("nan")


def timed_workflow(folder: Path) -> tuple[float, float, xr.Dataset]:
    for name in ["Snakefile", "workflow", "config", "profiles", "raw_data"]:
        source = ROOT / name
        (shutil.copytree if source.is_dir() else shutil.copy)(source, folder / name)
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}",
           "SLIPWAVE_CACHE_DIR": str(folder / "cache")}
    # the map alone: the tests' fits are not part of it
    # (a config file: --config would pass false as a string)
    (folder / "map_only.yaml").write_text("tests: config/tests.tsv\nfit:\n  enabled: false\n")

    def snakemake(target: str) -> list[str]:
        # the target first: --quiet would take it in as one of its values
        return [str(BIN / "snakemake"), target, "--cores", "2", "--quiet", "all",
                "--configfile", "map_only.yaml"]
    subprocess.run(snakemake("results/summary.csv"), cwd=folder, env=env, check=True)
    start = time.perf_counter()
    subprocess.run(snakemake("results/map/map.nc"), cwd=folder, env=env, check=True)
    seconds = time.perf_counter() - start
    start = time.perf_counter()
    subprocess.run(snakemake("results/map/map.png"), cwd=folder, env=env, check=True)
    figures = time.perf_counter() - start
    whole = read_dataset(folder / "results/map/map.nc")
    whole.attrs["mean_case_seconds"] = mean_case_seconds(folder / "results/logs/map")
    return seconds, figures, whole


def _row(args: tuple[float, int]) -> xr.Dataset:
    height_ratio, elements = args
    return map_row(height_ratio, PAPER_FRICTIONS[::2], elements=elements,
                   path=LoadPath(normal_control="force", normal_friction=False))


def stability() -> tuple[float, int]:
    """Agreement of the quarter grid's successions at 160 and 320 elements."""
    ratios = PAPER_HEIGHT_RATIOS[::2]
    with ProcessPoolExecutor(2) as pool:
        coarse = xr.concat(list(pool.map(_row, [(r, 160) for r in ratios])), "height_ratio")
        fine = xr.concat(list(pool.map(_row, [(r, 320) for r in ratios])), "height_ratio")
    return map_agreement(coarse, fine), int(coarse["sequence"].size)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--skip-stability", action="store_true",
                        help="leave out the 320-element comparison (about 2 minutes)")
    args = parser.parse_args()
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as folder:
        seconds, figures, whole = timed_workflow(Path(folder))
    cases = int(whole["behaviour"].size)
    per_case = float(whole.attrs["mean_case_seconds"])
    print(f"map: {cases} cases, snakemake --cores 2 from a clean results/map/ and cache: "
          f"{seconds:.1f} s wall ({check('map wall time, s', seconds, 10.0, at_least=False)} "
          f"the 10 s target; load average {load:.2f} before), {per_case * 1e3:.1f} ms per "
          f"case; the figures "
          f"(map, one zone history per behaviour) then {figures:.1f} s")
    failed = int((whole["end"].values != "gross sliding").sum())
    residual = float(whole["max_residual"].max())
    print(f"map: {failed} cases without gross sliding "
          f"({check('map failed cases', failed, 0, at_least=False)} 0), largest residual "
          f"{residual:.2g}, {whole.sizes['behaviour_id']} behaviours")
    share = contiguity(whole)
    print(f"map: {100 * share:.1f} % of cases share their behaviour with a neighbour "
          f"({check('map contiguity', share, 0.95, at_least=True)} 95 %)")
    bench = whole.sel(height_ratio=0.5, friction=[0.9, 0.95, 1.0, 1.05, 1.1])
    zd = int(((bench["paper_name"] == "ZD") & (bench["L"] == 1)).sum())
    print(f"map: H/L 0.5, f 0.9-1.1: {zd} of {bench['L'].size} sampled cases open first at "
          f"the right edge and are ZD ({check('map bench geometry ZD+L', zd, 5, at_least=True)})")
    names = whole["behaviour_name"].values
    print("map: behaviours: " + ", ".join(
        f"{name} {int(n)}" for name, n in zip(names, whole["cases"].values, strict=True)))
    if not args.skip_stability:
        start = time.perf_counter()
        agreement, compared = stability()
        print(f"map: {100 * agreement:.1f} % of {compared} cases (every other f and H/L) keep "
              f"their succession from 160 to 320 elements "
              f"({check('map mesh stability', agreement, 0.95, at_least=True)} 95 %; "
              f"{time.perf_counter() - start:.0f} s)")
    finish()


if __name__ == "__main__":
    main()
