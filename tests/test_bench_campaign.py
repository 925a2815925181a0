"""The virtual bench's campaigns: figure-5 signature, video, determinism, files."""

from __future__ import annotations

import json
from pathlib import Path

import av
import numpy as np
import pandas as pd
import pytest

from slipwave.bench.generate import BenchTest, load_tests, simulate_test, write_test
from slipwave.cli import main
from slipwave.errors import ConfigError
from slipwave.io import read_acquisition
from slipwave.photoelastic import Camera, Photoelastic

CAMPAIGN = Path(__file__).parents[1] / "raw_data" / "bench"


@pytest.fixture(scope="module")
def hl050():
    recording = read_acquisition(CAMPAIGN / "hl050.csv")
    events = pd.read_csv(CAMPAIGN / "truth" / "hl050_events.csv")
    return recording, events[events["visible"]]


def load_at(recording, time: float, span: float = 0.3) -> dict[str, float]:
    """Median of each channel over ``span`` seconds ending at ``time`` (noise-robust)."""
    window = recording.sel(time=slice(time - span, time))
    return {name: float(window[name].median()) for name in ["T", "N", "DG", "DD"]}


def test_figure5_signature(hl050):
    recording, events = hl050
    time, T = recording["time"].values, recording["T"].values
    # Normal loading: N reaches the target, T stays near zero.
    loading = time < 9.5
    assert np.abs(np.median(T[loading])) < 0.5 and float(recording["N"][2000]) < -80
    # A stick ramp of T up to the first event.
    first = float(events["t_start"].min())
    ramp = (time > 12.0) & (time < first - 0.5)
    assert np.corrcoef(time[ramp], T[ramp])[0, 1] > 0.99
    # Several gross slips whose drops grow, each with DG and DD jumps in the signals.
    gross = events[events["kind"] == "gross_slip"]
    assert len(gross) >= 4
    drops = gross["drop"].to_numpy()
    assert np.all(np.diff(drops[1:5]) > 0)
    for _, event in gross.iterrows():
        before = load_at(recording, event["t_start"] - 0.05)
        after = load_at(recording, event["t_end"] + 0.35)
        assert before["T"] - after["T"] == pytest.approx(event["drop"], abs=0.6)
        assert abs(after["DG"] - before["DG"]) > 0.08
        assert abs(after["DD"] - before["DD"]) > 0.04
    # Partial slips: smaller T drops, DD moving without the full DG jump.
    partial = events[(events["kind"] == "partial_slip")
                     & (events["t_start"] > gross["t_start"].iloc[0])]
    assert len(partial) >= 5
    assert partial["drop"].median() < 0.5 * gross["drop"].median()
    assert partial["DG_jump"].abs().mean() < 0.35 * gross["DG_jump"].abs().mean()
    assert (partial["DD_jump"].abs() > partial["DG_jump"].abs()).mean() > 0.8
    # T/N at gross slips stays near the bench's value.
    assert np.all((gross["ratio_before"] > 0.6) & (gross["ratio_before"] < 1.1))


def test_waves_run_right_to_left_in_the_video(hl050):
    _, events = hl050
    gross = events[events["kind"] == "gross_slip"].iloc[1]
    start, end = gross["t_start"] - 0.12, gross["t_end"] + 0.12
    frames, times = [], []
    with av.open(str(CAMPAIGN / "hl050.mkv")) as container:
        for frame in container.decode(video=0):
            t = float(frame.pts * frame.time_base)
            if t > end:
                break
            if t >= start:
                frames.append(frame.to_ndarray(format="yuv420p")[:160].astype(float))
                times.append(t)
    assert len(frames) >= 8
    # Geometry only (not the truth): the band of rows just above the slab's bottom edge.
    camera = Photoelastic(BenchTest("hl050").slab(), Camera())
    band = slice(camera.interface_row - 10, camera.interface_row - 2)
    columns = np.flatnonzero(camera.inside.any(axis=0))[5:-5]
    stack = np.stack([f[band][:, columns].mean(axis=0) for f in frames])
    change = np.abs(np.diff(stack, axis=0))  # (frames - 1, columns)
    moving = change.max(axis=0) > 3.0
    when = np.asarray(times[1:])[change.argmax(axis=0)]
    x = columns[moving]
    slope = np.polyfit(x, when[moving], 1)[0]
    assert slope < 0  # the right side changes first
    right = when[moving][x > np.quantile(x, 0.8)].mean()
    left = when[moving][x < np.quantile(x, 0.2)].mean()
    assert right < left


def small(test_id: str = "small", **changes) -> BenchTest:
    settings = {"elements": 40, "duration": 60.0, "video": "ffv1",
                "camera": Camera(width=160, height=80)}
    settings.update(changes)
    return BenchTest(test_id, **settings)


def test_same_seed_same_bytes_other_seed_other_noise(tmp_path):
    spec = small()
    a = write_test(simulate_test(spec, seed=3), tmp_path / "a")
    b = write_test(simulate_test(spec, seed=3), tmp_path / "b")
    c = write_test(simulate_test(spec, seed=4), tmp_path / "c")
    for key in ["csv", "video", "events", "phases", "parameters"]:
        assert a[key].read_bytes() == b[key].read_bytes(), key
    assert a["csv"].read_bytes() != c["csv"].read_bytes()
    assert a["video"].read_bytes() != c["video"].read_bytes()
    assert a["events"].read_bytes() == c["events"].read_bytes()  # same physics
    ra, rc = read_acquisition(a["csv"]), read_acquisition(c["csv"])
    assert float(np.median(np.abs(ra["T"].values - rc["T"].values))) < 0.3


@pytest.mark.parametrize("flavour", ["canonical", "vendor"])
def test_generated_csv_reads_back(tmp_path, flavour):
    result = simulate_test(small(flavour=flavour, video="none"), seed=1)
    paths = write_test(result, tmp_path)
    back = read_acquisition(paths["csv"])
    for name in ["T", "N", "DG", "DD", "DT"]:
        np.testing.assert_allclose(back[name].values, result.recording[name].values,
                                   rtol=1e-6, atol=1e-6)
        assert back[name].attrs["units"] == ("N" if name in "TN" else "mm")
    assert back.attrs["test_id"] == "small" and back.attrs["sync_time_s"] == 2.0
    parameters = json.loads(paths["parameters"].read_text())
    assert parameters["test"]["flavour"] == flavour and parameters["seed"] == 1
    assert "video" not in paths


def test_cli_bench(tmp_path, capsys):
    config = tmp_path / "campaign.yaml"
    config.write_text("defaults:\n  elements: 40\n  duration: 40.0\n  video: none\n"
                      "tests:\n  - test_id: one\n  - test_id: two\n    height: 20.0\n")
    assert main(["bench", str(config), "-o", str(tmp_path / "out"), "--quiet"]) == 0
    table = pd.read_csv(tmp_path / "out" / "tests.tsv", sep="\t")
    assert list(table["test_id"]) == ["one", "two"]
    assert (tmp_path / "out" / "truth" / "two_events.csv").exists()
    config.write_text("tests:\n  - test_id: one\n    colour: blue\n")
    assert main(["bench", str(config), "-o", str(tmp_path / "bad"), "--quiet"]) == 1
    assert "tests[0] (test 'one')" in capsys.readouterr().err


def test_frames_as_image_sequence(tmp_path):
    result = simulate_test(small(video="png", duration=14.0), seed=0)
    paths = write_test(result, tmp_path)
    images = sorted(paths["video"].glob("*.png"))
    assert paths["video"].name == "small_frames" and len(images) == result.frame_times.size
    with av.open(str(images[100])) as container:
        assert next(container.decode(video=0)).width == 160


def test_bench_ids_stay_inside_the_output_folder(tmp_path, capsys):
    config = tmp_path / "c.yaml"
    config.write_text("tests:\n  - test_id: ../escaped\n    duration: 20\n    video: none\n")
    assert main(["bench", str(config), "-o", str(tmp_path / "out"), "--quiet"]) == 1
    assert "c.yaml, line 2: tests[0] (test '../escaped').test_id" in capsys.readouterr().err
    assert not (tmp_path / "escaped.csv").exists() and not (tmp_path / "out").exists()
    with pytest.raises(ConfigError, match="does not match"):
        BenchTest("../escaped")


@pytest.mark.parametrize(("setting", "message"), [
    ("duration: 0", "duration: 0 is less than or equal to the minimum of 0"),
    ("duration: -10", "duration: -10 is less than or equal to the minimum of 0"),
    ("sample_rate: 0", "sample_rate: 0 is less than or equal to the minimum of 0"),
    ("height: forty", "height: 'forty' is not of type 'number'"),
    ("video: avi", "video: 'avi' is not one of"),
    ("speed: 0", "speed: 0 is less than or equal to the minimum of 0"),
])
def test_bench_yaml_is_checked_against_its_schema(tmp_path, capsys, setting, message):
    config = tmp_path / "c.yaml"
    config.write_text(f"tests:\n  - test_id: a\n    {setting}\n")
    assert main(["bench", str(config), "-o", str(tmp_path / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert f"c.yaml, line 3: tests[0] (test 'a').{message}" in err
    assert not (tmp_path / "out").exists()


def test_load_tests_names_the_source():
    with pytest.raises(ConfigError, match=r"the bench config: tests: \[\] should be non-empty"):
        load_tests({"tests": []})
