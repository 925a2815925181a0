"""The compiled solver against the interpreted one it replaced (issue 33), measured.

The interpreted solver is the repository at ``--reference`` (by default 06b4878, the
last commit before the compiled one), checked out in a temporary worktree and run by
the same Python. Both run:

1. the full behaviour map, 1572 cases (12 H/L x 131 f, 160 elements, N held): every
   case must keep its succession of events (the differences, if any, are listed);
2. the virtual bench's tests (Coulomb fs 0.9 fd 0.6 at 80 and 160 elements, the run-in
   tests of the default campaign's three slabs, slip-weakening Dc 0.1 mm at 80 and 160):
   the same steps, zone states and events, and the signals (T, N, DG, DD, DT, T before
   each wave) and visible events' features (loads before and after, T/N, drop, edge
   jumps, swept fraction, start) equal to 1e-9 of their scale.

The reference runs without the gross-slip onset cut that the solver has since dropped
(its increments are then the compiled side's, and the kernels are compared alone).

Run: make bench  (or python benchmarks/bench_equivalence.py [--reference REV]); about
four minutes on two cores, most of it the interpreted solver's.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import subprocess
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from targets import check, finish

ROOT = Path(__file__).parents[1]
TOLERANCE = 1e-9
TESTS = {
    "coulomb_80": {"elements": 80, "fs": 0.9, "fd": 0.6, "fs_final": None},
    "coulomb_160": {"elements": 160, "fs": 0.9, "fd": 0.6, "fs_final": None},
    "runin_hl025": {"height": 20.0},
    "runin_hl050": {},
    "runin_hl075": {"height": 60.0},
    "weakening_80": {"elements": 80, "fs": 1.0, "fd": 0.6, "dc": 0.1, "fs_final": None},
    "weakening_160": {"elements": 160, "fs": 1.0, "fd": 0.6, "dc": 0.1, "fs_final": None},
}
SIGNALS = ("T", "N", "DG", "DD", "DT", "T_before_wave")
FEATURES = ("T_before", "T_after", "ratio_before", "ratio_after", "drop", "DG_jump",
            "DD_jump", "swept_fraction", "t_start")

# What each side runs, in its own process (the solver under test imported from its
# PYTHONPATH): the map's rows and the tests, written to a folder.
_RUN = """
import sys
from concurrent.futures import ProcessPoolExecutor
from functools import partial
from pathlib import Path
import xarray as xr
from slipwave.bench.generate import BenchTest, simulate_test
from slipwave.map import PAPER_FRICTIONS, PAPER_HEIGHT_RATIOS, map_row

TESTS = {tests!r}

# The reference cut each gross slip out of its actuator step (solving the step again to
# the first node's onset, then the rest); the solver since lets it land on its step.
# Without the cut both sides solve the same increments, kernel against kernel.
_simulate = sys.modules["slipwave.solver.simulate"]
if hasattr(_simulate, "_gross_onset"):
    _simulate._gross_onset = lambda *args: None

def test(item):
    name, spec = item
    result = simulate_test(BenchTest(name, video="none", **spec), seed=0)
    keep = result.simulation[["T", "N", "DG", "DD", "DT", "T_before_wave", "state", "wave"]]
    keep.attrs = {{}}
    keep.to_netcdf(Path(sys.argv[1]) / f"{{name}}.nc")
    result.events.to_csv(Path(sys.argv[1]) / f"{{name}}_events.csv", index=False)

if __name__ == "__main__":
    with ProcessPoolExecutor(2) as pool:
        # the mesh named: the map's default has moved from 160 to 320 elements since
        rows = list(pool.map(partial(map_row, elements=160), PAPER_HEIGHT_RATIOS,
                             [PAPER_FRICTIONS] * 12))
        xr.concat(rows, "height_ratio")[["sequence"]].to_netcdf(Path(sys.argv[1]) / "map.nc")
        list(pool.map(test, TESTS.items()))
"""


def run_side(source: Path, folder: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(source)}
    subprocess.run([sys.executable, "-c", _RUN.format(tests=TESTS), str(folder)],
                   env=env, check=True, cwd=folder)


def scale_difference(new: np.ndarray, old: np.ndarray) -> float:
    """Largest difference relative to the quantity's scale (its largest magnitude)."""
    scale = np.nanmax(np.abs(old)) if np.isfinite(old).any() else 1.0
    return float(np.nanmax(np.abs(new - old)) / max(scale, 1e-300)) if old.size else 0.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--reference", default="06b4878",
                        help="the commit of the interpreted solver")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        tree = folder / "reference"
        subprocess.run(["git", "worktree", "add", "--detach", str(tree), args.reference],
                       cwd=ROOT, check=True, capture_output=True)
        try:
            (folder / "old").mkdir()
            (folder / "new").mkdir()
            with ProcessPoolExecutor(1) as pool:  # the two sides one after the other
                list(pool.map(run_side, [tree / "src", ROOT / "src"],
                              [folder / "old", folder / "new"]))
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=ROOT,
                           check=False, capture_output=True)
        old = xr.open_dataset(folder / "old/map.nc")["sequence"].values
        new = xr.open_dataset(folder / "new/map.nc")["sequence"].values
        differ = np.argwhere(old != new)
        status = check("map cases whose succession differs", len(differ), 0, at_least=False)
        print(f"equivalence: map, {old.size} cases: {len(differ)} successions differ "
              f"({status} 0)")
        for i, j in differ[:10]:
            print(f"  case ({i}, {j}): {old[i, j]!r} -> {new[i, j]!r}")
        for name in TESTS:
            a = xr.open_dataset(folder / f"new/{name}.nc")
            b = xr.open_dataset(folder / f"old/{name}.nc")
            ea = pd.read_csv(folder / f"new/{name}_events.csv")
            eb = pd.read_csv(folder / f"old/{name}_events.csv")
            same = (a.sizes["step"] == b.sizes["step"] and len(ea) == len(eb)
                    and bool((a["state"].values == b["state"].values).all()))
            if not same:
                check(f"{name}: same steps, states and events", 0, 1, at_least=True)
                print(f"equivalence: {name}: steps {a.sizes['step']} vs {b.sizes['step']}, "
                      f"events {len(ea)} vs {len(eb)}: DIFFER")
                continue
            signals = max(scale_difference(a[v].values, b[v].values) for v in SIGNALS)
            visible = eb["visible"].astype(bool).to_numpy()
            features = max(scale_difference(ea.loc[visible, f].to_numpy(float),
                                            eb.loc[visible, f].to_numpy(float))
                           for f in FEATURES)
            worst = max(signals, features)
            status = check(f"{name}: relative difference", worst, TOLERANCE, at_least=False)
            print(f"equivalence: {name}: {a.sizes['step']} steps, {len(eb)} events "
                  f"({int(visible.sum())} visible), the same zone states; signals to "
                  f"{signals:.1e}, visible events' features to {features:.1e} of their "
                  f"scale ({status} {TOLERANCE:g})")
    finish()


if __name__ == "__main__":
    main()
