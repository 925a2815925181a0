"""Frames of a photoelastic recording, streamed one at a time with their times.

:func:`open_frames` reads a video file (any container and codec FFmpeg reads,
through PyAV, with each frame's own timestamp), a folder of numbered images
(PNG or TIFF, in natural order, times from a ``frames.csv`` beside them or from
a frame rate) or a multi-page TIFF. Grey levels are kept as recorded (8 or 16
bits); colour video gives its luma.
"""

from __future__ import annotations

import csv
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from slipwave.errors import SlipwaveError
from slipwave.video.frame import Frame

if TYPE_CHECKING:
    import av

IMAGE_SUFFIXES = (".png", ".tif", ".tiff")


@dataclass
class FrameSource:
    """An iterable of :class:`Frame` over a video, an image sequence or a TIFF stack.

    Iterating streams the frames (one in memory at a time). ``warnings``
    collects what was skipped or cut; with ``keep_partial`` a damaged video
    ends the iteration at its last good frame (with a warning) instead of
    raising :class:`~slipwave.errors.SlipwaveError`.
    """

    path: Path
    fps: float | None = None
    keep_partial: bool = False
    warnings: list[str] = field(default_factory=list)

    def __iter__(self) -> Iterator[Frame]:
        if self.path.is_dir():
            return self._sequence()
        if not self.path.exists():
            raise SlipwaveError(f"{self.path}: no such video, image folder or TIFF stack")
        if self.path.suffix.lower() in (".tif", ".tiff"):
            return self._tiff_stack()
        return self._video()

    def _warn(self, message: str) -> None:
        # a source is iterated more than once (geometry, then kymograph): warn once
        if message not in self.warnings:
            self.warnings.append(message)

    def _check(self, image: np.ndarray, shape: tuple[int, ...] | None, where: str) -> None:
        if shape is not None and image.shape != shape:
            raise SlipwaveError(f"{where}: frame of {image.shape[1]} x {image.shape[0]} px, "
                                f"the frames before it are {shape[1]} x {shape[0]} px")

    def _video(self) -> Iterator[Frame]:
        import av  # PyAV loads FFmpeg: only where a video is read

        last_good = "none (the first frame is damaged)"
        lost: list[str] = []
        shape = None
        try:
            container = av.open(str(self.path))
        except av.FFmpegError as err:
            raise SlipwaveError(f"{self.path}: not a readable video ({err})") from err
        try:
            if not container.streams.video:
                raise SlipwaveError(f"{self.path}: no video stream")
            stream = container.streams.video[0]
            stream.thread_type = "AUTO"
            declared = container.duration / av.time_base if container.duration else None
            time, period, nominal = float("nan"), 0.0, 0.0
            for index, frame in enumerate(self._decode(container, stream)):
                image = _grey(frame)
                where = f"{self.path}, frame {index}"
                self._check(image, shape, where)
                shape = image.shape
                previous = time
                time = float(frame.time) if frame.time is not None else (
                    index / self.fps if self.fps else float("nan"))
                period = time - previous if index else 0.0
                nominal = nominal or period
                if nominal and period > 1.5 * nominal:  # the decoder skipped damaged frames
                    lost.append(f"frames lost between {previous:.3f} s and {time:.3f} s")
                yield Frame(index, time, image)
                last_good = f"frame {index} at {time:.3f} s"
            # a file cut short ends cleanly for the demuxer: its header still says how long
            # the video was
            if declared is not None and shape is not None and time + 2 * period < declared:
                raise av.InvalidDataError(1, f"the file ends at {time:.3f} s of the "
                                             f"{declared:.3f} s its header declares")
        except av.FFmpegError as err:
            before = f" ({'; '.join(lost)} before it)" if lost else ""
            message = (f"{self.path}: damaged video after its last good frame, {last_good}"
                       f"{before} ({err})")
            if not self.keep_partial:
                raise SlipwaveError(message) from err
            self._warn(message + "; the frames before it were kept")
        finally:
            container.close()

    @staticmethod
    def _decode(container: av.container.InputContainer,
                stream: av.video.stream.VideoStream) -> Iterator[av.VideoFrame]:
        import av

        for packet in container.demux(stream):
            if packet.size == 0 and packet.pts is None:  # the flush packet at the end
                yield from packet.decode()
                continue
            if packet.is_corrupt:
                raise av.InvalidDataError(1, "corrupt packet")
            yield from packet.decode()

    def _sequence(self) -> Iterator[Frame]:
        files = sorted((p for p in self.path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES),
                       key=_natural_key)
        if not files:
            raise SlipwaveError(f"{self.path}: no PNG or TIFF images")
        times = _sequence_times(self.path)
        numbers = [_last_number(p.name) for p in files]
        shape = None
        previous: int | None = None
        for index, (image_path, number) in enumerate(zip(files, numbers, strict=True)):
            if previous is not None and number is not None and number > previous + 1:
                missing = number - previous - 1
                self._warn(f"{self.path}: {missing} image(s) missing between numbers "
                           f"{previous} and {number}; skipped")
            previous = number
            image = _read_image(image_path)
            self._check(image, shape, str(image_path))
            shape = image.shape
            if image_path.name in times:
                time = times[image_path.name]
            elif self.fps:
                time = (number if number is not None else index) / self.fps
            else:
                raise SlipwaveError(f"{image_path}: no time (no frames.csv entry, no fps)")
            yield Frame(index, time, image)

    def _tiff_stack(self) -> Iterator[Frame]:
        from PIL import Image, UnidentifiedImageError

        shape = None
        try:
            with Image.open(self.path) as stack:
                for index in range(getattr(stack, "n_frames", 1)):
                    stack.seek(index)
                    image = np.asarray(stack)
                    self._check(image, shape, f"{self.path}, page {index}")
                    shape = image.shape
                    if not self.fps:
                        raise SlipwaveError(f"{self.path}: a TIFF stack needs fps for its times")
                    yield Frame(index, index / self.fps, image)
        except (OSError, UnidentifiedImageError) as err:
            raise SlipwaveError(f"{self.path}: not a readable TIFF ({err})") from err


def open_frames(
    path: str | PathLike[str], *, fps: float | None = None, keep_partial: bool = False
) -> FrameSource:
    """Frames of a video, a numbered image sequence or a multi-page TIFF.

    Parameters
    ----------
    path
        A video file (Matroska, MP4, AVI...: what FFmpeg reads), a folder of
        numbered PNG/TIFF images, or a multi-page TIFF.
    fps
        Frame rate for sources without timestamps (TIFF stacks; image folders
        without ``frames.csv``). Videos use their own per-frame timestamps.
    keep_partial
        On a truncated or corrupt video, stop at the last good frame with a
        warning (``source.warnings``) instead of raising.

    Returns
    -------
    FrameSource
        Iterate it for :class:`Frame` objects; it can be iterated again.

    Examples
    --------
    >>> import tempfile
    >>> from slipwave.bench.camera import write_video
    >>> images = [np.full((16, 32), 10 * k, dtype=np.uint8) for k in range(3)]
    >>> path = write_video(images, [0.0, 0.04, 0.08], tempfile.mkdtemp() + "/v.mkv")
    >>> [(f.index, round(f.time, 2), int(f.image[0, 0])) for f in open_frames(path)]
    [(0, 0.0, 0), (1, 0.04, 10), (2, 0.08, 20)]
    """
    return FrameSource(Path(path), fps=fps, keep_partial=keep_partial)


def _grey(frame: av.VideoFrame) -> np.ndarray:
    """The frame's grey levels as recorded: gray/gray16 as they are, else the luma plane."""
    name = frame.format.name
    if name in ("gray", "gray8"):
        return frame.to_ndarray()
    if name.startswith("gray16") or name.startswith("gray1"):
        return frame.to_ndarray(format="gray16le")
    if name in ("yuv420p", "yuvj420p"):  # the luma plane comes first, as recorded
        return frame.to_ndarray(format="yuv420p")[: frame.height]
    return frame.to_ndarray(format="gray")


def _natural_key(path: Path) -> list[object]:
    return [int(part) if part.isdigit() else part.lower()
            for part in re.split(r"(\d+)", path.name)]


def _last_number(name: str) -> int | None:
    numbers = re.findall(r"\d+", name)
    return int(numbers[-1]) if numbers else None


def _sequence_times(folder: Path) -> dict[str, float]:
    listing = folder / "frames.csv"
    if not listing.exists():
        return {}
    times = {}
    with listing.open(newline="", encoding="utf-8") as handle:
        for line, row in enumerate(csv.reader(handle), start=1):
            if line == 1 or not row:
                continue
            try:
                times[row[0]] = float(row[1])
            except (IndexError, ValueError) as err:
                raise SlipwaveError(f"{listing}, line {line}: expected file,camera_time_s, "
                                    f"got {','.join(row)!r}") from err
    return times


def _read_image(path: Path) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            array = np.asarray(image)
    except (OSError, UnidentifiedImageError) as err:
        raise SlipwaveError(f"{path}: not a readable image ({err})") from err
    if array.ndim == 3:  # colour: its luma (ITU-R BT.601), as video would give
        array = np.round(array[..., :3] @ np.array([0.299, 0.587, 0.114])).astype(np.uint8)
    if array.dtype not in (np.uint8, np.uint16):
        array = array.astype(np.uint16)
    return array
