"""The virtual bench's quasi-dynamic tests: the card, the truth and the camera of one run."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from slipwave.bench import BenchResult, BenchTest, load_tests, simulate_test, write_test
from slipwave.errors import ConfigError, SlipwaveError
from slipwave.photoelastic import Camera
from slipwave.video import find_geometry, kymograph, open_frames, track_waves

SLOW_FRONTS = {"a": 0.01, "b": 0.04, "dc_um": 80.0, "mu0": 0.9, "v0_um_s": 1.0}
"""A law whose fronts run at hundreds of mm/s on the bench's slab (Dc long, b - a large)."""

FILMED_FROM = 64.0  # s on the card's clock: the camera films the first wave (about 67 s)


@pytest.fixture(scope="module")
def slow(tmp_path_factory: pytest.TempPathFactory) -> tuple[BenchResult, dict[str, Path]]:
    """A 40-element test under the slow law, filmed from 64 s to its end at 70 s."""
    spec = BenchTest("slow", elements=40, duration=70.0, rate_state=SLOW_FRONTS,
                     video="ffv1", camera=Camera(clock_offset=FILMED_FROM))
    result = simulate_test(spec, seed=5)
    return result, write_test(result, tmp_path_factory.mktemp("bench"))


def test_the_card_records_the_pressing_then_the_run(slow) -> None:
    result, _ = slow
    recording, run = result.recording, result.simulation
    time = recording["time"].values
    N = recording["N"].values
    # the pressing: the normal load rises in proportion to time over the loading time
    assert np.median(N[(time > 4.9) & (time < 5.1)]) == pytest.approx(-42.5, abs=0.5)
    assert np.median(N[time > 12.0]) == pytest.approx(-85.0, abs=0.5)
    # then the run's loads on the test's clock, with the card's noise only
    driven = time >= 10.0
    T_run = np.interp(time[driven], run["time"].values, run["T"].values)
    assert np.abs(recording["T"].values[driven] - T_run).max() < 1.0
    assert float(recording["DT"][-1]) == pytest.approx(0.048 * 60.0, abs=0.01)


def test_each_wave_of_the_truth_is_a_drop_the_card_sees(slow) -> None:
    result, _ = slow
    events, recording = result.events, result.recording
    assert len(events) >= 1
    for _, wave in events.iterrows():
        assert wave["t_end"] > wave["t_start"] > 10.0
        # its speed is the run's: hundreds of mm/s for this law, not a setting
        assert 100.0 < wave["speed"] < 2000.0
        T = recording["T"]
        before = float(T.sel(time=slice(wave["t_start"] - 0.3, wave["t_start"])).median())
        after = float(T.sel(time=slice(wave["t_end"], wave["t_end"] + 0.3)).median())
        # (the slab creeps on after the front has passed: a few percent more)
        assert before - after == pytest.approx(wave["drop"], rel=0.05)
        assert wave["drop"] > 0.5 and wave["visible"]


def test_the_camera_films_the_run_and_the_video_tracks_its_wave(slow) -> None:
    result, paths = slow
    first = result.events.iloc[0]
    # the wave runs for several frames at 25 per second, and changes the fringes
    assert first["camera_frames"] >= 3 and first["camera_visible"]
    video = paths["video"]
    geometry = find_geometry(open_frames(video), result.spec.length)
    waves = track_waves(kymograph(open_frames(video), geometry))
    waves[["t_start", "t_end"]] += FILMED_FROM  # the camera's clock onto the card's
    found = waves[(waves["t_start"] - first["t_start"]).abs() < 0.2]
    assert len(found) == 1
    wave = found.iloc[0]
    # it starts at the same end and runs the same way as the run's front
    assert wave["direction"] == first["direction"]
    assert abs(wave["x_start"] - first["x_first"]) < 10.0


def test_the_same_seed_gives_the_same_test() -> None:
    spec = BenchTest("again", elements=20, duration=30.0, rate_state=SLOW_FRONTS, video="none")
    one, two = simulate_test(spec, seed=2), simulate_test(spec, seed=2)
    other = simulate_test(spec, seed=3)
    np.testing.assert_array_equal(one.recording["T"].values, two.recording["T"].values)
    assert not np.array_equal(one.recording["T"].values, other.recording["T"].values)


def test_a_bench_yaml_asks_for_a_quasi_dynamic_test() -> None:
    config = {"defaults": {"elements": 40, "video": "none"},
              "tests": [{"test_id": "qd", "rate_state": SLOW_FRONTS}, {"test_id": "qs"}]}
    quasi_dynamic, quasi_static = load_tests(config)
    assert quasi_dynamic.rate_state == SLOW_FRONTS and quasi_static.rate_state is None
    with pytest.raises(ConfigError, match="dc_um"):
        load_tests({"tests": [{"test_id": "qd", "rate_state": {"a": 0.01, "b": 0.04,
                                                                "mu0": 0.9, "v0_um_s": 1.0}}]})
    with pytest.raises(SlipwaveError, match="ends before its loading time"):
        simulate_test(BenchTest("short", duration=5.0, rate_state=SLOW_FRONTS, video="none"))


def test_the_truth_is_written_with_its_speeds(slow) -> None:
    result, paths = slow
    written = pd.read_csv(paths["events"])
    assert list(written["speed"].round(3)) == list(result.events["speed"].round(3))
    assert set(written["kind"]) <= {"gross_slip", "partial_slip"}
