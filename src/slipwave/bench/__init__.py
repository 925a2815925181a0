"""The virtual test bench: what the acquisition card and the camera would record.

Built so far: :mod:`slipwave.bench.signals` (a machine-driven simulation sampled
like the card, and the sensor model). The campaign generator, the camera and the
``slipwave bench`` command come next (issue 4).
"""

from slipwave.bench.signals import DEFAULT_SENSORS, Sensor, apply_sensors, clean_signals

__all__ = ["DEFAULT_SENSORS", "Sensor", "apply_sensors", "clean_signals"]
