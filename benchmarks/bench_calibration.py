"""Calibration of the fit's posteriors (issue 35): do its intervals cover the truth?

A seeded generator draws virtual-bench tests from the fit's documented priors
(``slipwave.fit.laws.PRIORS``): a law (Coulomb, run-in, slip-weakening, one third each),
its parameters, and each load cell's calibration error from ``fit.load_calibration``.
Each test is made at four times the fit's mesh (320 elements against 80), so that no
test is fitted with the very model that made it: the fit's features are carried to twice
its mesh (``slipwave.fit.ensemble.mesh_error``'s shift), and a test made there would be
fitted, where the shift was measured, with its own model. Each is fitted with all three
laws, as the workflow does, on one core. (``--made-elements 80`` makes them at the fit's
own mesh: a control that measures the inference alone, without the mesh's error, and
is no benchmark of the fit.) Measured against the issue's targets:

- the chosen law's 95 % intervals hold the true fs and fd in at least 90 % of the tests;
  their median half-width at most 1.5 % (fd) and 5 % (fs);
- the right law in at least 85 % of the tests; Dc inside its interval in at least 90 %
  of the slip-weakening tests;
- the chosen law's posterior predictive agrees on every feature in at least 90 %;
- a test's fit, three laws with their ensembles, at most 60 s on one core (median);
- simulation-based calibration (Talts et al. 2018): the rank of each true parameter
  among 99 thinned posterior samples of its own law, whose histogram is uniform when
  the posterior is calibrated; chi-square test over 5 bins (p above 0.01).

A recording none of the laws can reproduce is fitted too: a run-in that turns, its static
coefficient 0.8 at the first gross slip, 1.33 at the second and third and 0.8 again from
the fourth on (``fs_peak`` 1.6 and ``fs_final`` 0.8 over 1.5 slips each way; fd 0.6).
The features the fit compares could show it (the first three gross slips' T/|N| each,
then the later ones' median), but only at the edge: the turn moves T/|N| by 0.06, about
three of the predictive's standard deviations, and is flagged on some seed sets, not on
others. Coulomb holds fs, the run-in law goes one way, and
slip-weakening's coefficient falls within a slip, not from one slip to the next.
(Slip-weakening with a run-in, the recording used before, was reproduced by the
slip-weakening law alone within the features' errors: no misspecification the features
see.) It is made and fitted three times (:data:`MISSPECIFIED_DRAWS`: other sensor noise,
members and draws). Target: in every draw its chosen law's predictive differs on at
least one feature, and the test's page would say so.

A drawn test without two gross slips in its 280 s, or one the solver cannot follow, is
drawn again (no fit can tell a law's dynamic coefficient without a gross slip); how
many were is reported.

Run: make bench  (or python benchmarks/bench_calibration.py --seed N --tests K)
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import json
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import chisquare

from slipwave.bench.generate import BenchTest, simulate_test, write_test
from slipwave.bench.sensors import DEFAULT_SENSORS
from slipwave.defaults import FIT_ELEMENTS, LOAD_CALIBRATION
from slipwave.errors import SlipwaveError
from slipwave.fit import FitSettings, measured_events
from slipwave.fit.laws import LAWS, draw_prior
from slipwave.fit.procedure import choose_law, dc_per_excess, fit_laws
from slipwave.io import read_acquisition
from slipwave.setup import Setting, TestSetup, read_test_setup
from targets import check, finish

CELLS = {"youngs_modulus_mpa": "7", "poisson_ratio": "0.48", "edge_reference": "frame"}
RANKS = 99
BINS = 5
COVERAGE, FD_WIDTH, FS_WIDTH, RIGHT_LAW, DC_COVERAGE, AGREES = 0.9, 0.015, 0.05, 0.85, 0.9, 0.9
UNIFORM_P = 0.01
FIT_SECONDS = 60.0
DRAWS = 20
MADE_ELEMENTS = 4 * FIT_ELEMENTS
"""The tests' mesh: beyond the twice-the-fit's mesh the fit carries its features to."""


def draw_test(seed: int, index: int, made_elements: int = MADE_ELEMENTS
              ) -> tuple[BenchTest, dict[str, Any], dict[str, float]]:
    """Test ``index`` of the seed set, made on ``made_elements``: its spec, law and gains."""
    rng = np.random.default_rng([seed, index])
    law = str(rng.choice(list(LAWS)))
    probe = BenchTest("probe", elements=MADE_ELEMENTS, video="none")
    # the prior stops at the Dc the fit's mesh resolves (its process zone, 3 elements)
    setup = TestSetup("probe", {key: Setting(value, "bench") for key, value in {
        "length_mm": probe.length, "width_mm": probe.width,
        "youngs_modulus_mpa": probe.youngs_modulus, "poisson_ratio": probe.poisson_ratio,
        "normal_load_n": probe.normal_load}.items()}, "frame")
    params = draw_prior(law, rng, dc_per_excess=dc_per_excess(setup, FIT_ELEMENTS))
    gains = {"T": float(rng.normal(0.0, LOAD_CALIBRATION)),
             "N": float(rng.normal(0.0, LOAD_CALIBRATION))}
    truth = {"fs": params["fs"], "fd": params["fd"], "fs_final": None, "runin_slips": 4,
             "dc": None}
    if law == "run-in":
        # as drawn, not rounded: a rounded truth is no draw from the prior (its ranks
        # are then not uniform), and one rounded to the prior's bound (1 or 10) lies
        # outside every central interval
        truth.update(fs_final=params["fs_final"], runin_slips=params["runin_slips"])
    if law == "slip-weakening":
        truth["dc"] = params["dc"]
    spec = BenchTest(f"cal{seed}-{index}", elements=made_elements, video="none", **truth)
    return spec, {"law": law, "params": params}, gains


MISSPECIFIED = {"fs": 0.8, "fd": 0.6, "fs_peak": 1.6, "fs_final": 0.8, "runin_slips": 1.5}
"""The recording none of the laws reproduces: a run-in that turns (up, then back)."""
MISSPECIFIED_DRAWS = 3
"""Its recordings (the sensors' noise, the fit's members and draws differ): the first
one's seed set is the one its turn was chosen on, the others are not."""


def one(job: tuple[int, int, int]) -> dict[str, Any]:
    """Draw test ``job`` (seed, index, mesh; redrawn while it shows fewer than two gross
    slips) and fit it.

    A negative index is a draw of the misspecified test (:data:`MISSPECIFIED`).
    """
    seed, index, made_elements = job
    start = time.perf_counter()
    redrawn = 0
    for attempt in range(DRAWS):
        if index < 0:
            spec = BenchTest("misspecified", elements=made_elements, video="none",
                             **MISSPECIFIED)
            truth = {"law": "run-in that turns", "params": dict(MISSPECIFIED)}
            gains = {"T": 0.0, "N": 0.0}
        else:
            spec, truth, gains = draw_test(seed, index + 1000 * attempt, made_elements)
        sensors = {**DEFAULT_SENSORS,
                   "T": replace(DEFAULT_SENSORS["T"], gain=gains["T"]),
                   "N": replace(DEFAULT_SENSORS["N"], gain=gains["N"])}
        try:
            result = simulate_test(spec, seed=seed * 1000 + index, sensors=sensors)
        except SlipwaveError:  # a law the solver cannot follow on this slab: drawn again
            redrawn += 1
            continue
        events = result.events
        gross = int(((events["kind"] == "gross_slip") & events["visible"]).sum()
                    if not events.empty else 0)
        if gross >= 2:
            break
        redrawn += 1
    print(f"calibration: test {index} ({truth['law']}, {truth['params']}) made in "
          f"{time.perf_counter() - start:.0f} s, fitting", file=sys.stderr, flush=True)
    with tempfile.TemporaryDirectory() as folder:
        recording = read_acquisition(write_test(result, Path(folder))["csv"])
    settings = FitSettings.from_values({"mesh_check": False})
    made = time.perf_counter() - start
    try:
        events = measured_events(recording)
        setup = read_test_setup(recording, CELLS)
        fitted = fit_laws(setup, events, settings)
    except SlipwaveError as err:
        return {"index": index, "truth": truth, "error": str(err), "redrawn": redrawn}
    choice = choose_law(fitted, settings)
    chosen, predictive = choice.posterior, choice.predictive
    ranks = {}
    if truth["law"] in fitted.posteriors:
        own = fitted.posteriors[truth["law"]]
        thinned = own.samples[np.linspace(0, own.samples.shape[0] - 1, RANKS).astype(int)]
        ranks = {name: int(np.sum(thinned[:, k] < truth["params"][name]))
                 for k, name in enumerate(LAWS[truth["law"]])}
    differs = [name for name, c in predictive.items() if not c["agrees"]]
    print(f"calibration: test {index} ({truth['law']}) fitted in "
          f"{time.perf_counter() - start - made:.0f} s: {chosen.law} "
          + ", ".join(f"{k} {v['value']:.4g} [{v['low']:.4g}, {v['high']:.4g}]"
                      for k, v in chosen.summary().items())
          + f"; predictive differs on {differs}", file=sys.stderr, flush=True)
    return {"index": index, "truth": truth, "gains": gains, "redrawn": redrawn,
            "gross_slips": gross, "chosen": chosen.law,
            "log_evidence": {law: p.log_evidence for law, p in fitted.posteriors.items()},
            "summaries": {law: p.summary() for law, p in fitted.posteriors.items()},
            "ranks": ranks, "agrees": all(c["agrees"] for c in predictive.values()),
            "differs": differs,
            "simulations": sum(fitted.simulations.values()),
            "seconds_made": made, "seconds_fit": time.perf_counter() - start - made}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seed", type=int, default=4503)  # fresh for the reported figures
    parser.add_argument("--tests", type=int, default=20)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--output", type=Path, default=None, help="JSON of every test's fit")
    parser.add_argument("--made-elements", type=int, default=MADE_ELEMENTS,
                        help="the tests' mesh; the fit's own (a control: the inference "
                             "alone, without the mesh's error) is not a benchmark of the fit")
    args = parser.parse_args()
    load = os.getloadavg()[0]
    begun = time.perf_counter()
    jobs = ([(args.seed, -k, args.made_elements) for k in range(1, MISSPECIFIED_DRAWS + 1)]
            + [(args.seed, k, args.made_elements) for k in range(args.tests)])
    done: dict[int, dict[str, Any]] = {}
    with ProcessPoolExecutor(args.jobs) as pool:
        futures = [pool.submit(one, job) for job in jobs]
        for future in as_completed(futures):
            result = future.result()
            done[result["index"]] = result
            if args.output:  # each test kept as it ends: a long run stopped loses none
                partial = args.output.with_suffix(".partial")
                partial.write_text(json.dumps(list(done.values()), indent=1, default=float),
                                   encoding="utf-8")
                partial.replace(args.output)
    runs = [done[index] for _, index, _ in jobs]
    wall = time.perf_counter() - begun
    odd, runs = runs[:MISSPECIFIED_DRAWS], runs[MISSPECIFIED_DRAWS:]
    fitted = [r for r in runs if "error" not in r]
    print(f"calibration: {len(runs)} tests (seed set {args.seed}) made at "
          f"{args.made_elements} elements, fitted at {FIT_ELEMENTS}; {len(fitted)} fitted, "
          f"{sum(r['redrawn'] for r in runs)} redrawn for lack of gross slips; "
          f"{wall:.0f} s on {args.jobs} processes (load average {load:.2f} before)")
    for r in runs:
        truth = r["truth"]
        law = ", ".join(f"{k} {v:.4g}" for k, v in truth["params"].items())
        if "error" in r:
            print(f"  {r['index']:2d} {truth['law']} ({law}): not fitted: {r['error']}")
            continue
        chosen = r["summaries"][r["chosen"]]
        fitted_text = ", ".join(f"{k} {v['value']:.4g} [{v['low']:.4g}, {v['high']:.4g}]"
                                for k, v in chosen.items())
        print(f"  {r['index']:2d} {truth['law']} ({law}); {r['gross_slips']} gross slips -> "
              f"{r['chosen']}: {fitted_text}; predictive "
              f"{'agrees' if r['agrees'] else 'differs on ' + ', '.join(r['differs'])}; "
              f"{r['simulations']} simulations, fit {r['seconds_fit']:.0f} s")
    covered = {name: [] for name in ("fs", "fd")}
    widths = {name: [] for name in ("fs", "fd")}
    for r in fitted:
        chosen = r["summaries"][r["chosen"]]
        for name in covered:
            true = r["truth"]["params"][name]
            covered[name].append(chosen[name]["low"] <= true <= chosen[name]["high"])
            widths[name].append(0.5 * (chosen[name]["high"] - chosen[name]["low"])
                                / chosen[name]["value"])
    n = max(1, len(fitted))
    for name, target in (("fs", FS_WIDTH), ("fd", FD_WIDTH)):
        share = float(np.mean(covered[name])) if fitted else 0.0
        status = check(f"calibration: {name} covered", share, COVERAGE, at_least=True)
        print(f"calibration: the chosen law's 95 % interval holds the true {name} in "
              f"{sum(covered[name])} of {len(fitted)} tests ({100 * share:.0f} %, {status} >= "
              f"{100 * COVERAGE:.0f} %)")
        median = float(np.median(widths[name])) if fitted else np.inf
        status = check(f"calibration: {name} median half-width", median, target,
                       at_least=False)
        print(f"calibration: {name}'s median half-width {100 * median:.2f} % ({status} <= "
              f"{100 * target:.1f} %)")
    right = sum(r["chosen"] == r["truth"]["law"] for r in fitted)
    status = check("calibration: right law", right / n, RIGHT_LAW, at_least=True)
    print(f"calibration: the right law in {right} of {len(fitted)} tests ({status} >= "
          f"{100 * RIGHT_LAW:.0f} %)")
    weakening = [r for r in fitted if r["truth"]["law"] == "slip-weakening"]
    inside = [r["summaries"]["slip-weakening"]["dc"]["low"] <= r["truth"]["params"]["dc"]
              <= r["summaries"]["slip-weakening"]["dc"]["high"] for r in weakening]
    share = float(np.mean(inside)) if inside else 0.0
    status = check("calibration: Dc covered", share, DC_COVERAGE, at_least=True)
    print(f"calibration: Dc inside its interval in {sum(inside)} of {len(inside)} "
          f"slip-weakening tests ({status} >= {100 * DC_COVERAGE:.0f} %)")
    agrees = sum(r["agrees"] for r in fitted)
    status = check("calibration: predictive agrees", agrees / n, AGREES, at_least=True)
    print(f"calibration: the chosen law's predictive agrees on every feature in {agrees} of "
          f"{len(fitted)} tests ({status} >= {100 * AGREES:.0f} %)")
    for name in ("fs", "fd", "fs_final", "runin_slips", "dc"):
        ranks = [r["ranks"][name] for r in fitted if name in r["ranks"]]
        if len(ranks) < BINS:
            continue
        counts = np.histogram(ranks, bins=BINS, range=(0, RANKS + 1))[0]
        p = float(chisquare(counts).pvalue)
        status = check(f"calibration: {name} ranks uniform (p)", p, UNIFORM_P, at_least=True)
        print(f"calibration: {name}'s ranks (of {RANKS + 1}) over {len(ranks)} tests, in "
              f"{BINS} bins: {counts.tolist()}; chi-square p {p:.3f} ({status} > {UNIFORM_P})")
    flagged = sum("error" not in r and not r["agrees"] for r in odd)
    status = check("calibration: a recording no law reproduces is flagged, share of draws",
                   flagged / len(odd), 1.0, at_least=True)
    print(f"calibration: a run-in that turns (fs 0.8, then 1.33 at the second and third gross "
          f"slips, then 0.8), which no law fitted reproduces, flagged in {flagged} of "
          f"{len(odd)} draws ({status} all; the first draw's seed is the one its turn was "
          "chosen on): " + "; ".join(
              f"chosen {r.get('chosen')}, predictive "
              + (f"differs on {', '.join(r['differs'])}" if r.get("differs")
                 else "agrees everywhere" if "error" not in r else f"error {r['error']}")
              for r in odd))
    seconds = [r["seconds_fit"] for r in fitted]
    if seconds:
        median = float(np.median(seconds))
        status = check("calibration: a test's fit, median s", median, FIT_SECONDS,
                       at_least=False)
        print(f"calibration: a test's fit (three laws with their ensembles, and the chosen "
              f"law's predictive) took {median:.0f} s median ({status} <= {FIT_SECONDS:.0f} "
              f"s), {max(seconds):.0f} s at most, one core each ({args.jobs} at once)")
    finish()


if __name__ == "__main__":
    main()
