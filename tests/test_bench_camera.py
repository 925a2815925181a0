"""The photoelastic camera: stresses of the slab, fringe images, video files."""

from __future__ import annotations

import av
import numpy as np
import pytest
import xarray as xr

from slipwave.bench.camera import write_image_sequence, write_video
from slipwave.errors import SlipwaveError
from slipwave.photoelastic import Camera, Photoelastic
from slipwave.solver import Coulomb, LoadPath, Slab, simulate

SLAB = Slab(height=40.0, elements=80)


@pytest.fixture(scope="module")
def simulation() -> xr.Dataset:
    return simulate(SLAB, Coulomb(fs=1.0), LoadPath(normal_load=85.0, normal_control="force"))


@pytest.fixture(scope="module")
def camera() -> Photoelastic:
    return Photoelastic(SLAB, Camera(noise=0.0, blur=0.0))


def random_frames(seed: int, bits: int, shape: tuple[int, int], count: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    dtype = np.uint8 if bits == 8 else np.uint16
    return [rng.integers(0, np.iinfo(dtype).max, shape).astype(dtype) for _ in range(count)]


def contact(simulation: xr.Dataset, k: int) -> np.ndarray:
    return np.concatenate([simulation["ux"].values[k], simulation["uy"].values[k]])


@pytest.mark.parametrize("height", [12.0, 20.0, 30.0])
def test_stress_resultants_on_a_horizontal_cut(simulation, camera, height):
    k = int(np.flatnonzero(simulation["T"].values > 40.0)[0])
    stress = np.zeros((3, *camera.inside.shape))
    stress[:, camera.inside] = camera.stress(contact(simulation, k))
    row = round(camera.interface_row - height * camera.scale)
    pixel = 1.0 / camera.scale  # mm
    normal = -stress[1, row].sum() * pixel * SLAB.width
    shear = stress[2, row].sum() * pixel * SLAB.width
    assert normal == pytest.approx(float(simulation["N"][k]), rel=0.03)
    assert abs(shear) == pytest.approx(float(simulation["T"][k]), rel=0.03)


def test_fringes_mirror_symmetric_after_pressing(simulation, camera):
    k = int(np.flatnonzero(simulation["phase"].values == "normal")[-1])
    image = camera.render(camera.stress(contact(simulation, k)), np.random.default_rng(0))
    columns = np.flatnonzero(camera.inside.any(axis=0))
    slab = image[:, columns[0] : columns[-1] + 1].astype(int)
    assert np.abs(slab - slab[:, ::-1]).mean() < 2.0
    orders = camera.fringe_order(camera.stress(contact(simulation, k)))
    assert 2.0 < np.median(orders) < 20.0  # a readable number of fringes


def test_shear_breaks_the_symmetry(simulation, camera):
    k = int(np.flatnonzero(simulation["T"].values > 40.0)[0])
    image = camera.render(camera.stress(contact(simulation, k)), np.random.default_rng(0))
    columns = np.flatnonzero(camera.inside.any(axis=0))
    slab = image[:, columns[0] : columns[-1] + 1].astype(int)
    assert np.abs(slab - slab[:, ::-1]).mean() > 20.0


def test_a_band_film_is_the_whole_frame_in_the_band_and_bare_elsewhere(simulation):
    # the film of a band (Photoelastic(below=), the band's top plus 1 mm, more than the
    # blur's reach): the band's pixels are the whole frame's; the rows beyond the
    # blur's reach of the slab imaged are the bare background
    blurred = Camera(noise=0.0)
    whole, band = Photoelastic(SLAB, blurred), Photoelastic(SLAB, blurred, below=4.0)
    u = contact(simulation, simulation.sizes["step"] - 1)
    rng = np.random.default_rng(0)
    full, part = whole.render(whole.stress(u), rng), band.render(band.stress(u), rng)
    top = band.interface_row - int(3.0 * band.scale)  # the band's top, 3 mm
    assert band.rows.start < top and band.rows.stop > band.interface_row
    assert np.array_equal(part[top : band.interface_row + 1], full[top : band.interface_row + 1])
    assert np.all(part[: band.rows.start] == blurred.background)
    assert np.all(part[band.rows.stop :] == blurred.background)
    # the camera's noise is drawn in the rendered rows alone
    noisy = Photoelastic(SLAB, Camera(), below=4.0).render(band.stress(u), rng)
    assert np.all(noisy[: band.rows.start] == blurred.background)
    assert np.abs(noisy.astype(float) - part).max() > 0


@pytest.mark.parametrize(("bits", "below"), [(8, None), (8, 4.0), (16, 4.0)])
def test_frames_rendered_at_once_are_those_rendered_one_by_one(simulation, bits, below):
    # the film's frames, a chunk at a time: the same blur, noise (drawn frame after frame
    # from one stream), sync LED and quantisation as one frame at a time
    photo = Photoelastic(SLAB, Camera(bits=bits), below=below)
    steps = np.linspace(0, simulation.sizes["step"] - 1, 5).astype(int)
    stresses = photo.stresses(np.stack([contact(simulation, k) for k in steps]))
    leds = np.array([False, True, True, False, True])
    one, chunk = np.random.default_rng(3), np.random.default_rng(3)
    expected = [photo.render(stress, one, led=bool(led)) for stress, led in zip(
        stresses, leds, strict=True)]
    frames = photo.render_frames(stresses, chunk, leds=leds)
    assert frames.dtype == expected[0].dtype and frames.shape == (5, *expected[0].shape)
    for frame, image in zip(frames, expected, strict=True):
        np.testing.assert_array_equal(frame, image)
    bright = 0.8 * np.iinfo(frames.dtype).max
    assert frames[1][4:8, 4:8].mean() > bright > frames[0][4:8, 4:8].mean()  # the lit LED
    assert not np.array_equal(frames[0], frames[-1])


@pytest.mark.parametrize("bits", [8, 16])
def test_ffv1_is_lossless_and_keeps_timestamps(tmp_path, bits):
    frames = random_frames(1, bits, (160, 320), 4)
    times = [0.0, 0.04, 0.081, 0.12]  # a late frame: variable frame rate
    path = write_video(frames, times, tmp_path / "v.mkv", codec="ffv1")
    with av.open(str(path)) as container:
        decoded = [(f.to_ndarray(), float(f.pts * f.time_base)) for f in container.decode(video=0)]
    assert len(decoded) == 4
    for frame, (back, time), expected in zip(frames, decoded, times, strict=True):
        np.testing.assert_array_equal(back, frame)
        assert time == pytest.approx(expected, abs=1e-4)


def test_video_bytes_are_deterministic(tmp_path):
    frames = [np.full((160, 320), 10 * k, dtype=np.uint8) for k in range(5)]
    times = [k / 25 for k in range(5)]
    for codec in ["ffv1", "vp9"]:
        a = write_video(frames, times, tmp_path / f"a.{codec}", codec=codec).read_bytes()
        b = write_video(frames, times, tmp_path / f"b.{codec}", codec=codec).read_bytes()
        assert a == b


def test_vp9_refuses_16_bit(tmp_path):
    with pytest.raises(SlipwaveError, match="16-bit frames need"):
        write_video([np.zeros((16, 16), np.uint16)], [0.0], tmp_path / "v.mkv", codec="vp9")
    assert not (tmp_path / "v.mkv").exists()


def test_vp9_keeps_the_grey_levels(tmp_path):
    rng = np.random.default_rng(2)
    y, x = np.mgrid[0:160, 0:320]
    frames = [np.clip(128 + 100 * np.sin(x / 9.0 + k) * np.cos(y / 7.0)
                      + rng.normal(0, 1.5, x.shape), 0, 255).astype(np.uint8) for k in range(6)]
    path = write_video(frames, [k / 25 for k in range(6)], tmp_path / "v.mkv", codec="vp9")
    with av.open(str(path)) as container:
        luma = [f.to_ndarray(format="yuv420p")[:160].astype(float)
                for f in container.decode(video=0)]
    error = np.mean([np.mean((a - b) ** 2) for a, b in zip(luma, frames, strict=True)])
    assert 10 * np.log10(255**2 / error) > 35.0


def test_camera_clock():
    camera = Camera(clock_offset=2.5, clock_rate_error=1e-3)
    np.testing.assert_allclose(camera.acquisition_time(np.array([0.0, 100.0])), [2.5, 102.6])


@pytest.mark.parametrize("bits", [8, 16])
def test_image_sequence_is_lossless_and_numbered(tmp_path, bits):
    frames = random_frames(4, bits, (40, 60), 3)
    folder = write_image_sequence(frames, [0.0, 0.04, 0.08], tmp_path / "seq")
    names = sorted(p.name for p in folder.glob("*.png"))
    assert names == ["frame_000000.png", "frame_000001.png", "frame_000002.png"]
    for name, frame in zip(names, frames, strict=True):
        with av.open(str(folder / name)) as container:
            image = next(container.decode(video=0))
            back = image.to_ndarray(format="gray16le" if bits == 16 else "gray")
        np.testing.assert_array_equal(back, frame)
    table = (folder / "frames.csv").read_text().splitlines()
    assert table[0] == "file,camera_time_s" and table[2] == "frame_000001.png,0.040000"
