"""Photoelastic video: frames, the contact's geometry, kymographs, waves, clocks.

- :mod:`slipwave.video.frames`: frame sources (videos, image sequences, TIFF stacks).
- :mod:`slipwave.video.kymograph`: the contact's geometry and the kymograph stage.
- :mod:`slipwave.video.waves`: the waves stage, fronts tracked in a kymograph.
- :mod:`slipwave.video.clock`: the camera's clock against the card's.
- :mod:`slipwave.video.fuse`: load events paired with waves.
"""

from slipwave.video.clock import ClockFit, align_clocks, on_card_clock, read_clock
from slipwave.video.frame import Frame
from slipwave.video.frames import FrameSource, open_frames
from slipwave.video.fuse import fuse
from slipwave.video.kymograph import Geometry, find_geometry, kymograph
from slipwave.video.waves import WAVE_COLUMNS, track_waves

__all__ = [
    "WAVE_COLUMNS", "ClockFit", "Frame", "FrameSource", "Geometry", "align_clocks",
    "find_geometry", "fuse", "kymograph", "on_card_clock", "open_frames", "read_clock",
    "track_waves",
]
