"""The virtual test bench: what the acquisition card and the camera would record.

Built so far: :mod:`slipwave.bench.signals` (a machine-driven simulation sampled
like the card, and the sensor model) and :mod:`slipwave.bench.camera` (stresses
of the slab at the camera's pixels, isochromatic frames, video files). The
campaign generator (interface history, truth files, ``slipwave bench``) comes
next (issue 4).
"""

from slipwave.bench.camera import Camera, Photoelastic, write_video
from slipwave.bench.signals import DEFAULT_SENSORS, Sensor, apply_sensors, clean_signals

__all__ = [
    "DEFAULT_SENSORS", "Camera", "Photoelastic", "Sensor", "apply_sensors", "clean_signals",
    "write_video",
]
