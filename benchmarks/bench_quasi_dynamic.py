"""The quasi-dynamic contact (issue 37): its 1-node reduction, its fronts' convergence, its time.

The bench's slab (H/L 0.5, 76 N pressed without friction, the flat's normal position
then held, driven at 0.048 mm/s) under rate-and-state friction (aging law, a 0.01,
b 0.015, Dc 2 um, mu0 0.9: T/N near 0.85 at its slips, as the bench's near 1), with the
polyurethane's radiation damping (density 1200 kg/m^3, shear waves at 44 m/s).

1. The 1-node reduction against the quasi-dynamic spring-slider (scipy's LSODA on the
   slider's own equations): the largest difference of T/N over 30 s of stick-slip.
2. Convergence: the first 70 s (the stick, then eight or nine waves) at 80, 160 and 320
   elements; each wave's front speed (Theil-Sen on the side it runs to), start and
   drop; the median front speed at each mesh (nine waves: reported, the target is
   taken on the whole test's).
   The same against the steps' tolerance: the default against ten times tighter, at 160
   elements. Target: within 5 %.
3. The whole 280 s test at 80, 160, 320 and 640 elements, on one core: the mesh used is
   the coarsest whose front speeds agree with twice its elements' (the median within
   5 %, and Mann-Whitney's U p >= 0.05). Target: its time <= 10 s. Where the time goes
   (each compiled kernel's calls per step, and its time per call at a stuck state and
   in a wave).
   What a multirate integrator could save at best, on the same test at 320 elements:
   after each step, each node's own local error estimate (the RMS of its entries', in
   units of their tolerance) says how much longer a step of that node alone could have
   been, by its order's power (err^(-1/(q+1))); the node-steps of an ideal integrator
   that stepped each node at its own pace, with no cost for the coupling, the
   interpolation of its neighbours or a second history, against those of a global
   integrator held to the same per-node error (the largest node's pace) and against
   today's (every node at every step), by what the fastest node does (creeping below
   0.01 mm/s, nucleating to 1 mm/s, in a front above).
4. A figure of the 160-element run for the documentation (T/N, where the contact slips
   against time, one wave's arrivals): docs/_static/quasi_dynamic_waves.png.

The runs are deterministic: no seed to choose.
Run: make bench  (or python benchmarks/bench_quasi_dynamic.py)
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import itertools
import math
import time
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from numba import njit, objmode
from scipy.stats import mannwhitneyu

from slipwave.solver import quasi_dynamic_steps as steps
from slipwave.solver import quasi_dynamic_stretch as stretch_steps
from slipwave.solver import stiff_steps
from slipwave.solver.fronts import front_waves, slip_intervals
from slipwave.solver.quasi_dynamic import (
    TOLERANCE,
    Drive,
    record_times,
    shear_impedance,
    simulate_quasi_dynamic,
    slab_body,
    spring_slider_body,
)
from slipwave.solver.rate_state import RateState
from slipwave.solver.slab import Slab
from slipwave.solver.spring_slider import SpringSlider, simulate_spring_slider
from targets import check, finish

LAW = RateState(a=0.01, b=0.015, dc=2e-6, mu0=0.9)
DRIVE = Drive(normal_load=76.0, drive_speed=0.048)
CONVERGENCE_TARGET = 0.05
TIME_TARGET = 10.0
MESHES = (80, 160, 320)
WHOLE_TEST_MESHES = (80, 160, 320, 640)
SAME_DISTRIBUTION_P = 0.05  # Mann-Whitney's U: below, the two meshes' speeds differ
MIN_EXTENT = 0.25  # the video's smallest wave
FIGURE = Path(__file__).resolve().parent.parent / "docs" / "_static" / "quasi_dynamic_waves.png"


def run(elements: int, duration: float) -> tuple[xr.Dataset, float]:
    """A run of the bench's slab, and its time (the slab condensed beforehand)."""
    body = slab_body(Slab(elements=elements))
    start = time.process_time()
    ds = simulate_quasi_dynamic(body, LAW, DRIVE, duration=duration, sample_rate=100.0,
                                field_times=record_times(duration, 10.0))
    return ds, time.process_time() - start


def one_node() -> None:
    """The 1-node reduction against the damped spring-slider."""
    law = RateState(a=0.01, b=0.015, dc=1e-6, mu0=0.6)
    body = spring_slider_body(stiffness=1.0, normal_load=0.3, damping=1e-3)
    start = time.process_time()
    reduced = simulate_quasi_dynamic(body, law, Drive(0.3, 0.01), duration=30.0,
                                     sample_rate=100.0)
    middle = time.process_time()
    slider = simulate_spring_slider(SpringSlider(0.0, 1000.0, 1e-5, 0.3, damping=1.0), law,
                                    duration=30.0, sample_rate=100.0, initial_ratio=0.0,
                                    initial_log_state=math.log(10.0))
    end = time.process_time()
    ratio = (reduced["T"] / reduced["N"]).values
    difference = np.abs(ratio - slider["friction_ratio"].values)
    print(f"quasi-dynamic: 1 node against the quasi-dynamic spring-slider (K 1000 N/m, "
          f"K_c 1500, eta 1 N s/m, 30 s): T/N from {ratio.min():.4f} to {ratio.max():.4f}, "
          f"largest difference {difference.max():.2e} (at a slip's sample), median "
          f"{np.median(difference):.1e}; {middle - start:.2f} s against LSODA on the "
          f"slider's equations {end - middle:.2f} s")


def figure(ds: xr.Dataset, elements: int) -> None:
    """T/N, the slip intervals and one wave's arrivals, for the documentation."""
    intervals = slip_intervals(ds)
    x = ds["x"].values
    waves = front_waves(ds, min_extent=MIN_EXTENT)
    shown = waves.iloc[min(2, len(waves) - 1)]
    fig, axes = plt.subplots(3, 1, figsize=(8, 8.5), constrained_layout=True)
    axes[0].plot(ds["time"], ds["T"] / ds["N"], lw=0.8, color="k")
    axes[0].set(ylabel="T / N", xlim=(0, float(ds["time"][-1])),
                title=f"The bench's slab, rate-and-state friction, {elements} elements")
    # a wave lasts tens of milliseconds: each node's slips drawn as a tick where they start
    axes[1].plot(intervals["start"], x[intervals["node"]], "|", color="tab:red", ms=3)
    axes[1].set(ylabel="x (mm)", xlim=axes[0].get_xlim(), ylim=(-41, 41),
                title="where the contact starts to slip (its slip rate passes ten times the "
                      "drive's)")
    axes[1].set_xlabel("t (s)")
    inside = intervals[(intervals["start"] >= shown["t_start"] - 1e-9)
                       & (intervals["start"] <= shown["t_end"])]
    first = inside.groupby("node")["start"].min()
    axes[2].plot(1e3 * (first.to_numpy() - shown["t_start"]), x[first.index.to_numpy()], ".",
                 color="tab:red")
    axes[2].set(xlabel=f"t - {shown['t_start']:.3f} s (ms)", ylabel="x (mm)",
                title=f"a wave's arrivals: from x = {shown['x_start']:.1f} mm, "
                      f"{shown['speed'] / 1e3:.1f} m/s towards {shown['x_end']:.0f} mm")
    fig.savefig(FIGURE, dpi=110)
    plt.close(fig)
    print(f"quasi-dynamic: figure {FIGURE.relative_to(FIGURE.parents[2])}")


def tolerances() -> None:
    """The front speed against the steps' tolerance, at 160 elements over 70 s."""
    medians = {}
    for tolerance in (TOLERANCE, TOLERANCE / 10):
        body = slab_body(Slab(elements=160))
        start = time.process_time()
        ds = simulate_quasi_dynamic(body, LAW, DRIVE, duration=70.0, sample_rate=100.0,
                                    field_times=record_times(70.0, 10.0), tolerance=tolerance)
        seconds = time.process_time() - start
        medians[tolerance] = float(front_waves(ds, min_extent=MIN_EXTENT)["speed"].median())
        print(f"quasi-dynamic: tolerance {tolerance:g}: 70 s at 160 elements in {seconds:.1f} s"
              f", {ds.attrs['steps']} steps, median front speed {medians[tolerance]:.0f} mm/s")
    change = abs(medians[TOLERANCE] - medians[TOLERANCE / 10]) / medians[TOLERANCE / 10]
    status = check("front speed, tolerance / 10", change, CONVERGENCE_TARGET, at_least=False)
    print(f"quasi-dynamic: the front speed moves {100 * change:.1f} % with a tolerance ten times"
          f" tighter ({status} the 5 % target)")


@njit
def _kernel_times(y: np.ndarray, reduction: steps.Reduction, law: steps.Law, band: int,
                  repeats: int) -> np.ndarray:
    """Seconds per call of each kernel of a step, at state y (compiled: no dispatch)."""
    per = 1 + law.b.size
    factors = stiff_steps.factors_for(y.size, band, per)
    packed = steps.jacobian(0.0, y, reduction, law, band)
    times = np.zeros(5)
    for kernel in range(5):
        with objmode(begin="f8"):
            begin = time.perf_counter()
        for _ in range(repeats):
            if kernel == 0:
                steps.rates(0.0, y, reduction, law)
            elif kernel == 1:
                steps.jacobian(0.0, y, reduction, law, band)
            elif kernel == 2:
                stiff_steps._factorise(packed, 1e-4, band, per, factors)
            elif kernel == 3:
                stiff_steps._solve(factors, per, y)
            else:
                steps.step_end(0.0, y, reduction, law, 1e-9, 1e-9)
        with objmode(end="f8"):
            end = time.perf_counter()
        times[kernel] = (end - begin) / repeats
    return times


def where_the_time_goes() -> None:
    """A 280 s test's steps at 160 elements: each kernel's calls per step and time per call.

    The kernels are timed at two states of a run: all stuck after the pressing, and in a
    wave (the first field record, every millisecond, whose fastest node passes 10 mm/s).
    """
    caught: dict[str, Any] = {}
    advance = stretch_steps.advance

    def watched(stepper: Any, reduction: Any, law: Any, band: int, *rest: Any) -> int:
        status = advance(stepper, reduction, law, band, *rest)
        speeds = rest[-1].speeds
        if "y" not in caught and speeds.size and np.abs(speeds).max() > 10.0:
            caught.update(y=stepper.D[0].copy(), reduction=reduction, law=law, band=band)
        if "stuck" not in caught:
            caught["stuck"] = (stepper.D[0].copy(), reduction)
        return status

    body = slab_body(Slab(elements=160))
    stretch_steps.advance = watched  # type: ignore[assignment]  # watched for two states
    try:
        ds = simulate_quasi_dynamic(body, LAW, DRIVE, duration=60.0, sample_rate=100.0,
                                    field_times=record_times(60.0, 1000.0))
    finally:
        stretch_steps.advance = advance
    names = ("right-hand side", "Jacobian", "factorisation", "solve", "step's end")
    per_step = (ds.attrs["evaluations"], ds.attrs["jacobians"], ds.attrs["factorisations"],
                ds.attrs["evaluations"], ds.attrs["steps"])
    stuck_y, stuck_reduction = caught["stuck"]
    slipping = _kernel_times(caught["y"], caught["reduction"], caught["law"], caught["band"],
                             200)
    stuck = _kernel_times(stuck_y, stuck_reduction, caught["law"], caught["band"], 200)
    print(f"quasi-dynamic: where the steps' time goes (60 s at 160 elements, "
          f"{ds.attrs['steps']} steps; kernels timed stuck / in a wave):")
    for name, calls, quiet, busy in zip(names, per_step, stuck, slipping, strict=True):
        share = calls / ds.attrs["steps"]
        print(f"    {name}: {share:.2f} per step, {1e6 * quiet:.0f} / {1e6 * busy:.0f} us a call"
              f" ({1e6 * share * quiet:.0f} / {1e6 * share * busy:.0f} us per step)")


PHASE_SPEEDS = (0.01, 1.0)  # mm/s: creeping, nucleating, a front (the fastest node's rate)


@njit(cache=True)
def _advance_tallied(stepper: Any, reduction: Any, law: Any, band: int, force_scale: float,
                     gap_scale: float, until: float, front_speed: float, record: Any,
                     tally: np.ndarray) -> int:
    """:func:`quasi_dynamic_stretch.advance`, tallying each step's node-steps by phase.

    ``tally[phase]``: [steps, nodes x the largest node's pace, the sum of the nodes'
    paces], a node's pace being the share of the step it could not have taken alone.
    """
    sc = stepper.scalars
    room = record.crossing_node.size - reduction.closed.size
    per = 1 + law.b.size
    nodes = stepper.D.shape[1] // per
    while True:
        if (record.cursor[stretch_steps.CROSSINGS] > room
                or record.cursor[stretch_steps.FIELDS_HELD] == record.field_states.shape[0]):
            return stretch_steps.FULL
        order = sc[stiff_steps._ORDER]
        if stiff_steps.step(stepper, reduction, law, band) != stiff_steps.OK:
            return stretch_steps.TOO_SMALL
        end = sc[stiff_steps.T]
        margin, after = steps.step_end(end, stepper.D[0], reduction, law, force_scale,
                                       gap_scale)
        if margin < -1.0:
            return stretch_steps.CHANGES
        stretch_steps.record_step(stepper, reduction, law, sc[stiff_steps.T_OLD], end, after,
                                  front_speed, record)
        fastest = np.abs(after).max() if after.size else 0.0
        phase = 0 if fastest < PHASE_SPEEDS[0] else (1 if fastest < PHASE_SPEEDS[1] else 2)
        largest, total = 0.0, 0.0
        for node in range(nodes):
            square = 0.0
            for m in range(per):
                square += stepper.error[node * per + m] ** 2
            pace = (square / per) ** (0.5 / (order + 1.0))
            largest = max(largest, pace)
            total += pace
        tally[phase, 0] += 1.0
        tally[phase, 1] += nodes * largest
        tally[phase, 2] += total
        if end >= until or end >= sc[stiff_steps.BOUND]:
            return stretch_steps.PASSED


def multirate_bound(elements: int, seconds: float) -> None:
    """The node-steps an ideal multirate integrator would take on the 280 s test."""
    tally = np.zeros((3, 3))
    advance = stretch_steps.advance

    def tallied(*arguments: Any) -> int:
        return _advance_tallied(*arguments, tally)

    stretch_steps.advance = tallied  # type: ignore[assignment]
    try:
        ds = simulate_quasi_dynamic(slab_body(Slab(elements=elements)), LAW, DRIVE,
                                    duration=280.0, sample_rate=100.0,
                                    field_times=record_times(280.0, 10.0))
    finally:
        stretch_steps.advance = advance
    nodes = elements + 1
    today = tally[:, 0].sum() * nodes
    print(f"quasi-dynamic: an ideal multirate integrator on the 280 s test at {elements} "
          f"elements ({ds.attrs['steps']} steps): each node stepped at its own error's pace"
          f" would take {100 * tally[:, 2].sum() / today:.0f} % of today's node-steps (every "
          f"node at every step), {tally[:, 2].sum() / tally[:, 1].sum():.2f} of a global "
          f"integrator's held to the same per-node error; at today's cost per node-step, "
          f"{seconds * tally[:, 2].sum() / today:.1f} s against {seconds:.1f} s, before any "
          f"cost of its coupling")
    for phase, name in enumerate(("creeping (fastest node below 0.01 mm/s)",
                                  "nucleating (0.01 to 1 mm/s)", "in a front (above 1 mm/s)")):
        count, largest, total = tally[phase]
        print(f"    {name}: {100 * count / tally[:, 0].sum():.0f} % of the steps; ideal "
              f"per-node work {100 * total / (count * nodes):.0f} % of today's there, "
              f"{largest / total:.1f} times less than the same-error global integrator's")


def whole_test_convergence(coarse: int, coarse_speeds: np.ndarray, fine: int,
                           fine_speeds: np.ndarray) -> tuple[float, float]:
    """A whole 280 s test's front speeds at a mesh against twice its elements.

    The first 70 s hold nine waves; a whole test holds 80 to 90, most of them in the
    cycle that settles after 100 s. Their medians are compared against the same 5 %,
    and their distributions by Mann-Whitney's U (a chaotic sequence of waves is judged
    by its distribution, not wave by wave). Returns the median's change and U's p.
    """
    change = abs(np.median(coarse_speeds) - np.median(fine_speeds)) / np.median(fine_speeds)
    p_value = float(mannwhitneyu(coarse_speeds, fine_speeds).pvalue)
    print(f"quasi-dynamic: over the whole 280 s test the median front speed moves "
          f"{100 * change:.1f} % from {coarse} to {fine} elements; Mann-Whitney U p = "
          f"{p_value:.2g} that the two meshes' speeds share a distribution")
    return change, p_value


def main() -> None:
    print(f"quasi-dynamic: load average {os.getloadavg()[0]:.2f} before")
    start = time.process_time()  # the compiled kernels, loaded (or compiled) once
    simulate_quasi_dynamic(slab_body(Slab(elements=40)), LAW, DRIVE, duration=50.0,
                           sample_rate=100.0, field_times=record_times(50.0, 10.0))
    print(f"quasi-dynamic: the kernels loaded and a first run in {time.process_time() - start:.1f}"
          f" s")
    one_node()
    slab = Slab(elements=160)
    shear_modulus = slab.youngs_modulus / (2 * (1 + slab.poisson_ratio))
    print(f"quasi-dynamic: shear impedance G/(2 c_s) {shear_impedance(slab):.3e} MPa s/mm; "
          f"L_b = G Dc / (b sigma) {shear_modulus * LAW.dc * 1e3 / (LAW.b * 0.095):.2f} mm "
          f"at the mean pressure of 76 N, {shear_modulus * LAW.dc * 1e3 / (LAW.b * 0.18):.2f}"
          f" mm at that of 145 N (N grows with T under the held position)")
    medians = {}
    for elements in MESHES:
        ds, seconds = run(elements, 70.0)
        waves = front_waves(ds, min_extent=MIN_EXTENT)
        ratio = (ds["T"] / ds["N"]).values
        medians[elements] = float(waves["speed"].median())
        spacing = 80.0 / elements
        times = ds["time"].values
        # each wave's drop: T/N just before it less its least in the 0.15 s after
        drops = [float(ratio[(times > start - 0.05) & (times <= start)].max()
                       - ratio[(times > start) & (times <= start + 0.15)].min())
                 for start in waves["t_start"]]
        print(f"quasi-dynamic: {elements} elements ({spacing:.2f} mm), 70 s in {seconds:.1f} "
              f"s ({ds.attrs['steps']} steps, {ds.attrs['jacobians']} Jacobians, "
              f"{ds.attrs['contact_changes']} contact changes): {len(waves)} waves, median "
              f"front speed {medians[elements]:.0f} mm/s; first wave at "
              f"{waves['t_start'].iloc[0]:.3f} s, median start x "
              f"{waves['x_start'].median():.2f} mm, recurrence "
              f"{np.median(np.diff(waves['t_start'])):.3f} s, median drop of T/N "
              f"{np.median(drops):.4f}, median extent {waves['extent'].median():.3f}, "
              f"largest T/N {ratio.max():.4f}")
        if elements == 160:
            figure(ds, elements)
        for wave in waves.itertuples():
            print(f"    wave at {wave.t_start:7.3f} s from x {wave.x_start:6.2f} to "
                  f"{wave.x_end:6.2f} mm ({wave.direction}, {wave.kind}): "
                  f"{wave.speed:6.0f} mm/s")
    for coarse, fine in itertools.pairwise(MESHES):
        change = abs(medians[coarse] - medians[fine]) / medians[fine]
        print(f"quasi-dynamic: median front speed over the first 70 s, {coarse} -> {fine} "
              f"elements: {100 * change:.1f} %")
    whole: dict[int, np.ndarray] = {}
    taken: dict[int, float] = {}
    for elements in WHOLE_TEST_MESHES:
        ds, taken[elements] = run(elements, 280.0)
        waves = front_waves(ds, min_extent=MIN_EXTENT)
        whole[elements] = waves["speed"].to_numpy()
        quartiles = np.percentile(whole[elements], [25, 50, 75])
        print(f"quasi-dynamic: 280 s test at {elements} elements: {taken[elements]:.1f} s, "
              f"{ds.attrs['steps']} steps, {len(waves)} waves, front speed quartiles "
              f"{quartiles[0]:.0f} / {quartiles[1]:.0f} / {quartiles[2]:.0f} mm/s")
    used = WHOLE_TEST_MESHES[-1]
    for coarse, fine in itertools.pairwise(WHOLE_TEST_MESHES):
        change, p_value = whole_test_convergence(coarse, whole[coarse], fine, whole[fine])
        if used == WHOLE_TEST_MESHES[-1] and change <= CONVERGENCE_TARGET and (
                p_value >= SAME_DISTRIBUTION_P):
            used = coarse
    status = check("front speed over a 280 s test, the mesh used -> twice it",
                   abs(np.median(whole[used]) - np.median(whole[2 * used]))
                   / np.median(whole[2 * used]) if used < WHOLE_TEST_MESHES[-1] else np.inf,
                   CONVERGENCE_TARGET, at_least=False)
    print(f"quasi-dynamic: the mesh used: {used} elements, the coarsest whose whole test's "
          f"front speeds agree with twice its elements' ({status} the 5 % target)")
    status = check(f"280 s test at {used} elements, s", taken[used], TIME_TARGET,
                   at_least=False)
    print(f"quasi-dynamic: 280 s test at the mesh used, {used} elements: "
          f"{taken[used]:.1f} s ({status} the {TIME_TARGET:.0f} s target)")
    multirate_bound(320, taken[320])
    tolerances()
    where_the_time_goes()
    finish()


if __name__ == "__main__":
    main()
