"""The behaviour map (issues 14, 33, 34): wall time of the workflow, and what the map must be.

1. Time: ``snakemake --cores 2 results/map/map.nc`` builds the full 1572-case map at
   160 elements, without its band (N held: the rows dealt to ``map.row_jobs`` jobs, then
   joined) from a clean ``results/map/`` and an empty condensation cache, in a copy of
   the repository (the compiled solver already on disk and the compile stage done: it
   is not the map's, and bench_solver times it). Target <= 10 s wall (issue 33, whose
   map was at 160 elements); the mean per case is reported.
2. The default map (320 elements, its band drawn from the map at 160): its wall time,
   the same way (no target), then the figures (``map.png``, ``zones.png``, which need
   the campaign summary, built first and not timed), timed apart.
3. Zero failed cases; the largest residual is reported.
4. Contiguous: >= 95 % of the cases share their behaviour with one of their four
   neighbours.
5. The bench's geometry, H/L 0.5 with f 0.9-1.1: first opening at the right edge (L)
   and ZD.
6. Converged (issue 34): the whole map computed again at twice its mesh (640 elements,
   about 7 minutes on 2 cores); at most 1 % of the cases may change their succession
   outside the band. The successions and the paper's names that change are counted,
   and ``docs/_static/map_convergence.png`` / ``.csv`` are written for the
   documentation.

Run: make bench  (or python benchmarks/bench_map.py [--skip-convergence])
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

import numpy as np
import xarray as xr

from slipwave.io import read_dataset
from slipwave.map import PAPER_FRICTIONS, PAPER_HEIGHT_RATIOS, contiguity, map_row
from slipwave.plot import plot_map
from slipwave.solver import LoadPath
from targets import check, finish

ROOT = Path(__file__).parents[1]
DOCS = ROOT / "docs" / "_static"
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


def timed_workflow(folder: Path, settings: str, *, figures: bool
                   ) -> tuple[float, float, xr.Dataset]:
    """Copy the repository to ``folder`` and time the map there with ``settings`` (YAML),
    then its figures when asked.

    Returns the map's wall time, the figures' wall time (0 when not drawn) and the map.
    """
    for name in ["Snakefile", "workflow", "config", "profiles", "raw_data"]:
        source = ROOT / name
        (shutil.copytree if source.is_dir() else shutil.copy)(source, folder / name)
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}",
           "SLIPWAVE_CACHE_DIR": str(folder / "cache")}
    # the map alone: the tests' fits are not part of it
    # (a config file: --config would pass false as a string)
    (folder / "map_only.yaml").write_text("tests: config/tests.tsv\nfit:\n  enabled: false\n"
                                          + settings)

    def snakemake(target: str) -> list[str]:
        # the target first: --quiet would take it in as one of its values
        return [str(BIN / "snakemake"), target, "--cores", "2", "--quiet", "all",
                "--configfile", "map_only.yaml"]
    # not in the map's time: the campaign summary (the figures need it), and the compile
    # stage, timed apart (on a solver numba has cached it only loads it; the stage's own
    # timing from an empty cache is bench_solver's)
    subprocess.run(snakemake("results/summary.csv"), cwd=folder, env=env, check=True)
    start = time.perf_counter()
    subprocess.run(snakemake("results/solver.json"), cwd=folder, env=env, check=True)
    compiled = time.perf_counter() - start
    start = time.perf_counter()
    subprocess.run(snakemake("results/map/map.nc"), cwd=folder, env=env, check=True)
    seconds = time.perf_counter() - start
    whole = read_dataset(folder / "results/map/map.nc")
    whole.attrs["compile_stage_seconds"] = compiled
    whole.attrs["mean_case_seconds"] = mean_case_seconds(
        folder / "results/logs/map" / str(whole.attrs["contact_elements"]))
    drawn = 0.0
    if figures:
        start = time.perf_counter()
        subprocess.run(snakemake("results/map/map.png"), cwd=folder, env=env, check=True)
        drawn = time.perf_counter() - start
    return seconds, drawn, whole


DEFAULT_MAP = ""
"""No settings: the workflow's default map."""
MAP_160 = "map:\n  elements: 160\n  band_elements: 0\n"
"""The map as issue 33 timed it: 160 elements, no band."""


def _row(args: tuple[float, int]) -> xr.Dataset:
    height_ratio, elements = args
    return map_row(height_ratio, PAPER_FRICTIONS, elements=elements,
                   path=LoadPath(normal_control="force", normal_friction=False))


def finer_map(elements: int) -> xr.Dataset:
    """The whole map at ``elements``, its rows on two processes (tallest first)."""
    with ProcessPoolExecutor(2) as pool:
        rows = list(pool.map(_row, [(r, elements) for r in sorted(PAPER_HEIGHT_RATIOS)[::-1]]))
    return xr.concat(rows, "height_ratio").sortby("height_ratio")


def convergence(whole: xr.Dataset) -> None:
    """The default map against the map at twice its mesh; the documentation's figure."""
    elements = int(whole.attrs["contact_elements"])
    start = time.perf_counter()
    finer = finer_map(2 * elements)
    seconds = time.perf_counter() - start
    changed = whole["sequence"].values != finer["sequence"].values
    band = whole["mesh_band"].values.astype(bool)
    outside = changed & ~band
    renamed = int((whole["paper_name"].values != finer["paper_name"].values).sum())
    share = float(outside.mean())
    print(f"map: from {elements} to {2 * elements} elements ({seconds:.0f} s on 2 processes) "
          f"{int(changed.sum())} successions change ({changed.mean():.1%}), {renamed} of the "
          f"paper's names (ZD, ZG or neither) change; the band ({band.mean():.1%} of the map, "
          f"from {whole.attrs['band_elements']} elements, +-{whole.attrs['band_steps']} f "
          f"steps) holds {int((changed & band).sum())} of the changes, "
          f"{int(outside.sum())} ({share:.2%} of the map) lie outside it "
          f"({check('map changes outside the band', share, 0.01, at_least=False)} 1 %)")
    table = whole[["sequence", "paper_name", "mesh_band"]].to_dataframe().reset_index()
    table["sequence_finer"] = finer["sequence"].values.ravel()
    table["paper_name_finer"] = finer["paper_name"].values.ravel()
    table = table[(table["sequence"] != table["sequence_finer"]) | (table["mesh_band"] == 1)]
    table.to_csv(DOCS / "map_convergence.csv", index=False)
    figure = plot_map(whole)
    ax = figure.axes[0]
    i, j = np.nonzero(changed)
    (marks,) = ax.plot(whole["height_ratio"].values[i], whole["friction"].values[j], "x",
                       color="crimson", ms=4, mew=1.0,
                       label=f"succession changes at {2 * elements} elements")
    ax.legend(handles=[*ax.get_legend().legend_handles, marks], loc="upper right", fontsize=8)
    figure.savefig(DOCS / "map_convergence.png", dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--skip-convergence", action="store_true",
                        help="leave out the map at twice the default mesh (about 7 minutes)")
    args = parser.parse_args()
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as folder:
        seconds, _, coarse = timed_workflow(Path(folder), MAP_160, figures=False)
    per_case = float(coarse.attrs["mean_case_seconds"])
    print(f"map: {coarse['behaviour'].size} cases at 160 elements (no band), snakemake "
          f"--cores 2 from a clean results/map/ and cache: {seconds:.1f} s wall "
          f"({check('map wall time, s', seconds, 10.0, at_least=False)} the 10 s target; load "
          f"average {load:.2f} before), {per_case * 1e3:.1f} ms per case; before it, the "
          f"compile rule's job, on the solver numba had cached, "
          f"{coarse.attrs['compile_stage_seconds']:.1f} s (Snakemake's start included)")
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as folder:
        seconds, figures, whole = timed_workflow(Path(folder), DEFAULT_MAP, figures=True)
    print(f"map: the default map, {whole.attrs['contact_elements']} elements with its band "
          f"from {whole.attrs['band_elements']}: {seconds:.1f} s wall (load average "
          f"{load:.2f} before), {float(whole.attrs['mean_case_seconds']) * 1e3:.1f} ms per "
          f"case at {whole.attrs['contact_elements']}; the figures (map, one zone history "
          f"per behaviour) then {figures:.1f} s")
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
    if not args.skip_convergence:
        convergence(whole)
    finish()


if __name__ == "__main__":
    main()
