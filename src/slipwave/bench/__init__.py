"""The virtual test bench: what the acquisition card and the camera would record.

- :mod:`slipwave.bench.generate`: one test (:class:`BenchTest`,
  :func:`simulate_test`, :func:`write_test`) or a campaign
  (:func:`write_campaign`, the ``slipwave bench`` command), with the truth.
- :mod:`slipwave.bench.quasi_dynamic`: a test made with the quasi-dynamic contact
  under a rate-and-state law (a :class:`BenchTest` with ``rate_state``), its waves'
  speeds the physics'.
- :mod:`slipwave.bench.sensors`: what real sensors add to the noise-free signals
  of :mod:`slipwave.solver.signals`.
- :mod:`slipwave.bench.camera`: the frames of :mod:`slipwave.photoelastic` written
  as video files or image sequences.
- :mod:`slipwave.bench.sawtooth`: a synthetic sawtooth recording with known events.

The bench builds on the analysis's modules (:mod:`slipwave.setup`,
:mod:`slipwave.solver`); nothing that analyses a test imports it.
"""

from slipwave.bench.camera import write_video
from slipwave.bench.generate import (
    BenchResult,
    BenchTest,
    load_tests,
    setup_bench_test,
    simulate_test,
    write_campaign,
    write_test,
)
from slipwave.bench.sensors import DEFAULT_SENSORS, Sensor, apply_sensors

__all__ = [
    "DEFAULT_SENSORS", "BenchResult", "BenchTest", "Sensor", "apply_sensors", "load_tests",
    "setup_bench_test", "simulate_test", "write_campaign", "write_test", "write_video",
]
