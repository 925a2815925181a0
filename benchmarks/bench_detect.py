"""Event detection speed: ``detect_events`` on a 10^7-sample, five-channel recording.

The recording is the virtual bench's hl050 test (H/L = 0.5, 280 s) sampled at
35.7 kHz (10^7 samples of T, N, DG, DD, DT with the default sensors' noise,
spikes and drift), as a fast acquisition card would record it.
Target: >= 10 million samples per second on one core.
Run: make bench  (or python benchmarks/bench_detect.py)
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})  # one core, as the target says

import time
from pathlib import Path

import numpy as np
import scipy.io

from slipwave.bench.generate import BenchTest, simulate_test
from slipwave.bench.sensors import DEFAULT_SENSORS, apply_sensors
from slipwave.events import detect_events, load_drops
from slipwave.solver.signals import clean_signals
from targets import check, finish

SAMPLES = 10_000_000
COLAS = Path(__file__).parents[1].parent / "shared/data/colas2019/k1002Nm_v42.mat"
TARGET = 10e6  # samples per second


def main() -> None:
    spec = BenchTest("hl050", video="none")
    simulation = simulate_test(spec, seed=0).simulation
    clean = clean_signals(simulation, speed=spec.speed, loading_time=spec.loading_time,
                          duration=spec.duration, sample_rate=SAMPLES / spec.duration,
                          wave_speed=spec.wave_speed)
    recording = apply_sensors(clean, DEFAULT_SENSORS, seed=0)
    timings = []
    for _ in range(3):
        start = time.perf_counter()
        events = detect_events(recording)
        timings.append(time.perf_counter() - start)
    best, median = min(timings), float(np.median(timings))
    rate = recording.sizes["time"] / median
    status = check("detect_events samples/s", rate, TARGET, at_least=True)
    load = recording["T"].values
    alone = []
    for _ in range(3):
        start = time.perf_counter()
        drops = load_drops(recording["time"].values, load)
        alone.append(time.perf_counter() - start)
    drops_rate = load.size / float(np.median(alone))
    verdict = check("load_drops samples/s", drops_rate, TARGET, at_least=True)
    print(f"load_drops: {load.size:,} samples of T, {len(drops)} drops: median "
          f"{np.median(alone):.2f} s = {drops_rate / 1e6:.1f} M samples/s ({verdict} the "
          f"{TARGET / 1e6:.0f} M samples/s target)")
    counts = events["kind"].value_counts().to_dict()
    print(f"detect_events: {recording.sizes['time']:,} samples x 5 channels, {len(events)} "
          f"events {counts}: median {median:.2f} s (best {best:.2f} s) = "
          f"{rate / 1e6:.1f} M samples/s ({status} the {TARGET / 1e6:.0f} M samples/s target)")

    if COLAS.exists():  # an event-dense real record: the cost per event shows
        mat = scipy.io.loadmat(COLAS)
        time_s, force = mat["t"].ravel(), mat["Fnorm"].ravel()
        start = time.perf_counter()
        drops = load_drops(time_s, force)
        took = time.perf_counter() - start
        print(f"load_drops on {COLAS.name}: {force.size:,} samples, {len(drops)} drops in "
              f"{took:.2f} s ({force.size / took / 1e6:.1f} M samples/s, "
              f"{took / max(len(drops), 1) * 1e3:.2f} ms per drop)")
    finish()


if __name__ == "__main__":
    main()
