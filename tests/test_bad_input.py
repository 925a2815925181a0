"""Bad input found by trying slipwave as a new user would (issue 12): one test per defect."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from slipwave.bench.camera import write_image_sequence, write_video
from slipwave.bench.generate import BenchTest, load_tests, simulate_test
from slipwave.campaign import check_config_files, read_campaign
from slipwave.cli import main
from slipwave.errors import ConfigError, SlipwaveError
from slipwave.io import atomic_output, read_acquisition
from slipwave.io import ingest as ingest_module
from slipwave.solver import LoadPath
from slipwave.video import Frame, Geometry, kymograph, open_frames

ROOT = Path(__file__).parents[1]
HL050 = ROOT / "raw_data/bench/hl050.csv"
BIN = Path(sys.executable).parent


def test_1_a_last_line_cut_inside_a_number_is_dropped(tmp_path):
    raw = HL050.read_bytes()
    cut = tmp_path / "cut.csv"
    cut.write_bytes(raw[:-7])  # "11.58905\n" becomes "11.0" and no line end: it parses
    whole, partial = read_acquisition(HL050), read_acquisition(cut)
    assert partial.sizes["time"] == whole.sizes["time"] - 1
    np.testing.assert_array_equal(partial["DT"].values, whole["DT"].values[:-1])
    assert "the file ends inside this line" in partial.attrs["warnings"]


def test_2_the_file_is_read_in_blocks_not_whole(tmp_path, monkeypatch):
    """Peak memory stays near the arrays (figures in bench_ingest): no read of the whole file."""
    monkeypatch.setattr(ingest_module, "_CHUNK_BYTES", 4096)
    reads: list[int] = []
    real_open = ingest_module._open

    def spying_open(path):
        handle = real_open(path)
        read = handle.read

        def counted(size=-1):
            reads.append(size)
            return read(size)

        handle.read = counted  # type: ignore[method-assign]
        return handle

    monkeypatch.setattr(ingest_module, "_open", spying_open)
    blocks = read_acquisition(HL050)
    assert reads and all(0 < size <= ingest_module._HEAD_BYTES for size in reads)
    monkeypatch.undo()
    whole = read_acquisition(HL050)
    assert blocks.identical(whole)  # 300 blocks of 4 KiB give the same Dataset


def test_2_b_line_numbers_hold_across_blocks(write, monkeypatch):
    monkeypatch.setattr(ingest_module, "_CHUNK_BYTES", 64)
    rows = "".join(f"{k / 100:.2f},{k},-80,0,0,0\n" for k in range(40))
    text = "time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]\n" + rows.replace(
        "0.30,30,", "0.30,x30,").replace("0.12,12,-80,0,0,0\n", "0.12,12,-80,0,0,0\n\n")
    with pytest.raises(SlipwaveError, match=r"line 33, column 'T \[N\]': 'x30' is not a number"):
        read_acquisition(write(text))


def test_2_c_a_long_line_at_the_start_of_any_block_is_refused(write, monkeypatch):
    monkeypatch.setattr(ingest_module, "_CHUNK_BYTES", 64)  # pandas only warns on a block's first
    rows = [f"{k / 100:.2f},{k},-80,0,0,0\n" for k in range(30)]
    for k in range(len(rows)):
        longer = [*rows[:k], rows[k].rstrip("\n") + ",7\n", *rows[k + 1 :]]
        path = write("time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]\n" + "".join(longer))
        with pytest.raises(SlipwaveError, match=rf"line {k + 2}: 7 fields where the header has 6"):
            read_acquisition(path)


def test_3_simulate_and_bench_refuse_what_the_machine_cannot_hold(tmp_path, capsys):
    assert main(["simulate", "--fs", "1", "--elements", "100000", "-o",
                 str(tmp_path / "s.nc")]) == 1
    assert "needs about" in capsys.readouterr().err
    assert main(["simulate", "--fs", "1", "--height", "1e6", "-o", str(tmp_path / "s.nc")]) == 1
    assert "H = 1e+06 mm needs about" in capsys.readouterr().err
    with pytest.raises(SlipwaveError, match=r"'big' \(2000 elements.*more than the limit of 1"):
        simulate_test(BenchTest("big", elements=2000), memory_limit_gb=1.0)
    assert not (tmp_path / "s.nc").exists()


def test_4_bench_ids_stay_inside_the_output_folder(tmp_path, capsys):
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
def test_5_bench_yaml_is_checked_against_its_schema(tmp_path, capsys, setting, message):
    config = tmp_path / "c.yaml"
    config.write_text(f"tests:\n  - test_id: a\n    {setting}\n")
    assert main(["bench", str(config), "-o", str(tmp_path / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert f"c.yaml, line 3: tests[0] (test 'a').{message}" in err
    assert not (tmp_path / "out").exists()


def test_6_kymograph_band_and_options():
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
def test_6_b_kymograph_command_refuses_silly_numbers(tmp_path, capsys, option):
    with pytest.raises(SystemExit) as stopped:
        main(["kymograph", str(tmp_path), "-o", str(tmp_path / "k.nc"), *option])
    assert stopped.value.code == 2
    assert f"argument {option[0]}: must be positive, got {option[1]}" in capsys.readouterr().err


def test_7_a_hole_in_the_frame_times_is_reported(tmp_path):
    rng = np.random.default_rng(0)
    images = [rng.integers(0, 50, (40, 60), dtype=np.uint8) for _ in range(30)]
    times = np.r_[np.arange(10) * 0.04, 2.0 + np.arange(20) * 0.04]  # 1.64 s lost
    path = write_video(images, times, tmp_path / "gap.mkv", codec="ffv1")
    source = open_frames(path)
    kymo = kymograph(source, Geometry(interface_row=30, left=10.0, right=50.0, length=80.0))
    assert kymo.attrs["frame_gaps"] == "0.360-2.000 s (40 frames)"
    assert source.warnings == ["no frame between 0.360 s and 2.000 s of camera time (about 40 "
                               "frames missing: skipped or lost); the kymograph has a hole there"]


def test_7_b_a_video_damaged_in_the_middle_names_the_frames_lost(tmp_path):
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


def test_8_sigterm_during_a_write_leaves_nothing(tmp_path):
    big = tmp_path / "big.csv"
    rows = "".join(f"{k / 1000:.3f},{k % 97},-80,0.1,0.2,{k / 1e5:.5f}\n" for k in range(400_000))
    big.write_text("time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]\n" + rows)
    out = tmp_path / "out"
    out.mkdir()
    process = subprocess.Popen([str(BIN / "slipwave"), "ingest", str(big), "-o",
                                str(out / "rec.nc")], stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not list(out.glob(".rec.nc.*.part")) and time.monotonic() < deadline:
        time.sleep(0.01)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    if process.returncode == 0:
        pytest.skip("the write finished before the signal arrived")
    assert process.returncode == 130, err
    assert "interrupted; nothing half-written was kept" in err
    assert list(out.iterdir()) == []


def test_8_c_an_interrupt_just_after_the_part_is_created_leaves_nothing(tmp_path,
                                                                         monkeypatch):
    """SIGTERM (as KeyboardInterrupt) between the part file's creation and its use.

    CI once caught test 8's signal there: the command said nothing half-written was
    kept, and the part file stayed.
    """
    import os

    real_close = os.close

    def interrupted_close(fd: int) -> None:
        real_close(fd)
        monkeypatch.setattr(os, "close", real_close)
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "close", interrupted_close)
    with pytest.raises(KeyboardInterrupt), atomic_output(tmp_path / "rec.nc") as temporary:
        temporary.write_bytes(b"never")
    assert list(tmp_path.iterdir()) == []


def test_8_b_a_stale_part_of_the_same_output_is_removed(tmp_path):
    stale = tmp_path / ".rec.nc.k1ll3d00.part"  # what SIGKILL leaves
    other = tmp_path / ".other.nc.k1ll3d00.part"
    stale.write_bytes(b"x" * 100)
    other.write_bytes(b"x")
    with atomic_output(tmp_path / "rec.nc") as temporary:
        temporary.write_bytes(b"whole")
    assert not stale.exists() and other.exists()
    assert (tmp_path / "rec.nc").read_bytes() == b"whole"


def test_9_campaign_tables_and_configs(write, tmp_path):
    with pytest.raises(ConfigError, match=r"t\.tsv: no test: the table has a header but no row"):
        read_campaign(write("# a campaign\ntest_id\tcsv\n", "t.tsv"))
    table = read_campaign(write("# comment\n\ntest_id\tcsv\na\tx.csv\n# gone\nb\ty.csv\n",
                                "u.tsv"))
    assert table.attrs["lines"] == {"a": 4, "b": 6}
    config = tmp_path / "mine.yaml"
    config.write_text("column_maps: {}\n")
    with pytest.raises(ConfigError, match=r"mine\.yaml: no 'tests' entry naming the campaign"):
        check_config_files([config], command_line=[config])
    check_config_files([config])  # the workflow's own config only: fine


def test_10_binary_and_utf16_files(write):
    with pytest.raises(SlipwaveError, match=r"not a text CSV: binary content \(a NUL byte"):
        read_acquisition(write(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256))))
    text = "time [s];T [N];N [N]\r\n0,0;1,5;-80\r\n0,01;2,5;-80\r\n"
    ds = read_acquisition(write(text.encode("utf-16")))
    assert ds["T"].values.tolist() == [1.5, 2.5]


def test_10_b_infinite_values_are_missing(write):
    ds = read_acquisition(write("time [s],T [N],N [N]\n0,1,-80\n0.01,inf,-80\n0.02,2,-80\n"))
    assert np.isnan(ds["T"].values[1]) and ds["T"].attrs["nan_count"] == 1
    assert "T: 1 infinite value(s) (inf) read as missing" in ds.attrs["warnings"]


def test_10_c_a_missing_image_is_reported_once(tmp_path):
    images = [np.full((40, 60), k, dtype=np.uint8) for k in range(5)]
    folder = write_image_sequence(images, np.arange(5) * 0.04, tmp_path / "frames")
    (folder / "frame_000002.png").unlink()
    source = open_frames(folder)
    kymograph(source, Geometry(interface_row=30, left=10.0, right=50.0, length=80.0))
    list(source)  # a second pass (geometry, then kymograph) does not repeat it
    assert sum("1 image(s) missing between numbers 1 and 3" in w for w in source.warnings) == 1
    assert len(set(source.warnings)) == len(source.warnings)


@pytest.mark.parametrize(("option", "message"), [
    (["--max-travel", "-5"], "max_travel must be positive, not -5"),
    (["--max-travel", "1", "--travel-step", "0"], "travel_step must be positive, not 0"),
])
def test_10_d_simulate_refuses_silly_travel(tmp_path, capsys, option, message):
    assert main(["simulate", "--fs", "1", "--elements", "8", "-o", str(tmp_path / "s.nc"),
                 *option]) == 1
    assert message in capsys.readouterr().err
    with pytest.raises(SlipwaveError, match=message):
        LoadPath(**{option[2 * k][2:].replace("-", "_"): float(option[2 * k + 1])
                    for k in range(len(option) // 2)})


def test_an_unexpected_exception_is_one_line_and_a_log(monkeypatch, tmp_path, capsys):
    def broken(args):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr("slipwave.cli._summary", broken)
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)
    assert main(["summary", "x.nc", "-o", "y.csv"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error (ZeroDivisionError: a bug)" in err
    log = next(tmp_path.glob("slipwave-crash-*.log"))
    assert "Traceback" in log.read_text() and str(log) in err


def test_load_tests_names_the_source():
    with pytest.raises(ConfigError, match=r"the bench config: tests: \[\] should be non-empty"):
        load_tests({"tests": []})
