"""Photoelastic video: frames, the contact's geometry, kymographs, waves, clocks."""

from slipwave.video.frames import Frame, FrameSource, open_frames
from slipwave.video.kymograph import Geometry, find_geometry, kymograph

__all__ = ["Frame", "FrameSource", "Geometry", "find_geometry", "kymograph", "open_frames"]
