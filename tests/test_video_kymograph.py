"""The kymograph's band and options, and holes in a video's frame times."""

from __future__ import annotations

import re

import numpy as np
import pytest

from slipwave.bench.camera import write_video
from slipwave.cli import main
from slipwave.errors import SlipwaveError
from slipwave.video import Frame, Geometry, kymograph, open_frames


def test_kymograph_band_and_options():
    images = [np.full((40, 60), 10 * k, dtype=np.uint8) for k in range(3)]
    frames = [Frame(k, 0.04 * k, image) for k, image in enumerate(images)]
    # 0.5 px/mm: a band up to 60 mm reaches the top row exactly (np.pad failed there)
    geometry = Geometry(interface_row=30, left=10.0, right=50.0, length=80.0)
    assert kymograph(frames, geometry, band_mm=(0.5, 60.0)).sizes["time"] == 3
    with pytest.raises(SlipwaveError, match=r"reaches above the frame, which shows 60\.0 mm"):
        kymograph(frames, geometry, band_mm=(0.5, 70.0))
    with pytest.raises(SlipwaveError, match="must start at 0 mm or above and end above"):
        kymograph(frames, geometry, band_mm=(2.0, 0.5))
    with pytest.raises(SlipwaveError, match="contact length must be positive, not 0 mm"):
        Geometry(interface_row=30, left=10.0, right=50.0, length=0.0)


@pytest.mark.parametrize("option", [["--length", "0"], ["--fps", "-5"]])
def test_kymograph_command_refuses_silly_numbers(tmp_path, capsys, option):
    with pytest.raises(SystemExit) as stopped:
        main(["kymograph", str(tmp_path), "-o", str(tmp_path / "k.nc"), *option])
    assert stopped.value.code == 2
    assert re.search(rf"argument {option[0]}: (must be positive, got {option[1]}|"
                     rf"{option[1]}(.0)? is less than or equal to the minimum of 0)",
                     capsys.readouterr().err)


def test_hole_in_the_frame_times_is_reported(tmp_path):
    rng = np.random.default_rng(0)
    images = [rng.integers(0, 50, (40, 60), dtype=np.uint8) for _ in range(30)]
    times = np.r_[np.arange(10) * 0.04, 2.0 + np.arange(20) * 0.04]  # 1.64 s lost
    path = write_video(images, times, tmp_path / "gap.mkv", codec="ffv1")
    source = open_frames(path)
    kymo = kymograph(source, Geometry(interface_row=30, left=10.0, right=50.0, length=80.0))
    assert kymo.attrs["frame_gaps"] == "0.360-2.000 s (40 frames)"
    assert source.warnings == ["no frame between 0.360 s and 2.000 s of camera time (about 40 "
                               "frames missing: skipped or lost); the kymograph has a hole there"]
