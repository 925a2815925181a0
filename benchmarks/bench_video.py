"""Kymograph extraction speed and memory: a 20 000-frame, 320 x 160 FFV1 video, one core.

The video repeats 250 frames of the default campaign's hl050 test (a gross slip
and its surroundings, with the virtual camera's own sensor noise); FFV1 codes
every frame on its own (intra only), so a repeated frame costs what a new one
would. The process is pinned to one core, decoder threads included; the
decoder alone is timed too, as the ceiling.
Target: >= 1000 frames/s, memory flat in the video's length (the kymograph
itself, 2 x 268 float32 a frame, is the only thing that grows).
Run: make bench  (or python benchmarks/bench_video.py)
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import tempfile
import time
import tracemalloc
from itertools import islice
from pathlib import Path

import numpy as np

from slipwave.bench.camera import write_video
from slipwave.video import Geometry, kymograph, open_frames
from targets import check, finish

ROOT = Path(__file__).parents[1]
FRAMES = 20_000
TARGET = 1000.0
GEOMETRY = Geometry(interface_row=140, left=26.0, right=294.0, length=80.0)


def clip() -> list[np.ndarray]:
    source = open_frames(ROOT / "raw_data/bench/hl050.mkv")
    return [f.image for f in islice(source, 1750, 2000)]


def frames(base: list[np.ndarray], count: int):
    for k in range(count):
        yield base[k % len(base)]


def run(path: Path, count: int) -> tuple[float, float]:
    """Seconds and traced peak memory (MB) of a kymograph over the first ``count`` frames."""
    tracemalloc.start()
    start = time.perf_counter()
    kymograph(islice(open_frames(path), count), GEOMETRY)
    took = time.perf_counter() - start
    peak = tracemalloc.get_traced_memory()[1] / 1e6
    tracemalloc.stop()
    return took, peak


def main() -> None:
    if hasattr(os, "sched_setaffinity"):  # one core, decoder threads included
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "long.mkv"
        start = time.perf_counter()
        write_video(frames(clip(), FRAMES), (k / 25 for k in range(FRAMES)), path, codec="ffv1")
        written = time.perf_counter() - start
        start = time.perf_counter()
        decoded = sum(1 for _ in open_frames(path))
        decoding = decoded / (time.perf_counter() - start)
        start = time.perf_counter()
        kymo = kymograph(open_frames(path), GEOMETRY)
        took = time.perf_counter() - start
        rate = kymo.sizes["time"] / took
        short, long = run(path, 5000), run(path, FRAMES)
        size = path.stat().st_size / 1e6
    status = check("kymograph frames/s", rate, TARGET, at_least=True)
    print(f"kymograph: {FRAMES} frames 320 x 160 FFV1 ({size:.0f} MB, written in {written:.0f} s)"
          f" in {took:.1f} s = {rate:.0f} frames/s ({status} the {TARGET:.0f} frames/s target; "
          f"decoding alone {decoding:.0f} frames/s)")
    print(f"kymograph: traced peak memory {short[1]:.1f} MB for 5000 frames, {long[1]:.1f} MB "
          f"for {FRAMES} (the kymograph itself: {FRAMES * 268 * 4 * 3 / 1e6:.1f} MB)")
    finish()


if __name__ == "__main__":
    main()
