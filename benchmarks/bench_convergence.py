"""Mesh convergence of the fit's features (issue 34): what moves when the mesh is doubled.

The virtual bench's 280 s test (H/L 0.5, N 85 N held, the flat driven at 48 um/s
through a 40 N/mm machine) is simulated under Coulomb's law with fs > fd, under run-in
(fs rising over the first gross slips) and under linear slip-weakening over several
Dc, each at 40 to 640 elements along the contact, and under Coulomb's law again with
the slab's corners rounded (2 mm radius); each simulation's features are read as the
fit reads them (detection on its noise-free recording). Written:

- ``docs/_static/convergence.csv``: every law, mesh and feature;
- ``docs/_static/convergence.png``: each feature against the element count;
- ``docs/_static/convergence_changes.csv``: each feature's change from each mesh to
  twice it, also in units of the uncertainty the fit gives it;
- ``docs/_static/convergence_summary.csv``: per law, the largest of those at each
  doubling and the coarsest mesh from which they all stay within one;
- here: for each law, its process zone and elements across it at each mesh, the
  largest change of any fitted feature from each mesh to twice it (in those
  uncertainties), how far the first slip moves, and the coarsest mesh from which
  every doubling keeps every fitted feature within its uncertainty.

There is no pass or fail: the figures are what the mesh study of
``docs/methods/convergence.md`` reads.

Run: make bench  (or python benchmarks/bench_convergence.py [--elements 40 80 ...])
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from slipwave.bench.generate import BenchTest
from slipwave.convergence import (
    FEATURES,
    converged_from,
    mesh_changes,
    simulated_summary,
)
from slipwave.setup import Setting, TestSetup
from slipwave.solver import Coulomb, SlipWeakening
from slipwave.solver.slab import rounded_corners

ROOT = Path(__file__).parents[1]
STATIC = ROOT / "docs" / "_static"
MIN_DROP_N = 0.5

LAWS: dict[str, Coulomb] = {
    "Coulomb fs 0.9 fd 0.6": Coulomb(fs=0.9, fd=0.6),
    "run-in fs 0.9 → 1.3, fd 0.6": Coulomb(fs=0.9, fd=0.6, fs_final=1.3, runin_slips=4),
    **{f"slip-weakening Dc {dc:g} mm": SlipWeakening(fs=0.9, fd=0.6, dc=dc)
       for dc in (0.02, 0.05, 0.1, 0.2)},
    "Coulomb fs 0.9 fd 0.6, corners rounded 2 mm": Coulomb(fs=0.9, fd=0.6),
}
CORNER_RADII: dict[str, float] = {"Coulomb fs 0.9 fd 0.6, corners rounded 2 mm": 2.0}
"""The cases whose slab has rounded corners (radius, mm); the others' are sharp."""


def bench_setup(spec: BenchTest) -> TestSetup:
    """The setup a fit would read from the virtual test's files, straight from its spec."""
    values = {"length_mm": spec.length, "height_mm": spec.height, "width_mm": spec.width,
              "youngs_modulus_mpa": spec.youngs_modulus, "poisson_ratio": spec.poisson_ratio,
              "normal_load_n": spec.normal_load, "speed_mm_s": spec.speed,
              "machine_stiffness_n_mm": spec.machine_stiffness,
              "duration_s": spec.duration, "loading_time_s": spec.loading_time}
    return TestSetup(spec.test_id, {key: Setting(float(value), "virtual bench spec")
                                    for key, value in values.items()}, "frame")


SPEC = BenchTest("hl050", height=40.0, video="none")
SETUP = bench_setup(SPEC)


def one(job: tuple[str, int]) -> dict[str, float | str]:
    law, elements = job
    start = time.perf_counter()
    radius = CORNER_RADII.get(law)
    summary = simulated_summary(SETUP, LAWS[law], elements, min_drop=MIN_DROP_N,
                                sample_rate=SPEC.sample_rate,
                                profile=rounded_corners(radius, SETUP["length_mm"])
                                if radius else None)
    return {"law": law, "elements": elements, **summary,
            "seconds": time.perf_counter() - start}


def figure(table: pd.DataFrame, path: Path) -> None:
    names = list(FEATURES)
    meshes = sorted(table["elements"].unique())
    fig, axes = plt.subplots(2, 5, figsize=(17, 7), sharex=True)
    for ax, name in zip(axes.ravel(), names, strict=True):
        for law, group in table.groupby("law", sort=False):
            ax.plot(group["elements"], group[name], marker="o", ms=3, label=law)
        ax.set_xscale("log", base=2)
        ax.set_xticks(meshes, [str(n) for n in meshes])
        ax.minorticks_off()
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.set_title(FEATURES[name].replace(" (x / L, 0 at the contact's centre)", " (x / L)"),
                     fontsize=9)
        ax.tick_params(labelsize=8)
    axes[0, 3].set_ylim(0.59, 0.61)  # fd for every law: a flat line, not noise magnified
    for ax in axes[-1]:
        ax.set_xlabel("elements along the contact", fontsize=9)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(4, len(labels)), fontsize=9,
               frameon=False)
    fig.suptitle("The fit's features against the mesh: the virtual bench's 280 s test "
                 "(H/L 0.5), noise-free", fontsize=11)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def summary(changes: pd.DataFrame, start_of: pd.Series, meshes: list[int]) -> pd.DataFrame:
    """One row per law: its process zone, the largest change at each doubling."""
    fitted = changes[changes["feature"] != "first_slip_place"]
    moved = fitted["sigmas"].abs().fillna(np.inf)
    rows = []
    for law, friction in LAWS.items():
        zone = SETUP.process_zone(friction)
        row: dict[str, str] = {
            "law": law,
            "process zone (mm)": f"{zone:.1f}" if zone else "none",
            "elements across it at 80": f"{zone * 80 / SETUP['length_mm']:.1f}" if zone
            else "",
        }
        for coarse in meshes[:-1]:
            mine = moved[(fitted["law"] == law) & (fitted["elements"] == coarse)]
            worst = float(mine.max()) if mine.size else float("nan")
            row[f"{coarse} → {2 * coarse}"] = ("a feature appears or vanishes"
                                                if np.isinf(worst) else f"{worst:.2f}")
        found = start_of[law]
        row["within from"] = f"{int(found)}" if np.isfinite(found) else "none studied"
        rows.append(row)
    return pd.DataFrame(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--elements", type=int, nargs="+", default=[40, 80, 160, 320, 640])
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    load = os.getloadavg()[0]
    # the finest first, so that the longest runs do not come last
    jobs = [(law, n) for n in sorted(args.elements, reverse=True) for law in LAWS]
    start = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        rows = list(pool.map(one, jobs))
    table = (pd.DataFrame(rows).set_index(["law", "elements"])
             .loc[[(law, n) for law in LAWS for n in sorted(args.elements)]].reset_index())
    print(f"convergence: {len(jobs)} simulations in {time.perf_counter() - start:.0f} s on "
          f"{args.jobs} processes (load average {load:.2f} before)")
    STATIC.mkdir(parents=True, exist_ok=True)
    table.round(6).to_csv(STATIC / "convergence.csv", index=False)
    figure(table, STATIC / "convergence.png")

    changes = mesh_changes(table)
    changes.round(6).to_csv(STATIC / "convergence_changes.csv", index=False)
    start_of = converged_from(changes)
    summary(changes, start_of, sorted(args.elements)).to_csv(
        STATIC / "convergence_summary.csv", index=False)
    for law, friction in LAWS.items():
        zone = SETUP.process_zone(friction)
        across = ", ".join(f"{n} el {zone * n / SETUP['length_mm']:.1f}"
                           for n in sorted(args.elements))
        print(f"convergence: {law}: process zone {zone:.1f} mm"
              + (f" (elements across it: {across})" if zone else " (none: no length)"))
        mine = changes[(changes["law"] == law) & (changes["feature"] != "first_slip_place")]
        moved = mine["sigmas"].abs().fillna(np.inf)
        for elements, rows in mine.groupby("elements"):
            row = rows.loc[moved[rows.index].idxmax()]
            place = changes[(changes["law"] == law) & (changes["elements"] == elements)
                            & (changes["feature"] == "first_slip_place")]["change"]
            print(f"    {elements} -> {2 * elements} el: largest change {row['sigmas']:+.2f} "
                  f"sigma ({FEATURES[row['feature']]}: {row['value']:.4g} -> "
                  f"{row['finer']:.4g}); first slip moves {float(place.iloc[0]) * 80:+.1f} mm")
        found = start_of[law]
        print("    every fitted feature within its uncertainty of twice the mesh from "
              + (f"{int(found)} elements" if np.isfinite(found) else "no mesh studied"))
    times = table.groupby("elements")["seconds"].max()
    print("convergence: slowest simulation per mesh: " + ", ".join(
        f"{n} el {s:.1f} s" for n, s in times.items()))


if __name__ == "__main__":
    main()
