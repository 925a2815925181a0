"""Rate-and-state laws fitted on quasi-dynamic virtual tests (issue 37, item 5): coverage.

Laws drawn by a seeded generator from the fit's own prior restricted to where this slab
makes waves a 25 frames/s camera follows (a in [0.008, 0.012]; b - a in [0.015, 0.03];
D_c log-uniform in [40, 80] um; mu0 in [0.8, 1.0]), each made a 280 s virtual-bench test
of the bench's slab (H 40 mm, 85 N, 0.048 mm/s) at 160 elements, its card recorded and
its video filmed, tracked as the workflow's video stage tracks it. Each is then fitted
(:func:`slipwave.fit_waves.fit_filmed_test`) at 80 elements, half the mesh that made it:
no test is fitted with the model and mesh that made it.

Targets: each true a, b, D_c inside its 95 % interval in at least 90 % of the tests
(issue 37's acceptance); the fit's time is reported.

Run: make bench  (or python benchmarks/bench_fit_waves.py [tests] [processes] [seed])
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from bench_quasi_dynamic_tests import setup_of
from slipwave.bench import BenchTest, simulate_test, write_test
from slipwave.errors import SlipwaveError
from slipwave.fit_waves import (
    WavesFitSettings,
    filmed_test,
    fit_filmed_test,
    loglik,
    simulate_guess,
)
from slipwave.io import read_acquisition
from slipwave.solver.rate_state import RateState
from slipwave.video import find_geometry, kymograph, open_frames, track_waves
from targets import check, finish

SEED = 5113  # the laws' draws: fresh for the likelihood without the share followed, built
# on 5112's two misses (5107-5112 seen by earlier searches, 5110 by a failed fit)
TESTS = 12  # six of 5112's ten laws gave a test to fit
TRUTH_ELEMENTS = 160
FIT_ELEMENTS = 80
DURATION = 280.0
TARGET = 0.9  # share of tests whose true a, b and D_c all lie inside their intervals


def draw_laws(rng: np.random.Generator, count: int) -> list[dict[str, float]]:
    """Laws of slow fronts from the benchmark's priors."""
    laws = []
    for _ in range(count):
        a = float(rng.uniform(0.008, 0.012))
        laws.append({"a": a, "b": a + float(rng.uniform(0.015, 0.03)),
                     "dc_um": float(np.exp(rng.uniform(np.log(40.0), np.log(80.0)))),
                     "mu0": float(rng.uniform(0.8, 1.0)), "v0_um_s": 1.0})
    return laws


def made_test(job: tuple[int, dict[str, float], int]) -> tuple[BenchTest, xr.Dataset,
                                                                pd.DataFrame, float]:
    """A law's virtual test: its spec, card recording, video's waves and CPU time."""
    k, law, seed = job  # the law's index, the law, the draws' seed
    spec = BenchTest(f"qd{k}", elements=TRUTH_ELEMENTS, duration=DURATION, rate_state=law,
                     video="ffv1")
    start = time.process_time()
    with tempfile.TemporaryDirectory() as folder:
        paths = write_test(simulate_test(spec, seed=seed + k), Path(folder))
        video = paths["video"]
        waves = track_waves(kymograph(open_frames(video),
                                      find_geometry(open_frames(video), spec.length)))
        recording = read_acquisition(paths["csv"])
    waves["t_start_card"] = spec.camera.acquisition_time(waves["t_start"].to_numpy())
    return spec, recording, waves, time.process_time() - start


def main() -> None:
    tests = int(sys.argv[1]) if len(sys.argv) > 1 else TESTS
    processes = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    seed = int(sys.argv[3]) if len(sys.argv) > 3 else SEED
    print(f"rate-and-state fits of quasi-dynamic tests (seed {seed}): load average "
          f"{os.getloadavg()[0]:.2f} before")
    settings = WavesFitSettings(elements=FIT_ELEMENTS, processes=processes)
    laws = draw_laws(np.random.default_rng(seed), tests)
    with ProcessPoolExecutor(processes) as pool:  # the tests made side by side first
        made = list(pool.map(made_test, [(k, law, seed) for k, law in enumerate(laws)]))
    rows = []
    for law, (spec, recording, waves, seconds_made) in zip(laws, made, strict=True):
        try:
            test = filmed_test(setup_of(spec), recording, waves, frame_rate=spec.camera.fps)
        except SlipwaveError as err:  # a law of the prior that slid steadily: reported
            print(f"  {spec.test_id}: not fitted ({err})", flush=True)
            continue
        began = time.perf_counter()
        try:
            posterior = fit_filmed_test(test, settings)
        except SlipwaveError as err:  # a fit that fails counts as a miss, said
            print(f"  {spec.test_id}: the fit failed ({err})", flush=True)
            rows.append({"test": spec.test_id, "a_inside": False, "b_inside": False,
                         "dc_um_inside": False, "mu0_inside": False, "fit_s": np.nan})
            continue
        seconds = time.perf_counter() - began
        interval = posterior.interval()
        truth = {"a": law["a"], "b": law["b"], "dc_um": law["dc_um"], "mu0": law["mu0"]}
        inside = {name: interval[name][1] <= value <= interval[name][2]
                  for name, value in truth.items()}
        rows.append({"test": spec.test_id, **{f"true_{n}": v for n, v in truth.items()},
                     **{f"{n}": interval[n][0] for n in truth},
                     **{f"{n}_inside": inside[n] for n in truth},
                     "windows": test.windows, "followed": test.followed,
                     "made_s": seconds_made, "fit_s": seconds})
        error = posterior.mesh_error
        # the truth's own likelihood at the fit's mesh: a miss with the truth above the
        # best guess is the search's, one below it the likelihood's
        at_truth = loglik(test, simulate_guess(
            test, RateState(a=law["a"], b=law["b"], dc=law["dc_um"] * 1e-6, mu0=law["mu0"],
                            v0=law["v0_um_s"] * 1e-6),
            elements=FIT_ELEMENTS, members=settings.members, seed=settings.seed), error)
        print(f"  {spec.test_id}: " + "; ".join(
            f"{n} {truth[n]:.4g} -> {interval[n][0]:.4g} [{interval[n][1]:.4g}, "
            f"{interval[n][2]:.4g}]{'' if inside[n] else ' OUTSIDE'}" for n in truth)
            + f" ({test.windows} windows of {test.window:.1f} s, {test.followed}/{test.waves} "
            f"waves followed, median {np.median(test.speeds) if test.speeds else np.nan:.0f} "
            f"mm/s; mesh error card "
            f"{error.card.round(4).tolist()}, log speed {error.speed:.3f}; made in "
            f"{seconds_made:.0f} s of CPU, fitted in {seconds:.0f} s on {processes} "
            f"processes, {len(posterior.points)} guesses; log-likelihood at the best guess "
            f"{np.nanmax(posterior.logliks):.1f}, at the truth {at_truth:.1f})", flush=True)
    table = pd.DataFrame(rows)
    if len(table):
        covered = table[["a_inside", "b_inside", "dc_um_inside"]].all(axis=1)
        share = float(covered.mean())
        for name in ("a", "b", "dc_um", "mu0"):
            print(f"{name}: inside its 95 % interval in {int(table[f'{name}_inside'].sum())} "
                  f"of {len(table)}")
        print(f"a, b and D_c all inside in {int(covered.sum())} of {len(table)}")
        print(f"median fit time {table['fit_s'].median():.0f} s")
    else:
        share = 0.0
    status = check("fitted tests whose a, b and D_c lie inside their intervals", share,
                   TARGET, at_least=True)
    print(f"  target: at least {TARGET:.0%}: {status}")
    print(f"rate-and-state fits of quasi-dynamic tests: load average "
          f"{os.getloadavg()[0]:.2f} after")
    finish()


if __name__ == "__main__":
    main()
