"""Frame sources and kymographs: formats agree, bad input is named, geometry is found."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from slipwave.bench.camera import write_image_sequence, write_video
from slipwave.errors import SlipwaveError
from slipwave.video import Frame, Geometry, find_geometry, kymograph, open_frames

ROOT = Path(__file__).parents[1]
GEOMETRY = Geometry(interface_row=140, left=26.0, right=294.0, length=80.0)


@pytest.fixture(scope="module")
def clip() -> list[np.ndarray]:
    """120 frames of the default campaign's hl050 video around its first gross slip."""
    frames = []
    for frame in open_frames(ROOT / "raw_data/bench/hl050.mkv"):
        if 70.0 <= frame.time < 74.8:
            frames.append(frame.image)
        if frame.time >= 74.8:
            break
    return frames


def times(count: int) -> list[float]:
    return [0.04 * k for k in range(count)]


def test_video_and_image_sequence_give_the_same_kymograph(clip, tmp_path):
    lossless = write_video(clip, times(len(clip)), tmp_path / "clip.mkv", codec="ffv1")
    folder = write_image_sequence(clip, times(len(clip)), tmp_path / "frames")
    compact = write_video(clip, times(len(clip)), tmp_path / "clip_vp9.mkv", codec="vp9")
    a = kymograph(open_frames(lossless), GEOMETRY)
    b = kymograph(open_frames(folder), GEOMETRY)
    c = kymograph(open_frames(compact), GEOMETRY)
    assert a["time"].values == pytest.approx(b["time"].values, abs=1e-6)
    assert np.array_equal(a["intensity"].values, b["intensity"].values)  # both lossless
    # VP9 (constant quality 32, ~40 dB PSNR, ~2.5 grey levels RMS a pixel): the band's
    # mean over its rows stays within that
    difference = a["intensity"].values - c["intensity"].values
    assert np.sqrt(np.mean(difference**2)) < 2.5 / 255
    assert np.corrcoef(a["intensity"].values.ravel(), c["intensity"].values.ravel())[0, 1] > 0.99


def test_sixteen_bit_frames_and_tiff_stacks(tmp_path):
    rng = np.random.default_rng(0)
    deep = [rng.integers(0, 65535, (40, 60)).astype(np.uint16) for _ in range(4)]
    video = write_video(deep, times(4), tmp_path / "deep.mkv", codec="ffv1")
    read = list(open_frames(video))
    assert read[2].image.dtype == np.uint16 and np.array_equal(read[2].image, deep[2])
    stack = tmp_path / "stack.tif"
    pages = [Image.fromarray(image) for image in deep]
    pages[0].save(stack, save_all=True, append_images=pages[1:])
    frames = list(open_frames(stack, fps=25.0))
    assert [f.time for f in frames] == pytest.approx(times(4))
    assert np.array_equal(frames[3].image, deep[3])
    with pytest.raises(SlipwaveError, match="needs fps"):
        list(open_frames(stack))


def test_a_missing_image_is_reported_and_skipped(clip, tmp_path):
    folder = write_image_sequence(clip[:6], times(6), tmp_path / "frames")
    (folder / "frame_000003.png").unlink()
    source = open_frames(folder)
    frames = list(source)
    assert [f.time for f in frames] == pytest.approx([0.0, 0.04, 0.08, 0.16, 0.2])
    assert source.warnings == [f"{folder}: 1 image(s) missing between numbers 2 and 4; skipped"]


def test_a_frame_of_another_size_is_an_error(clip, tmp_path):
    folder = write_image_sequence(clip[:3], times(3), tmp_path / "frames")
    Image.fromarray(clip[0][:100, :200]).save(folder / "frame_000003.png")
    with pytest.raises(SlipwaveError, match=r"frame_000003.png: frame of 200 x 100 px, the "
                                            r"frames before it are 320 x 160 px"):
        list(open_frames(folder, fps=25.0))


def test_a_truncated_video_names_its_last_good_frame(clip, tmp_path):
    whole = write_video(clip, times(len(clip)), tmp_path / "clip.mkv", codec="ffv1")
    cut = tmp_path / "cut.mkv"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size * 2 // 3])
    seen = []
    with pytest.raises(SlipwaveError, match=r"cut.mkv: damaged video after its last good "
                                            r"frame, frame \d+ at"):
        for frame in open_frames(cut):
            seen.append(frame.index)
    assert 40 < len(seen) < len(clip)
    source = open_frames(cut, keep_partial=True)
    kept = list(source)
    assert len(kept) == len(seen)
    assert "the frames before it were kept" in source.warnings[0]


def test_not_a_video(tmp_path):
    bogus = tmp_path / "bogus.mkv"
    bogus.write_bytes(b"not a video at all" * 10)
    with pytest.raises(SlipwaveError, match=r"bogus\.mkv: not a readable video"):
        list(open_frames(bogus))
    with pytest.raises(SlipwaveError, match="no such video"):
        list(open_frames(tmp_path / "absent.mkv"))


@pytest.mark.parametrize(("test_id", "left", "right"),
                         [("hl050", 26.0, 294.0), ("hl025", 6.0, 314.0), ("hl075", 70.67, 249.33)])
def test_geometry_from_the_first_frames(test_id, left, right):
    """The camera draws the slab 80 mm wide, centred, over a flat from row 140."""
    geometry = find_geometry(open_frames(ROOT / f"raw_data/bench/{test_id}.mkv"), 80.0)
    assert geometry.interface_row == 140
    assert geometry.left == pytest.approx(left, abs=1.0)
    assert geometry.right == pytest.approx(right, abs=1.0)


def test_kymograph_band_and_reference():
    images = [np.full((40, 60), 20, dtype=np.uint8) for _ in range(4)]
    images[3][24:30, 10:30] = 200  # lit in the band above the interface, left half
    frames = [Frame(k, 0.04 * k, image) for k, image in enumerate(images)]
    geometry = Geometry(interface_row=30, left=10.0, right=50.0, length=40.0)
    kymo = kymograph(frames, geometry, band_mm=(0.0, 5.0))
    assert kymo["x"].values[[0, -1]] == pytest.approx([-19.5, 19.5])
    assert np.allclose(kymo["intensity"].values[:3], 0.0)
    assert kymo["intensity"].values[3, :20] == pytest.approx(180 / 255)
    assert kymo["motion"].values[3, :20] == pytest.approx(180 / 255)
    assert np.allclose(kymo["intensity"].values[3, 21:], 0.0)
    with pytest.raises(SlipwaveError, match=r"reaches above the frame, which shows 30\.0 mm"):
        kymograph(frames, geometry, band_mm=(50.0, 60.0))


def test_command_line_kymograph_on_a_damaged_video(clip, tmp_path, capsys):
    from slipwave.cli import main
    from slipwave.io import read_dataset

    whole = write_video(clip, times(len(clip)), tmp_path / "clip.mkv", codec="ffv1")
    cut = tmp_path / "cut.mkv"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size * 2 // 3])
    output = tmp_path / "kymo.nc"
    assert main(["kymograph", str(cut), "-o", str(output), "--geometry", "140", "26",
                 "294"]) == 1
    assert "damaged video after its last good frame" in capsys.readouterr().err
    assert not output.exists()  # nothing half-written
    assert main(["kymograph", str(cut), "-o", str(output), "--geometry", "140", "26", "294",
                 "--keep-partial"]) == 0
    assert "the frames before it were kept" in capsys.readouterr().err
    kymo = read_dataset(output)
    assert 40 < kymo.sizes["time"] < len(clip)
    assert "damaged video" in kymo.attrs["warnings"]


def test_a_video_damaged_in_the_middle_names_the_frames_lost(tmp_path):
    data = bytearray((ROOT / "raw_data/bench/hl050.mkv").read_bytes())
    middle = len(data) // 2
    data[middle : middle + 20_000] = np.random.default_rng(0).integers(
        0, 256, 20_000, dtype=np.uint8).tobytes()
    damaged = tmp_path / "damaged.mkv"
    damaged.write_bytes(bytes(data))
    with pytest.raises(SlipwaveError, match=r"frame 3705 at 153.360 s \(frames lost between "
                                            r"148.160 s and 153.360 s before it\)"):
        for _ in open_frames(damaged):
            pass


def test_a_missing_image_is_reported_once(tmp_path):
    images = [np.full((40, 60), k, dtype=np.uint8) for k in range(5)]
    folder = write_image_sequence(images, np.arange(5) * 0.04, tmp_path / "frames")
    (folder / "frame_000002.png").unlink()
    source = open_frames(folder)
    kymograph(source, Geometry(interface_row=30, left=10.0, right=50.0, length=80.0))
    list(source)  # a second pass (geometry, then kymograph) does not repeat it
    assert sum("1 image(s) missing between numbers 1 and 3" in w for w in source.warnings) == 1
    assert len(set(source.warnings)) == len(source.warnings)
