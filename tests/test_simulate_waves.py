"""The simulate-waves stage: a filmed test run quasi-dynamically, its waves in the video's
columns on the test's clock, and what it refuses."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from fuzzing import valid_fit
from slipwave.bench import BenchTest, simulate_test, write_test
from slipwave.cli import main
from slipwave.compare import compare_waves
from slipwave.io import read_dataset, read_table
from slipwave.io.tables import WAVE_COLUMNS
from slipwave.plot import WAVE_COLOURS, plot_simulated_fronts
from slipwave.setup import TestSetup
from slipwave.simulate_waves import WavesRun, rate_state_law, simulate_waves
from slipwave.video import find_geometry, kymograph, open_frames, track_waves

LAW = {"a": 0.01, "b": 0.015, "dc_um": 2.0, "mu0": 0.9, "v0_um_s": 1.0}
SLOW_FRONTS = {"a": 0.01, "b": 0.04, "dc_um": 80.0, "mu0": 0.9, "v0_um_s": 1.0}


@pytest.fixture(scope="module")
def ran() -> tuple[TestSetup, WavesRun]:
    setup = TestSetup.from_dict(valid_fit()["setup"])
    return setup, simulate_waves(setup, rate_state_law(LAW), elements=40, field_rate=10.0,
                                 sample_rate=20.0, frame_rate=25.0)


def test_a_test_runs_on_its_own_clock(ran: tuple[TestSetup, WavesRun]) -> None:
    setup, result = ran
    run, fronts = result.run, result.fronts
    loading = setup["loading_time_s"]
    assert float(run["time"][0]) == loading
    assert float(run["time"][-1]) == pytest.approx(setup["duration_s"])
    assert float(run["field_time"][0]) == loading
    np.testing.assert_allclose(np.diff(run["field_time"].values), 0.1)
    assert "ux" not in run  # the displacements are the film's, not kept
    # the slip-rate fronts of the drive (its first slips come some 20 s in at 0.1 mm/s)
    assert len(fronts) >= 3
    assert (fronts["t_start"] > loading + 10).all()
    assert np.all(run["crossing_time"].values >= loading)
    assert np.isfinite(fronts["speed"]).all() and (fronts["speed"] > 0).all()
    # the film: a frame every 1/25 s of the drive, on the same clock
    film = result.film["time"].values
    assert film[0] == loading and np.diff(film) == pytest.approx(0.04)


def test_fronts_faster_than_the_frames_are_unresolved_on_the_film(
        ran: tuple[TestSetup, WavesRun]) -> None:
    _, result = ran
    # this law's fronts cross the contact in milliseconds: a frame sees a slip, hardly
    # ever its front running, as the bench's camera would (where the slab's relaxation
    # after a slip spans three frames, the tracker reads a front into it)
    assert (result.fronts["t_end"] - result.fronts["t_start"]).max() < 0.04
    assert len(result.waves) >= 10
    assert (result.waves["kind"] == "unresolved").mean() >= 0.8
    # the fronts over half the contact show on the film, within two frames
    broad = result.fronts[result.fronts["extent"] >= 0.5]["t_start"].to_numpy()
    gaps = np.abs(result.waves["t_start"].to_numpy()[:, None] - broad[None, :]).min(axis=0)
    assert broad.size >= 10 and (gaps <= 0.08).mean() >= 0.85, gaps.round(2)


@pytest.fixture(scope="module")
def slow_test(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, TestSetup]:
    """A virtual-bench test made quasi-dynamically at 80 elements under a law of slow
    fronts, filmed at 25 frames/s; its setup as the workflow would read it."""
    spec = BenchTest("small", elements=80, duration=60.0, loading_time=5.0, speed=0.1,
                     rate_state=SLOW_FRONTS, video="ffv1")
    paths = write_test(simulate_test(spec, seed=4), tmp_path_factory.mktemp("slow"))
    return paths["video"], TestSetup.from_dict(valid_fit()["setup"])


def test_the_stage_films_a_run_as_the_bench_s_camera_does(
        slow_test: tuple[Path, TestSetup]) -> None:
    video, setup = slow_test
    geometry = find_geometry(open_frames(video), setup["length_mm"])
    measured = track_waves(kymograph(open_frames(video), geometry))
    # the run that made the test, run again by the stage (the same law and mesh) and
    # filmed: the same waves as the video's where the tracker follows both. The camera's
    # noise differs, and decides which of the fainter fronts it sees, follows, and at what
    # speed: over six draws of the noise (videos and films alike) this test's first wave
    # was followed four times at 287-426 mm/s, the last seen once; the others within 8 %
    result = simulate_waves(setup, rate_state_law(SLOW_FRONTS), elements=80,
                            field_rate=10.0, sample_rate=20.0, frame_rate=25.0)
    filmed = result.waves
    resolved = filmed[filmed["kind"] != "unresolved"]
    assert len(measured) >= 3 and len(resolved) >= 2
    ratios, unseen = [], 0
    for _, wave in resolved.iterrows():
        same = measured[(measured["t_start"] - wave["t_start"]).abs() <= 0.08]
        unseen += same.empty
        if len(same) == 1 and same["kind"].iloc[0] != "unresolved":
            assert same["direction"].iloc[0] == wave["direction"]
            ratios.append(float(wave["speed"] / same["speed"].iloc[0]))
    assert unseen <= 1 and len(ratios) >= 2
    apart = np.abs(np.log(ratios))
    assert (apart > 0.1).sum() <= 1 and apart.max() <= 0.5  # the faint one, within half
    verdicts = compare_waves(measured, filmed)["verdict"]
    assert (verdicts == "agrees").all()
    # the slip-rate fronts of the same waves run at more than twice the fringes' speed
    assert result.fronts["speed"].median() > 2.0 * filmed["speed"].median()


def _video_kymograph(path: Path, test_id: str = "small") -> Path:
    """A kymograph as the kymograph stage writes it: 25 frames/s, the default band."""
    time = np.arange(0.0, 60.0, 0.04)
    xr.Dataset({"motion": (("time", "x"), np.zeros((time.size, 3)))},
               coords={"time": time, "x": [-1.0, 0.0, 1.0]},
               attrs={"product": "kymograph", "band_mm": [0.5, 2.0],
                      "test_id": test_id}).to_netcdf(path)
    return path


def _command(tmp_path: Path, *options: str) -> list[str]:
    fit_path = tmp_path / "fit.json"
    if not fit_path.exists():
        fit_path.write_text(json.dumps(valid_fit()))
    return ["simulate-waves", "--fit", str(fit_path), "--kymograph",
            str(_video_kymograph(tmp_path.parent / f"{tmp_path.name}-kymograph.nc")),
            *options, "-o", str(tmp_path / "qd.nc"), "--film", str(tmp_path / "film.nc"),
            "--waves", str(tmp_path / "waves.csv"), "--fronts", str(tmp_path / "fronts.csv")]


def test_the_command_writes_the_run_its_film_and_their_waves_under_the_test_s_identity(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(_command(tmp_path, "--elements", "40", "--sample-rate", "20")) == 0
    run = read_dataset(tmp_path / "qd.nc", "quasi-dynamic run")
    assert run.attrs["test_id"] == "small" and run.attrs["recording_sha256"] == "0" * 64
    film = read_dataset(tmp_path / "film.nc", "kymograph")
    assert film.attrs["test_id"] == "small" and film.attrs["frame_rate"] == pytest.approx(25.0)
    for name in ("waves.csv", "fronts.csv"):
        table = read_table(tmp_path / name)
        assert tuple(table.columns) == WAVE_COLUMNS and len(table) >= 3
        assert table.attrs["test_id"] == "small"
    assert "filmed at 25 frames/s" in capsys.readouterr().out


def test_a_kymograph_of_another_test_is_refused(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    command = _command(tmp_path, "--elements", "40")
    _video_kymograph(Path(command[command.index("--kymograph") + 1]), test_id="other")
    assert main(command) == 1
    assert "other" in capsys.readouterr().err
    assert sorted(path.name for path in tmp_path.iterdir()) == ["fit.json"]


@pytest.mark.parametrize(("option", "value", "said"), [
    ("--a", "0", "simulate_waves.a"),
    ("--dc-um", "-2", "simulate_waves.dc_um"),
    ("--elements", "5", "simulate_waves.elements"),
])
def test_a_law_or_mesh_out_of_the_config_s_bounds_is_refused_before_anything_runs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], option: str, value: str,
        said: str) -> None:
    with pytest.raises(SystemExit) as stop:
        main(_command(tmp_path, option, value))
    assert stop.value.code == 2
    assert said in capsys.readouterr().err
    assert sorted(path.name for path in tmp_path.iterdir()) == ["fit.json"]


def test_a_fit_without_its_setup_is_named(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    fit = valid_fit()
    del fit["setup"]
    (tmp_path / "fit.json").write_text(json.dumps(fit))
    status = main(_command(tmp_path, "--elements", "40"))
    err = capsys.readouterr().err
    assert status == 1 and "fit.json" in err and "setup" in err
    assert sorted(path.name for path in tmp_path.iterdir()) == ["fit.json"]


def test_the_fronts_figure_draws_each_wave_in_its_direction_s_colour(
        ran: tuple[TestSetup, WavesRun]) -> None:
    run, waves = ran[1].run, ran[1].fronts
    whole, first = plot_simulated_fronts(run, waves).axes
    paths = [line for line in whole.get_lines() if line.get_linestyle() == "-"]
    assert len(paths) == len(waves)
    assert [line.get_color() for line in paths] == [WAVE_COLOURS[d] for d in waves["direction"]]
    assert "m/s" in first.get_title(loc="left")
    # the first wave's arrivals span its extent, within a few of its milliseconds
    arrivals = first.get_lines()[0].get_xdata()
    assert arrivals.min() >= 0.0 and arrivals.max() <= 1e3 * (
        waves["t_end"].iloc[0] - waves["t_start"].iloc[0]) + 1e-6
