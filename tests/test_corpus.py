"""A corpus of malformed inputs: each gives one clear error naming the file, where, and what.

Every case runs the command a user would (``slipwave ingest``, ``kymograph``, ``bench``)
or the workflow's checks before any job (``snakemake -n``), and asserts the message: the
file, the line or frame, what is wrong, and no traceback.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from slipwave.bench.camera import write_image_sequence, write_video
from slipwave.cli import main

ROOT = Path(__file__).parents[1]
HEADER = "time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]\n"
ROWS = "".join(f"{k / 100:.2f},{k},-80,0.1,0.2,0.0\n" for k in range(20))

# name -> (file content, regular expression the message must hold after the file's name)
CSV_CASES: dict[str, tuple[bytes, str]] = {
    "empty": (b"", r"the file is empty"),
    "blank": (b"\n\n  \n", r"the file is empty"),
    "only-metadata": (b"# test_id: x\n# sample_rate_hz: 100\n", r"no header row"),
    "binary": (b"PK\x03\x04\x14\x00\x00\x00" + bytes(range(200)), r"not a text CSV: binary"),
    "no-tangential-load": (b"time [s],N [N]\n0,1\n0.01,2\n",
                           r"line 1.*no column for the required channel T"),
    "not-a-number": ((HEADER + ROWS.replace("0.07,7,", "0.07,seven,")).encode(),
                     r"line 9, column 'T \[N\]': 'seven' is not a number"),
    "too-many-fields": ((HEADER + ROWS.replace("0.05,5,-80,0.1,0.2,0.0",
                                               "0.05,5,-80,0.1,0.2,0.0,9")).encode(),
                        r"line 7: 7 fields where the header has 6"),
    "short-row-inside": ((HEADER + ROWS.replace("0.04,4,-80,0.1,0.2,0.0", "0.04,4")).encode(),
                         r"line 6: 2 fields where the header has 6"),
    "time-backwards": ((HEADER + ROWS.replace("0.10,10,", "0.05,10,")).encode(),
                       r"line 12: time 0.05 goes backwards"),
    "time-repeats": ((HEADER + ROWS.replace("0.10,10,", "0.09,10,")).encode(),
                     r"line 12: time 0.09 repeats"),
    "time-missing": ((HEADER + ROWS.replace("0.03,3,", ",3,")).encode(),
                     r"line 5: time is missing"),
    "unknown-unit": ((HEADER.replace("T [N]", "T [blorp]") + ROWS).encode(),
                     r"line 1, column 'T \[blorp\]': unknown unit 'blorp'"),
    "wrong-dimension": ((HEADER.replace("T [N]", "T [mm]") + ROWS).encode(),
                        r"line 1, column 'T \[mm\]': unit 'mm' is not a force"),
    "same-channel-twice": (b"time [s],T [N],Ft [N],N [N]\n0,1,1,-80\n",
                           r"columns 'T \[N\]' and 'Ft \[N\]'"),
    "no-time-no-rate": (b"T [N],N [N]\n1,-80\n2,-80\n", r"no time column and no"),
    "bad-rate": (b"# sample_rate_hz: -5\nT [N],N [N]\n1,-80\n2,-80\n",
                 r"sample_rate_hz is -5, not a positive number"),
    "header-only": (HEADER.encode(), r"line 1: no data rows after the header"),
    "broken-utf16": (b"\xff\xfet\x00i\x00\x00\xd8", r"starts as UTF-16 but is not"),
}


def _stderr_of(capsys, argv: list[str]) -> str:
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 1, err
    return err


@pytest.mark.parametrize("name", list(CSV_CASES))
def test_malformed_csv(tmp_path, capsys, name):
    content, expected = CSV_CASES[name]
    path = tmp_path / f"{name}.csv"
    path.write_bytes(content)
    err = _stderr_of(capsys, ["ingest", str(path), "-o", str(tmp_path / "out.nc")])
    assert f"{name}.csv" in err
    assert re.search(expected, err), err
    assert not (tmp_path / "out.nc").exists()


def test_missing_file_and_folder(tmp_path, capsys):
    err = _stderr_of(capsys, ["ingest", str(tmp_path / "none.csv"), "-o", str(tmp_path / "o.nc")])
    assert "none.csv: no such file" in err
    err = _stderr_of(capsys, ["ingest", str(tmp_path), "-o", str(tmp_path / "o.nc")])
    assert "is a directory, not an acquisition file" in err


def _frames(count: int, size: tuple[int, int] = (48, 64)) -> list[np.ndarray]:
    rng = np.random.default_rng(1)
    return [rng.integers(0, 60, size, dtype=np.uint8) for _ in range(count)]


def _video_cases(folder: Path) -> dict[str, tuple[Path, list[str], str]]:
    """name -> (frames path, extra options, expected message)."""
    cases: dict[str, tuple[Path, list[str], str]] = {}
    text = folder / "text.mkv"
    text.write_text("not a video at all")
    cases["not-a-video"] = (text, [], r"text.mkv: not a readable video")
    good = write_video(_frames(60), np.arange(60) * 0.04, folder / "good.mkv", codec="ffv1")
    cut = folder / "cut.mkv"
    cut.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    cases["truncated-video"] = (cut, [], r"cut.mkv: damaged video after its last good frame, "
                                          r"frame \d+ at [\d.]+ s")
    sizes = write_image_sequence(_frames(4), np.arange(4) * 0.04, folder / "sizes")
    odd = write_image_sequence(_frames(1, (40, 64)), [0.12], folder / "odd")
    shutil.copy(odd / "frame_000000.png", sizes / "frame_000002.png")
    cases["frame-of-another-size"] = (sizes, ["--geometry", "40", "4", "60"],
                                      r"frame_000002.png: frame of 64 x 40 px, the frames before "
                                      r"it are 64 x 48 px")
    untimed = write_image_sequence(_frames(3), np.arange(3) * 0.04, folder / "untimed")
    (untimed / "frames.csv").unlink()
    cases["images-without-times"] = (untimed, ["--geometry", "40", "4", "60"],
                                     r"frame_000000.png: no time \(no frames.csv entry, no fps\)")
    listing = write_image_sequence(_frames(3), np.arange(3) * 0.04, folder / "listing")
    rows = (listing / "frames.csv").read_text().splitlines()
    rows[2] = rows[2].split(",")[0] + ",soon"
    (listing / "frames.csv").write_text("\n".join(rows) + "\n")
    cases["bad-frames-csv"] = (listing, ["--geometry", "40", "4", "60"],
                               r"frames.csv, line 3: expected file,camera_time_s")
    empty = folder / "empty"
    empty.mkdir()
    cases["empty-folder"] = (empty, [], r"empty: no PNG or TIFF images")
    cases["band-above-the-frame"] = (good, ["--geometry", "40", "4", "60", "--band", "0.5", "90"],
                                     r"good.mkv: the band 0.5-90 mm above the interface reaches "
                                     r"above the frame")
    return cases


def test_malformed_video_sources(tmp_path, capsys):
    cases = _video_cases(tmp_path)
    assert len(cases) == 7
    for name, (path, options, expected) in cases.items():
        err = _stderr_of(capsys, ["kymograph", str(path), "-o", str(tmp_path / "k.nc"),
                                  *options])
        assert re.search(expected, err), (name, err)
        assert not (tmp_path / "k.nc").exists()


BENCH_CASES = {
    "yaml-syntax": ("tests:\n  - test_id: a\n    fs: [0.9\n", r"line \d: not valid YAML"),
    "unknown-setting": ("tests:\n  - test_id: a\n    colour: blue\n",
                        r"line 2: tests\[0\] \(test 'a'\): Additional properties are not "
                        r"allowed \('colour' was unexpected\)"),
    "path-in-id": ("tests:\n  - test_id: ../x\n", r"line 2: tests\[0\] \(test '../x'\).test_id"),
    "negative-duration": ("defaults:\n  duration: -1\ntests:\n  - test_id: a\n",
                          r"line 2: defaults.duration: -1 is less than or equal to the minimum"),
    "not-a-mapping": ("- just\n- a list\n", r"line 1: the top level: \['just', 'a list'\] is "
                                             r"not of type 'object'"),
    "camera-bits": ("tests:\n  - test_id: a\n    camera:\n      bits: 12\n",
                    r"line 4: tests\[0\] \(test 'a'\).camera.bits: 12 is not one of \[8, 16\]"),
}


@pytest.mark.parametrize("name", list(BENCH_CASES))
def test_malformed_bench_config(tmp_path, capsys, name):
    text, expected = BENCH_CASES[name]
    config = tmp_path / f"{name}.yaml"
    config.write_text(text)
    err = _stderr_of(capsys, ["bench", str(config), "-o", str(tmp_path / "out"), "--quiet"])
    assert f"{name}.yaml, " in err
    assert re.search(expected, err), err
    assert not (tmp_path / "out").exists()


TABLE = "test_id\tcsv\tframes\tcolumns\tedge_reference\n"
CSV = str(ROOT / "raw_data/bench/hl050.csv")

# name -> (config YAML or None for the default, campaign table or None, expected message)
WORKFLOW_CASES = {
    "edge-ratio-negative": ("tests: t.tsv\ndetection: {gross_edge_ratio: -1}\n", None,
                            r"c.yaml, line 2: detection.gross_edge_ratio: -1 is less than or "
                            r"equal to the minimum of 0"),
    "band-of-three": ("tests: t.tsv\nvideo: {band_mm: [0.5, 1, 2]}\n", None,
                      r"c.yaml, line 2: video.band_mm: \[0.5, 1, 2\] is too long"),
    "unknown-section": ("tests: t.tsv\nplots: {dpi: 300}\n", None,
                        r"c.yaml, line 1: the top level: Additional properties are not allowed "
                        r"\('plots' was unexpected\)"),
    "no-tests-entry": ("column_maps: {}\n", None,
                       r"c.yaml: no 'tests' entry naming the campaign table"),
    "id-with-a-space": (None, TABLE + f"run one\t{CSV}\t\t\t\n",
                        r"t.tsv, line 2 \(test 'run one'\): test_id: 'run one' does not match"),
    "repeated-id": (None, TABLE + f"a\t{CSV}\t\t\t\n# b\na\t{CSV}\t\t\t\n",
                    r"t.tsv, line 4: test_id 'a' appears twice"),
    "no-rows": (None, TABLE, r"t.tsv: no test: the table has a header but no row"),
    "unknown-map": (None, TABLE + f"a\t{CSV}\t\tvendor_y\t\n",
                    r"t.tsv, line 2 \(test 'a'\): column map 'vendor_y' is not in the config"),
    "reference-unknown": (None, TABLE + f"a\t{CSV}\t\t\tabc\n",
                          r"t.tsv, line 2 \(test 'a'\): edge_reference: 'abc' does not match"),
}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(WORKFLOW_CASES))
def test_malformed_workflow_config_stops_before_any_job(snakemake_cli, tmp_path, name):
    config, table, expected = WORKFLOW_CASES[name]
    for item in ("Snakefile", "workflow", "config"):
        source = ROOT / item
        (shutil.copytree if source.is_dir() else shutil.copy)(source, tmp_path / item)
    (tmp_path / "t.tsv").write_text(table or TABLE + f"a\t{CSV}\t\t\t\n")
    (tmp_path / "c.yaml").write_text(config or "tests: t.tsv\n")
    run = snakemake_cli(tmp_path, "-n", "--configfile", "c.yaml")
    assert run.returncode != 0
    output = run.stdout + run.stderr
    assert re.search(expected, output), output
    assert "rule ingest" not in output and not (tmp_path / "results").exists()
