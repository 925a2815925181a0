"""One frame of a video, an image sequence or a film of a simulation.

:class:`Frame` is what :func:`slipwave.video.kymograph` reads: the sources of
:mod:`slipwave.video.frames` make them from files, and a simulation filmed
(:func:`slipwave.simulate_waves.film_kymograph`) from its images, without a video library.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Frame:
    """One frame: its position in the source, camera time (s) and grey image."""

    index: int
    time: float
    image: np.ndarray
