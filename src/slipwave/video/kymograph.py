"""Where the contact is in the image, and the kymograph of a thin band above it.

The kymograph stacks, frame after frame, the intensity along a thin band of
the slab just above the interface: a sliding wave is a front crossing it. The
band's mean intensity is taken relative to the unloaded reference frame (the
first, by default) and in units of the full grey scale, so 8- and 16-bit
recordings compare; the fringe activity G^2 (mean squared intensity gradient,
as in granular photoelasticity) is taken along the same band.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from slipwave.defaults import BAND_MM
from slipwave.errors import SlipwaveError
from slipwave.video.frame import Frame

LED_PATCH = (slice(2, 10), slice(2, 10))
"""Pixels of the sync LED (top left corner), as the virtual bench draws it."""


class _Rows:
    """Rows of float32 appended one at a time, kept in blocks.

    No object per row, and :meth:`stack` frees each block as it copies it (peak:
    the result and one block).
    """

    BLOCK = 1024

    def __init__(self) -> None:
        self.blocks: list[np.ndarray] = []
        self.count = 0

    def append(self, row: np.ndarray) -> None:
        at = self.count % self.BLOCK
        if at == 0:
            self.blocks.append(np.empty((self.BLOCK, row.size), dtype=np.float32))
        self.blocks[-1][at] = row
        self.count += 1

    def stack(self, scale: float) -> np.ndarray:
        width = self.blocks[0].shape[1] if self.blocks else 0
        out = np.empty((self.count, width), dtype=np.float32)
        start = 0
        while self.blocks:
            block = self.blocks.pop(0)
            rows = min(self.BLOCK, self.count - start)
            out[start : start + rows] = block[:rows] / scale
            start += rows
        return out


@dataclass(frozen=True)
class Geometry:
    """The contact in the image (pixel edges) and its length (mm).

    ``interface_row`` is the first pixel row below the slab (the flat);
    ``left`` and ``right`` are the columns of the contact's ends (pixel
    edges, so the contact covers ``right - left`` pixels).
    """

    interface_row: int
    left: float
    right: float
    length: float

    def __post_init__(self) -> None:
        if not self.length > 0:
            raise SlipwaveError(f"the contact length must be positive, not {self.length:g} mm")
        if not self.right > self.left:
            raise SlipwaveError(f"the contact's right end (column {self.right:g}) must be right "
                                f"of its left end (column {self.left:g})")

    @property
    def scale(self) -> float:
        """Pixels per mm.

        Returns
        -------
        float
            Pixels per mm.

        """
        return (self.right - self.left) / self.length

    def columns(self) -> np.ndarray:
        """Indices of the pixel columns inside the contact.

        Returns
        -------
        numpy.ndarray
            Column indices.

        """
        return np.arange(int(np.ceil(self.left - 0.5)), int(np.floor(self.right - 0.5)) + 1)

    def x(self, columns: np.ndarray) -> np.ndarray:
        """Position (mm, origin at the contact's centre) of pixel columns' centres.

        Parameters
        ----------
        columns
            Pixel column indices.

        Returns
        -------
        numpy.ndarray
            Positions, mm.

        """
        return (columns + 0.5 - self.left) / self.scale - self.length / 2

    def band_rows(self, band_mm: tuple[float, float]) -> np.ndarray:
        """Pixel rows between ``band_mm[0]`` and ``band_mm[1]`` mm above the interface.

        Parameters
        ----------
        band_mm
            (low, high), mm above the interface.

        Returns
        -------
        numpy.ndarray
            Row indices, top to bottom.

        Raises
        ------
        SlipwaveError
            If the band is empty, reaches above the frame or holds no row.

        """
        if not 0 <= band_mm[0] < band_mm[1]:
            raise SlipwaveError(f"the band {band_mm[0]:g}-{band_mm[1]:g} mm above the interface "
                                "must start at 0 mm or above and end above its start")
        low = self.interface_row - band_mm[1] * self.scale
        high = self.interface_row - band_mm[0] * self.scale
        if low < 0:
            raise SlipwaveError(
                f"the band {band_mm[0]:g}-{band_mm[1]:g} mm above the interface reaches above "
                f"the frame, which shows {self.interface_row / self.scale:.1f} mm above it")
        rows = np.arange(int(np.floor(low)), int(np.ceil(high)))
        rows = rows[(rows >= 0) & (rows < self.interface_row)]
        if rows.size == 0:
            raise SlipwaveError(f"the band {band_mm} mm above the interface has no pixel row "
                                f"at {self.scale:.2f} px/mm")
        return rows


def find_geometry(frames: Iterable[Frame], length: float, *, count: int = 300) -> Geometry:
    """Find the interface and the contact's ends in the first ``count`` frames.

    The interface is the strongest horizontal edge of the lower half of the
    image (the slab's bottom on the flat); the contact spans the columns where
    the slab lit up in any of these frames (fringes appear under the normal
    load). The scale follows from ``length``, the contact length in
    mm.

    Parameters
    ----------
    frames
        The frames (only the first ``count`` are read).
    length
        The contact's length, mm (sets the scale).
    count
        Frames looked at.

    Returns
    -------
    Geometry
        Interface row, contact ends (pixel columns) and length.

    Examples
    --------
    >>> image = np.full((40, 60), 10, dtype=np.uint8)
    >>> image[30:, :] = 60                      # the flat
    >>> image[5:30, 10:50] = 200                # the loaded slab
    >>> find_geometry([Frame(0, 0.0, image)], 80.0)
    Geometry(interface_row=30, left=10.0, right=50.0, length=80.0)
    """
    brightest: np.ndarray | None = None
    for k, frame in enumerate(frames):
        image = frame.image.astype(float)
        brightest = image if brightest is None else np.maximum(brightest, image)
        if k + 1 >= count:
            break
    if brightest is None:
        raise SlipwaveError("no frame to find the contact in")
    profile = brightest.mean(axis=1)
    half = profile.size // 2
    edge = np.abs(np.diff(profile[half - 1 :]))
    interface = half + int(np.argmax(edge))
    # columns of the slab: bright somewhere above the interface (the 90th percentile
    # over rows ignores small marks such as a sync LED)
    band = np.percentile(brightest[:interface], 90, axis=0)
    dark = float(band.min())
    lit = np.flatnonzero(band > dark + 0.5 * (float(band.max()) - dark))
    if lit.size < 2:
        raise SlipwaveError("no lit contact above the interface in the first frames: give "
                            "the geometry in the config")
    return Geometry(interface_row=interface, left=float(lit[0]), right=float(lit[-1] + 1),
                    length=float(length))


def frame_gaps(times: np.ndarray, *, tolerance: float = 1.5) -> list[tuple[float, float, int]]:
    """Where frames are missing: steps longer than ``tolerance`` times the usual one.

    Parameters
    ----------
    times
        Frame times, s, increasing.
    tolerance
        How many typical frame periods make a gap.

    Returns
    -------
    list of tuple
        (time of the frame before, time of the frame after, frames missing) per gap.

    Examples
    --------
    >>> frame_gaps(np.r_[np.arange(10) * 0.04, 1.0 + np.arange(5) * 0.04])
    [(0.36, 1.0, 15)]
    """
    steps = np.diff(times)
    if steps.size < 2:
        return []
    period = float(np.median(steps))
    if not period > 0:
        return []
    return [(round(float(times[k]), 6), round(float(times[k + 1]), 6),
             round(float(steps[k] / period)) - 1)
            for k in np.flatnonzero(steps > tolerance * period)]


def kymograph(
    frames: Iterable[Frame],
    geometry: Geometry,
    band_mm: tuple[float, float] = BAND_MM,
    *,
    reference: np.ndarray | None = None,
) -> xr.Dataset:
    """Intensity and fringe activity along a band above the interface, frame by frame.

    Parameters
    ----------
    frames
        From :func:`~slipwave.video.open_frames` (streamed: memory does not
        grow with their number).
    geometry
        Where the contact is (:func:`find_geometry` or the config).
    band_mm
        The band, in mm above the interface.
    reference
        The unloaded reference frame; ``None``: the first frame.

    Returns
    -------
    xarray.Dataset
        ``intensity`` (time, x): band mean minus the reference's, in units of
        the full grey scale; ``activity`` (time, x): G^2, the band's mean
        squared intensity gradient (full scale per pixel, squared); ``motion``
        (time, x): the mean absolute change of the band's pixels since the
        previous frame (full scale), what waves are tracked on; ``sync``
        (time): mean grey of the sync LED's corner (full scale). ``time`` is
        camera time (s), ``x`` the position along the contact (mm, origin at
        its centre).

    Examples
    --------
    >>> images = [np.zeros((40, 60), dtype=np.uint8) for _ in range(3)]
    >>> images[2][26:30, 20:30] = 255          # a change just above the interface
    >>> geometry = Geometry(interface_row=30, left=10.0, right=50.0, length=80.0)
    >>> kymo = kymograph([Frame(k, 0.04 * k, im) for k, im in enumerate(images)], geometry)
    >>> kymo["intensity"].sizes["time"], kymo["intensity"].sizes["x"]
    (3, 40)
    >>> float(kymo["intensity"].isel(time=2, x=15))
    1.0
    """
    try:
        return _kymograph(frames, geometry, band_mm, reference)
    except SlipwaveError as err:
        source = getattr(frames, "path", None)  # name the video where the message does not
        if source is None or str(source) in str(err):
            raise
        raise SlipwaveError(f"{source}: {err}") from err


def _kymograph(frames: Iterable[Frame], geometry: Geometry, band_mm: tuple[float, float],
               reference: np.ndarray | None) -> xr.Dataset:
    rows = geometry.band_rows(band_mm)
    columns = geometry.columns()
    top, bottom = int(rows[0]), int(rows[-1]) + 1
    first, last = int(columns[0]), int(columns[-1]) + 1
    times: list[float] = []
    intensity, activity, motion = _Rows(), _Rows(), _Rows()
    sync: list[float] = []
    previous: np.ndarray | None = None
    full_scale = None
    shape = None
    base: np.ndarray | None = None
    for frame in frames:
        image = frame.image
        if shape is None:
            shape = image.shape
            full_scale = 65535.0 if image.dtype == np.uint16 else 255.0
            if bottom > shape[0] or last > shape[1]:
                raise SlipwaveError(f"the contact ({first}-{last} px, rows {top}-{bottom}) is "
                                    f"outside the {shape[1]} x {shape[0]} px frames")
            ref = image if reference is None else reference
            base = ref[top:bottom, first:last].astype(float).mean(axis=0)
        elif image.shape != shape:
            raise SlipwaveError(f"frame {frame.index}: {image.shape[1]} x {image.shape[0]} px, "
                                f"the first frame is {shape[1]} x {shape[0]} px")
        window = image[max(top - 1, 0) : bottom + 1, max(first - 1, 0) : last + 1]
        window = window.astype(np.float32)
        if window.shape != (bottom - top + 2, last - first + 2):  # at the image's border
            window = np.pad(window, ((int(top == 0), int(bottom == shape[0])),
                                     (int(first == 0), int(last == shape[1]))), mode="edge")
        band = window[1:-1, 1:-1]
        # central differences, as numpy.gradient inside the window
        dx = 0.5 * (window[1:-1, 2:] - window[1:-1, :-2])
        dy = 0.5 * (window[2:, 1:-1] - window[:-2, 1:-1])
        rows = band.shape[0]
        # change since the previous frame, pixel by pixel, then averaged over the band's
        # rows: a fringe that moves shows even where the band's mean stays the same
        motion.append(np.add.reduce(np.abs(band - previous)) / rows if previous is not None
                      else np.zeros(band.shape[1]))
        previous = band
        intensity.append(np.add.reduce(band) / rows - base)
        activity.append(np.add.reduce(dx * dx + dy * dy) / rows)
        sync.append(float(image[LED_PATCH].mean()))
        times.append(frame.time)
    if not times or full_scale is None:
        raise SlipwaveError("no frames: the kymograph is empty")
    gaps = frame_gaps(np.array(times))
    notes = getattr(frames, "warnings", None)
    for start, end, missing in gaps:
        message = (f"no frame between {start:.3f} s and {end:.3f} s of camera time (about "
                   f"{missing} frames missing: skipped or lost); the kymograph has a hole there")
        if isinstance(notes, list) and message not in notes:
            notes.append(message)
    x = geometry.x(columns)
    return xr.Dataset(
        {
            "intensity": (("time", "x"), intensity.stack(full_scale), {
                "units": "1", "long_name": "band intensity minus the reference frame's, "
                                           "in units of full scale"}),
            "activity": (("time", "x"), activity.stack(full_scale**2), {
                "units": "px-2", "long_name": "fringe activity G^2: mean squared intensity "
                                              "gradient in the band (full scale)"}),
            "motion": (("time", "x"), motion.stack(full_scale), {
                "units": "1", "long_name": "mean absolute change of the band's pixels since "
                                           "the previous frame (full scale)"}),
            "sync": ("time", np.array(sync) / full_scale, {
                "units": "1", "long_name": "mean grey of the sync LED corner (full scale)"}),
        },
        coords={
            "time": ("time", np.array(times), {"units": "s", "long_name": "camera time"}),
            "x": ("x", x, {"units": "mm", "long_name": "position along the contact, "
                                                       "origin at its centre"}),
        },
        attrs={"product": "kymograph", "band_mm": list(band_mm),
               "frame_gaps": "; ".join(f"{a:.3f}-{b:.3f} s ({n} frames)" for a, b, n in gaps),
               **{f"geometry_{k}": v
                                            for k, v in asdict(geometry).items()}},
    )
