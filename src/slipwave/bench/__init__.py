"""The virtual test bench: what the acquisition card and the camera would record.

- :mod:`slipwave.bench.generate`: one test (:class:`BenchTest`,
  :func:`simulate_test`, :func:`write_test`) or a campaign
  (:func:`write_campaign`, the ``slipwave bench`` command), with the truth.
- :mod:`slipwave.bench.sensors`: a machine-driven simulation sampled like the
  card, and the sensor model.
- :mod:`slipwave.bench.camera`: stresses of the slab at the camera's pixels,
  isochromatic frames, video files.
"""

from slipwave.bench.camera import Camera, Photoelastic, write_video
from slipwave.bench.generate import (
    BenchResult,
    BenchTest,
    load_tests,
    simulate_test,
    write_campaign,
    write_test,
)
from slipwave.bench.sensors import DEFAULT_SENSORS, Sensor, apply_sensors, clean_signals

__all__ = [
    "DEFAULT_SENSORS", "BenchResult", "BenchTest", "Camera", "Photoelastic", "Sensor",
    "apply_sensors", "clean_signals", "load_tests", "simulate_test", "write_campaign",
    "write_test", "write_video",
]
