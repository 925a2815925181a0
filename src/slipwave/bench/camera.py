"""The virtual bench's camera files: frames stored as a video or as images.

:func:`write_video` stores frames with PyAV (lossless FFV1, or compact VP9), and
:func:`write_image_sequence` as numbered PNG images; the frames come from
:class:`slipwave.photoelastic.Photoelastic`.
"""

from __future__ import annotations

from collections.abc import Iterable
from fractions import Fraction
from os import PathLike
from pathlib import Path
from typing import Literal

import numpy as np

from slipwave.errors import SlipwaveError
from slipwave.io import atomic_output


def write_video(
    frames: Iterable[np.ndarray],
    times: Iterable[float],
    path: str | PathLike[str],
    *,
    codec: Literal["ffv1", "vp9"] = "ffv1",
    fps: float = 25.0,
) -> Path:
    """Encode grey frames with their camera timestamps (s), whole or not at all.

    Both codecs are stored in Matroska. ``ffv1`` is lossless (8 or 16 bits);
    ``vp9`` is compact (8 bits, constant quality 32: about 0.4 kB a frame at
    40 dB PSNR for these images). The grey levels are the luma plane, full
    range. The output is bit-exact for equal input (single encoder thread, no
    dates in the container); H.264 through libx264 was not, from one process to
    the next, on this project's machines, hence VP9.

    Parameters
    ----------
    frames
        Grey frames, all of one size and type.
    times
        Their camera timestamps, s.
    path
        The ``.mkv`` file.
    codec
        ``ffv1`` (lossless) or ``vp9``.
    fps
        Nominal frame rate.

    Returns
    -------
    Path
        The video written.

    """
    import av  # PyAV loads FFmpeg: only where a video is written

    target = Path(path)
    time_base = Fraction(1, 10_000)
    with atomic_output(target) as temporary:
        container = av.open(str(temporary), mode="w", format="matroska",
                            options={"fflags": "+bitexact"})
        try:
            stream = None
            for frame, time in zip(frames, times, strict=True):
                if stream is None:
                    deep = frame.dtype == np.uint16
                    if deep and codec != "ffv1":
                        raise SlipwaveError("16-bit frames need the lossless ffv1 codec")
                    stream = container.add_stream(
                        "libvpx-vp9" if codec == "vp9" else "ffv1",
                        rate=Fraction(fps).limit_denominator(1000))
                    stream.width, stream.height = frame.shape[1], frame.shape[0]
                    stream.pix_fmt = ("gray16le" if deep else "gray") if codec == "ffv1" \
                        else "yuv420p"
                    stream.time_base = time_base
                    stream.codec_context.time_base = time_base
                    stream.codec_context.thread_count = 1
                    stream.codec_context.flags |= av.codec.context.Flags.bitexact
                    if codec == "vp9":
                        stream.codec_context.color_range = 2  # full range (JPEG)
                        stream.codec_context.options = {
                            "crf": "32", "b": "0", "threads": "1", "row-mt": "0",
                            "deadline": "realtime", "cpu-used": "8",
                        }
                    source_format = "gray16le" if deep else "gray"
                if codec == "vp9":
                    # Grey as YUV 4:2:0 with neutral chroma, built here.
                    height, width = frame.shape
                    chroma = np.full((height // 2, width), 128, dtype=np.uint8)
                    video_frame = av.VideoFrame.from_ndarray(np.vstack([frame, chroma]),
                                                             format="yuv420p")
                else:
                    video_frame = av.VideoFrame.from_ndarray(frame, format=source_format)
                video_frame.pts = round(time / time_base)
                video_frame.time_base = time_base
                for packet in stream.encode(video_frame):
                    container.mux(packet)
            if stream is None:
                raise SlipwaveError(f"{target}: no frames to write")
            for packet in stream.encode():
                container.mux(packet)
        finally:
            container.close()
    return target


def write_image_sequence(
    frames: Iterable[np.ndarray],
    times: Iterable[float],
    folder: str | PathLike[str],
    *,
    prefix: str = "frame",
) -> Path:
    """Write frames as numbered PNG images (8 or 16 bit) and their times in ``frames.csv``.

    An image sequence has no timestamps of its own: ``frames.csv`` lists each
    file with its camera time (s). Returns the folder.

    Parameters
    ----------
    frames
        Grey frames.
    times
        Their camera timestamps, s.
    folder
        Where the images and ``frames.csv`` go.
    prefix
        Image names: ``<prefix>_00001.png``...

    Returns
    -------
    Path
        The folder.

    """
    import av  # PyAV loads FFmpeg: only where a video is written

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    lines = ["file,camera_time_s"]
    for index, (frame, time) in enumerate(zip(frames, times, strict=True)):
        deep = frame.dtype == np.uint16
        encoder = av.CodecContext.create("png", "w")
        encoder.width, encoder.height = frame.shape[1], frame.shape[0]
        encoder.pix_fmt = "gray16be" if deep else "gray"
        image = av.VideoFrame.from_ndarray(frame, format="gray16le" if deep else "gray")
        data = b"".join(bytes(packet) for packet in [*encoder.encode(image), *encoder.encode()])
        name = f"{prefix}_{index:06d}.png"
        with atomic_output(folder / name) as temporary:
            temporary.write_bytes(data)
        lines.append(f"{name},{time:.6f}")
    if len(lines) == 1:
        raise SlipwaveError(f"{folder}: no frames to write")
    with atomic_output(folder / "frames.csv") as temporary:
        temporary.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return folder
