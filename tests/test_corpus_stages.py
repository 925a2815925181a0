"""Hostile input to the newer stages (fit, simulate, compare, report, campaign report, the
campaign table): each case runs the command a user would and asserts the message (the
file, the key or line, the cause), that no traceback reached the user and that nothing
was written.

The products of one short test are made once (a 100 s stretch of the default campaign's
hl050, a hand-written fit.json on a small slab); another test's products are the same
files under another identity, which is what the stages must tell apart.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
import xarray as xr

from fuzzing import valid_fit
from slipwave.cli import main
from slipwave.io import read_dataset, read_table, write_dataset
from slipwave.io.atomic import remove_stale_parts

ROOT = Path(__file__).parents[1]
BENCH = ROOT / "raw_data" / "bench"
SETTINGS = ["--setting", "youngs_modulus_mpa=7", "poisson_ratio=0.48", "edge_reference=frame"]
OTHER_SHA = "f" * 64


def short_csv(folder: Path, name: str = "hl050.csv", seconds: float = 100.0,
              edit: Callable[[list[str], list[str]], None] | None = None) -> Path:
    """The first ``seconds`` of a bench CSV (header lines kept), optionally edited."""
    lines = (BENCH / "hl050.csv").read_text().splitlines()
    header = [line for line in lines if line.startswith("#")]
    table = [line for line in lines if not line.startswith("#")]
    rows = table[1: 1 + int(seconds * 100)]
    if edit is not None:
        edit(header, rows)
    path = folder / name
    path.write_text("\n".join([*header, table[0], *rows]) + "\n")
    return path


def run(capsys, argv: list[str]) -> tuple[int, str]:
    """The exit status and stderr of ``slipwave argv``; argparse's exits are caught."""
    try:
        status = main([str(item) for item in argv])
    except SystemExit as stop:
        status = int(stop.code or 0)
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    assert "internal error" not in err, err
    return status, err


def refused(capsys, argv: list[str], pattern: str, *, status: int = 1) -> str:
    """Run, and assert the status, the message and that no output was written."""
    outputs = [Path(item) for item in argv if Path(str(item)).parent.name == "out"]
    code, err = run(capsys, argv)
    assert code == status, err
    assert re.search(pattern, err), err
    for path in outputs:
        assert not path.exists(), path
        assert not list(path.parent.glob(f".{path.name}.*.part")), path
    return err


def restamp(source: Path, target: Path, **attrs: str) -> Path:
    """A copy of a netCDF product with other identity attributes."""
    dataset = read_dataset(source)
    dataset.attrs.update(attrs)
    write_dataset(dataset, target)
    return target


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """One short test's products, and the same files as another test's and out of date."""
    folder = tmp_path_factory.mktemp("products")
    csv = short_csv(folder)
    p = {name: folder / name for name in (
        "rec.nc", "events.csv", "events.nc", "fit.json", "sim.nc", "contact.nc", "steps.nc",
        "comparison.csv", "comparison.json", "simulated_events.csv")}
    assert main(["ingest", str(csv), "-o", str(p["rec.nc"]), "--test-id", "hl050"]) == 0
    assert main(["detect", str(p["rec.nc"]), "-o", str(p["events.csv"]),
                 "--netcdf", str(p["events.nc"])]) == 0
    sha = read_dataset(p["rec.nc"]).attrs["recording_sha256"]
    setup = {**valid_fit()["setup"], "test_id": "hl050"}
    p["fit.json"].write_text(json.dumps(valid_fit(test_id="hl050", recording_sha256=sha,
                                                  setup=setup)))
    assert main(["simulate", "--fit", str(p["fit.json"]), "-o", str(p["sim.nc"]),
                 "--contact", str(p["contact.nc"]), "--steps", str(p["steps.nc"])]) == 0
    assert main(["compare", str(p["events.nc"]), "--simulated", str(p["sim.nc"]),
                 "--steps", str(p["steps.nc"]), "--fit", str(p["fit.json"]),
                 "-o", str(p["comparison.csv"]), "--json", str(p["comparison.json"]),
                 "--simulated-events", str(p["simulated_events.csv"])]) == 0
    other = folder / "other"
    other.mkdir()
    for name in ("rec.nc", "events.nc", "sim.nc", "contact.nc", "steps.nc"):
        p[f"other/{name}"] = restamp(p[name], other / name, test_id="hl075")
        p[f"stale/{name}"] = restamp(p[name], folder / f"stale-{name}",
                                     recording_sha256=OTHER_SHA)
    for name in ("fit.json", "comparison.json"):
        content = json.loads(p[name].read_text())
        p[f"other/{name}"] = other / name
        p[f"other/{name}"].write_text(json.dumps({**content, "test_id": "hl075"}))
    for name in ("events.csv", "comparison.csv", "simulated_events.csv"):
        p[f"other/{name}"] = other / name
        p[f"other/{name}"].write_text(p[name].read_text().replace("# test_id: hl050",
                                                                  "# test_id: hl075"))
    p["csv"] = csv
    return p


@pytest.fixture
def out(tmp_path: Path) -> Path:
    """A folder for a case's outputs (which must stay empty)."""
    folder = tmp_path / "out"
    folder.mkdir()
    yield folder
    assert not list(folder.iterdir()), list(folder.iterdir())


def edited_fit(made, folder: Path, **changes: object) -> Path:
    content = json.loads(made["fit.json"].read_text())
    content.update(changes)
    path = folder.parent / "edited.json"
    path.write_text(json.dumps(content))
    return path


def test_the_products_carry_their_test(made):
    sha = read_dataset(made["rec.nc"]).attrs["recording_sha256"]
    for name in ("rec.nc", "events.nc", "sim.nc", "contact.nc", "steps.nc"):
        attrs = read_dataset(made[name]).attrs
        assert attrs["test_id"] == "hl050" and attrs["recording_sha256"] == sha, name
    for name in ("events.csv", "comparison.csv", "simulated_events.csv"):
        assert made[name].read_text().startswith(f"# test_id: hl050\n# recording_sha256: "
                                                 f"{sha}\n"), name
        assert read_table(made[name]).attrs == {"test_id": "hl050", "recording_sha256": sha}
    assert json.loads(made["comparison.json"].read_text())["recording_sha256"] == \
        read_dataset(made["rec.nc"]).attrs["recording_sha256"]


# --- the cases: files of different tests ------------------------------------

def test_compare_refuses_another_tests_simulation(made, out, capsys):
    refused(capsys, ["compare", made["events.nc"], "--simulated", made["other/sim.nc"],
                     "--steps", made["other/steps.nc"], "--fit", made["other/fit.json"],
                     "-o", out / "c.csv"],
            r"other/fit.json is of test 'hl075', .*events.nc of test 'hl050': files of "
            r"different tests cannot be combined")


def test_report_refuses_another_tests_fit(made, out, capsys):
    refused(capsys, ["report", made["rec.nc"], "--fit", made["other/fit.json"],
                     "-o", out / "r.html"], r"other/fit.json is of test 'hl075'")


def test_report_refuses_an_out_of_date_simulation(made, out, capsys):
    refused(capsys, ["report", made["rec.nc"], "--events", made["events.nc"],
                     "--simulated", made["stale/sim.nc"], "-o", out / "r.html"],
            r"stale-sim.nc and .*rec.nc are both of test 'hl050' but of different "
            r"recordings .*make it again")


def test_report_refuses_another_tests_tables(made, out, capsys):
    refused(capsys, ["report", made["rec.nc"], "--fit", made["fit.json"],
                     "--comparison", made["other/comparison.csv"], "-o", out / "r.html"],
            r"other/comparison.csv is of test 'hl075'")
    refused(capsys, ["report", made["rec.nc"], "--fit", made["fit.json"],
                     "--simulated-events", made["other/simulated_events.csv"],
                     "-o", out / "r.html"], r"other/simulated_events.csv is of test 'hl075'")


def test_compare_refuses_another_tests_waves(made, out, capsys):
    refused(capsys, ["compare", made["events.nc"], "--simulated", made["sim.nc"],
                     "--fit", made["fit.json"], "--waves", made["other/events.csv"],
                     "-o", out / "c.csv"], r"other/events.csv is of test 'hl075'")


def test_compare_refuses_another_tests_steps(made, out, capsys):
    refused(capsys, ["compare", made["events.nc"], "--simulated", made["sim.nc"],
                     "--steps", made["other/steps.nc"], "--fit", made["fit.json"],
                     "-o", out / "c.csv"], r"other/steps.nc is of test 'hl075'")


def test_report_refuses_another_tests_contact_and_comparison(made, out, capsys):
    refused(capsys, ["report", made["rec.nc"], "--fit", made["fit.json"],
                     "--contact", made["other/contact.nc"], "-o", out / "r.html"],
            r"other/contact.nc is of test 'hl075'")
    refused(capsys, ["report", made["rec.nc"], "--fit", made["fit.json"],
                     "--comparison-json", made["other/comparison.json"], "-o", out / "r.html"],
            r"other/comparison.json is of test 'hl075'")


def test_detect_refuses_another_tests_simulated_threshold(made, out, capsys):
    refused(capsys, ["detect", made["rec.nc"], "--simulated", made["other/sim.nc"],
                     "-o", out / "e.csv", "--netcdf", out / "e.nc"],
            r"other/sim.nc is of test 'hl075'")


def test_waves_refuses_another_tests_events(made, out, tmp_path, capsys):
    kymograph = tmp_path / "k.nc"
    write_dataset(xr.Dataset(attrs={"product": "kymograph"}), kymograph)
    refused(capsys, ["waves", kymograph, "--recording", made["rec.nc"],
                     "--events", made["other/events.nc"], "-o", out / "w.csv",
                     "--fused", out / "f.csv", "--clock", out / "c.json"],
            r"other/events.nc is of test 'hl075'")


def test_waves_refuses_another_tests_video(made, out, tmp_path, capsys):
    kymograph = tmp_path / "k.nc"
    write_dataset(xr.Dataset(attrs={"product": "kymograph", "test_id": "hl075"}), kymograph)
    refused(capsys, ["waves", kymograph, "--recording", made["rec.nc"],
                     "--events", made["events.nc"], "-o", out / "w.csv",
                     "--fused", out / "f.csv", "--clock", out / "c.json"],
            r"k.nc is of test 'hl075', .*rec.nc of test 'hl050'")


def test_summary_refuses_a_test_twice(made, out, capsys):
    refused(capsys, ["summary", made["events.nc"], made["events.nc"], "-o", out / "s.csv"],
            r"events.nc: test 'hl050' again")


# --- the cases: a file that is not the product asked for ---------------------

@pytest.mark.parametrize(("command", "pattern"), [
    (["fit", "{events_nc}", "-o", "{out}/f.json"],
     r"events.nc: holds events, not a recording \(the product of 'slipwave ingest'\)"),
    (["compare", "{events_nc}", "--simulated", "{contact_nc}", "--fit", "{fit_json}",
      "-o", "{out}/c.csv"], r"contact.nc: holds a contact history, not a simulated recording"),
    (["summary", "{rec_nc}", "-o", "{out}/s.csv"], r"rec.nc: holds a recording, not events"),
    (["map", "assemble", "{rec_nc}", "-o", "{out}/m.nc", "--csv", "{out}/m.csv",
      "--legend", "{out}/m.md"], r"rec.nc: holds a recording, not a map row"),
    (["map", "figures", "{sim_nc}", "--figure", "{out}/m.png"],
     r"sim.nc: holds a simulated recording, not a behaviour map"),
    (["report", "{events_nc}", "-o", "{out}/r.html"], r"events.nc: holds events, not a "
                                                     r"recording"),
])
def test_a_file_of_another_kind_is_refused(made, out, capsys, command, pattern):
    argv = [item.format(out=out, **{k.replace(".", "_"): v for k, v in made.items()
                                    if "/" not in k}) for item in command]
    refused(capsys, argv, pattern)


def test_a_kymograph_given_as_simulated_recording(made, out, tmp_path, capsys):
    kymograph = tmp_path / "k.nc"
    write_dataset(xr.Dataset(attrs={"product": "kymograph"}), kymograph)
    refused(capsys, ["compare", made["events.nc"], "--simulated", kymograph,
                     "--fit", made["fit.json"], "-o", out / "c.csv"],
            r"k.nc: holds a kymograph, not a simulated recording \(the product of 'slipwave "
            r"simulate --fit'\)")


def test_a_text_file_given_as_netcdf(made, out, tmp_path, capsys):
    text = tmp_path / "notes.nc"
    text.write_text("not netCDF")
    refused(capsys, ["fit", text, "-o", out / "f.json"], r"notes.nc: cannot be read as netCDF")


# --- the cases: fit.json read by simulate, compare, fits, report -------------

@pytest.mark.parametrize(("changes", "pattern"), [
    ({"parameters": {}}, r"parameters: \{\} should be non-empty|parameters: \{\} does not "
                         r"have enough properties"),
    ({"parameters": {"fs": "abc", "fd": 0.6}}, r"parameters.fs: 'abc' is not of type 'number'"),
    ({"setup": None}, r"setup: None is not of type 'object'"),
    ({"chosen": "run-in"}, r"chosen: 'run-in' is not one of the fitted laws \['coulomb'\]"),
    ({"parameters": {"fs": 0.5, "fd": 0.7}}, r"friction needs 0 <= fd <= fs"),
    ({"parameters": {"fs": 0.8, "dc": 0.7}}, r"parameters: \['dc', 'fs'\] are not the "
                                             r"parameters of the coulomb law"),
    ({"elements": 100000}, r"elements: 100000 is greater than the maximum of 1280"),
    ({"elements": 3}, r"elements: 3 is less than the minimum of 10"),
    ({"recording_sha256": "abc"}, r"recording_sha256: 'abc' does not match"),
    ({"load_calibration": -0.5}, r"load_calibration: -0.5 is less than the minimum of 0"),
    ({"test_id": "javascript:alert(1)//"}, r"test_id: 'javascript:alert\(1\)//' does not "
                                           r"match"),
])
def test_an_edited_fit_is_refused_naming_the_key(made, out, capsys, changes, pattern):
    path = edited_fit(made, out, **changes)
    refused(capsys, ["simulate", "--fit", path, "-o", out / "s.nc"], r"edited.json: " + pattern)


def test_a_fit_without_setup_given_to_fits(made, out, capsys):
    content = json.loads(made["fit.json"].read_text())
    del content["setup"]
    path = out.parent / "bare.json"
    path.write_text(json.dumps(content))
    refused(capsys, ["fits", path, "-o", out / "fits.csv"],
            r"bare.json: the top level: 'setup' is a required property")


def test_a_broken_fit_json_names_line_and_column(made, out, capsys):
    path = out.parent / "cut.json"
    path.write_text(made["fit.json"].read_text()[:200])
    refused(capsys, ["compare", made["events.nc"], "--simulated", made["sim.nc"],
                     "--fit", path, "-o", out / "c.csv"],
            r"cut.json, line 1, column \d+: not valid JSON")


def test_a_run_in_of_a_fractional_number_of_slips_is_simulated(made, out, tmp_path):
    """A fitted run-in's length need not be whole: the simulation takes 2.5 slips."""
    law = json.loads(made["fit.json"].read_text())["laws"]["coulomb"]
    run_in = {**law, "law": "run-in", "parameters": {
        name: {"value": 0.7, "low": 0.6, "high": 0.8} for name in ("fs", "fd", "fs_final")}
        | {"runin_slips": {"value": 2.5, "low": 2, "high": 3}}}
    path = edited_fit(made, out, laws={"run-in": run_in}, chosen="run-in",
                      parameters={"fs": 0.7, "fd": 0.6, "fs_final": 0.8, "runin_slips": 2.5})
    assert main(["simulate", "--fit", str(path), "-o", str(tmp_path / "s.nc")]) == 0
    assert (tmp_path / "s.nc").exists()


def test_a_comparison_json_without_test_id(made, out, capsys, tmp_path):
    content = json.loads(made["comparison.json"].read_text())
    del content["test_id"]
    path = tmp_path / "cmp.json"
    path.write_text(json.dumps(content))
    summary = tmp_path / "summary.csv"
    summary.write_text("test_id\nhl050\n")
    refused(capsys, ["campaign-report", "--summary", summary, "--comparisons", path,
                     "-o", out / "c.html"], r"cmp.json: the top level: 'test_id' is a required "
                                             r"property")


# --- the cases: memory checked before every simulation -----------------------

def test_the_fit_checks_memory_before_simulating(made, out, capsys, monkeypatch):
    monkeypatch.setenv("SLIPWAVE_MEMORY_LIMIT_GB", "0.01")
    refused(capsys, ["fit", made["rec.nc"], "-o", out / "f.json", *SETTINGS],
            r"fitting test 'hl050' with 80 elements \(checked at 160\) needs about [\d.]+ GB, "
            r"more than the limit of 0.01 GB")


def test_a_huge_slab_in_the_header_is_refused_before_the_fit(tmp_path, out, capsys):
    csv = short_csv(tmp_path, edit=lambda header, rows: header.__setitem__(
        3, "# height_mm: 1e6"))
    assert main(["ingest", str(csv), "-o", str(tmp_path / "r.nc")]) == 0
    capsys.readouterr()
    refused(capsys, ["fit", tmp_path / "r.nc", "-o", out / "f.json", *SETTINGS],
            r"fitting test 'hl050' with 80 elements \(checked at 160\) needs about [\d.]+ GB, "
            r"more than the")


def test_simulate_checks_memory_of_its_sample_rate(made, out, capsys):
    refused(capsys, ["simulate", "--fit", made["fit.json"], "-o", out / "s.nc",
                     "--sample-rate", "1e7"],
            r"simulating test 'hl050' with 16 elements at 1e\+07 Hz needs about [\d.]+ GB")


def test_an_edited_fit_of_many_elements_meets_the_memory_limit(made, out, capsys):
    path = edited_fit(made, out, elements=1280)
    refused(capsys, ["simulate", "--fit", path, "-o", out / "s.nc", "--memory-limit", "1"],
            r"with 1280 elements at 100 Hz needs about [\d.]+ GB, more than the limit of 1 GB")


# --- the cases: options without meaning --------------------------------------

@pytest.mark.parametrize(("argv", "pattern"), [
    (["fit", "{rec_nc}", "-o", "{out}/f.json", "--members", "1"],
     r"argument --members: 1 is less than the minimum of 2"),
    (["fit", "{rec_nc}", "-o", "{out}/f.json", "--design", "-5"],
     r"argument --design: -5 is less than the minimum of 1"),
    (["fit", "{rec_nc}", "-o", "{out}/f.json", "--load-calibration", "-0.5"],
     r"argument --load-calibration: -0.5 is less than the minimum of 0"),
    (["fit", "{rec_nc}", "-o", "{out}/f.json", "--elements", "100000"],
     r"argument --elements: 100000 is greater than the maximum of 1280"),
    (["report", "{rec_nc}", "-o", "{out}/r.html", "--threads", "0"],
     r"argument --threads: must be 1 or more"),
    (["map", "row", "--height-ratio", "0.5", "--shard", "-1", "-o", "{out}/r.nc"],
     r"argument --shard: must be 0 or more"),
    (["simulate", "--fs", "0.5", "--elements", "3", "-o", "{out}/s.nc"],
     r"argument --elements: 3 is less than the minimum of 8"),
    (["detect", "{rec_nc}", "-o", "{out}/e.csv", "--threshold", "abc"],
     r"argument --threshold: expected a number, got 'abc'"),
    (["report", "{rec_nc}", "-o", "{out}/r.html", "--waves", "{out}/missing.csv"],
     r"argument --waves: no such file or folder: '.*missing.csv'"),
])
def test_an_option_without_meaning_is_refused(made, out, capsys, argv, pattern):
    argv = [item.format(out=out, **{k.replace(".", "_"): v for k, v in made.items()
                                    if "/" not in k}) for item in argv]
    refused(capsys, argv, pattern, status=2)


def test_a_band_upside_down(made, out, capsys):
    refused(capsys, ["simulate", "--fit", made["fit.json"], "-o", out / "s.nc",
                     "--band", "2", "1"], r"--band 2 1: a band above the interface needs "
                                          r"0 <= LOW < HIGH")


# --- the cases: the test's setup ----------------------------------------------

@pytest.mark.parametrize(("line", "pattern"), [
    ("# height_mm: 0", r"hl050.csv's header line height_mm: 0.0 is less than or equal to the "
                       r"minimum of 0; correct it, or give the column height_mm"),
    ("# height_mm: abc", r"hl050.csv's header line height_mm: 'abc' is not a number"),
    ("# height_mm: 1", r"slab height 1.0 mm must exceed the sensor height"),
])
def test_a_bad_header_value_names_the_header_line(tmp_path, out, capsys, line, pattern):
    csv = short_csv(tmp_path, edit=lambda header, rows: header.__setitem__(3, line))
    assert main(["ingest", str(csv), "-o", str(tmp_path / "r.nc")]) == 0
    capsys.readouterr()
    refused(capsys, ["fit", tmp_path / "r.nc", "-o", out / "f.json", *SETTINGS],
            r"test 'hl050': " + pattern)


@pytest.mark.parametrize(("setting", "pattern"), [
    ("youngs_modulus_mpa=1e12", r"youngs_modulus_mpa: 1000000000000.0 is greater than the "
                                r"maximum of 1000000.0"),
    ("poisson_ratio=0.5", r"poisson_ratio: 0.5 is greater than or equal to the maximum of 0.5"),
    ("height_mm=-5", r"height_mm: -5.0 is less than or equal to the minimum of 0"),
    ("normal_load_n=0", r"normal_load_n: 0.0 is less than or equal to the minimum of 0"),
    ("edge_reference=sideways", r"what the edge sensors read against is 'sideways'"),
])
def test_a_bad_setting_names_the_column(made, out, capsys, setting, pattern):
    settings = [item for item in SETTINGS if not item.startswith(setting.split("=")[0])]
    refused(capsys, ["fit", made["rec.nc"], "-o", out / "f.json", *settings, setting],
            r"test 'hl050': (campaign-table column )?" + pattern)


def test_a_stick_only_record_has_nothing_to_fit(tmp_path, out, capsys):
    csv = short_csv(tmp_path, seconds=5.0)
    assert main(["ingest", str(csv), "-o", str(tmp_path / "r.nc")]) == 0
    capsys.readouterr()
    refused(capsys, ["fit", tmp_path / "r.nc", "-o", out / "f.json", *SETTINGS],
            r"test 'hl050': no slip detected in hl050.csv \(T never drops by more than the "
            r"detection's threshold\): no friction law can be fitted on stick alone")


def test_a_test_loaded_along_minus_x(made, out, tmp_path, capsys):
    recording = read_dataset(made["rec.nc"])
    for channel in ("T", "DG", "DD", "DT"):
        recording[channel] = -recording[channel]
    write_dataset(recording, tmp_path / "minus.nc")
    refused(capsys, ["detect", tmp_path / "minus.nc", "-o", out / "e.csv"],
            r"T falls from .* N to -\d+.* N .*no drop of T is found: the test was loaded "
            r"along -x")


def test_a_javascript_test_id_in_the_header(tmp_path, out, capsys):
    csv = short_csv(tmp_path, edit=lambda header, rows: header.__setitem__(
        0, "# test_id: javascript:alert(document.domain)//"))
    refused(capsys, ["ingest", csv, "-o", out / "r.nc"],
            r"hl050.csv: header line test_id: 'javascript:alert\(document.domain\)//' is not "
            r"a test id .*name the test with --test-id")
    refused(capsys, ["ingest", csv, "-o", out / "r.nc", "--test-id", "../up"],
            r"--test-id: '../up' is not a test id")


def test_a_javascript_test_id_in_a_summary(tmp_path, out, capsys):
    summary = tmp_path / "summary.csv"
    summary.write_text("test_id,gross_slips\nhl050,3\njavascript:alert(1)//,2\n")
    refused(capsys, ["campaign-report", "--summary", summary, "-o", out / "c.html"],
            r"summary.csv, line 3: 'javascript:alert\(1\)//' is not a test id")


def test_campaign_report_tables_that_are_not_tables(tmp_path, out, capsys):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    refused(capsys, ["campaign-report", "--summary", empty, "-o", out / "c.html"],
            r"empty.csv: the file is empty, not a CSV table")
    columns = tmp_path / "columns.csv"
    columns.write_text("id,slips\na,1\n")
    refused(capsys, ["campaign-report", "--summary", columns, "-o", out / "c.html"],
            r"columns.csv: no column 'test_id' \(its columns: id, slips\)")


def test_report_tables_that_are_not_tables(made, out, tmp_path, capsys):
    garbage = tmp_path / "garbage.csv"
    garbage.write_bytes(bytes(range(256)) * 4)
    refused(capsys, ["report", made["rec.nc"], "--fit", made["fit.json"],
                     "--comparison", garbage, "-o", out / "r.html"],
            r"garbage.csv: not (UTF-8 text|a CSV table)")
    clock = tmp_path / "clock.json"
    clock.write_text("[1, 2]")
    kymograph = tmp_path / "k.nc"
    write_dataset(xr.Dataset(attrs={"product": "kymograph"}), kymograph)
    refused(capsys, ["report", made["rec.nc"], "--kymograph", kymograph,
                     "--waves", made["comparison.csv"], "--clock", clock, "-o", out / "r.html"],
            r"clock.json: not a camera clock fit")


def test_a_recording_without_drive_channel(tmp_path, out, capsys):
    csv = short_csv(tmp_path)
    lines = csv.read_text().splitlines()
    csv.write_text("\n".join(line if line.startswith("#") else line.rsplit(",", 1)[0]
                             for line in lines) + "\n")
    assert main(["ingest", str(csv), "-o", str(tmp_path / "r.nc")]) == 0
    capsys.readouterr()
    assert "DT" not in read_dataset(tmp_path / "r.nc")
    refused(capsys, ["fit", tmp_path / "r.nc", "-o", out / "f.json", *SETTINGS],
            r"no DT channel to measure the drive on; add the column\(s\) speed_mm_s and "
            r"machine_stiffness_n_mm")


def _without_normal(header: list[str], rows: list[str]) -> None:
    for k, row in enumerate(rows):
        cells = row.split(",")
        cells[2] = "0"
        rows[k] = ",".join(cells)


def test_a_normal_load_of_zero(tmp_path, out, capsys):
    csv = short_csv(tmp_path, edit=_without_normal)
    assert main(["ingest", str(csv), "-o", str(tmp_path / "r.nc")]) == 0
    capsys.readouterr()
    refused(capsys, ["fit", tmp_path / "r.nc", "-o", out / "f.json", *SETTINGS],
            r"test 'hl050': N reads 0 N over the second before T rises \(t = [\d.]+ s\): no "
            r"normal load measured; check the N column, or give the column normal_load_n")


def test_no_normal_channel_cannot_be_fitted(tmp_path, out, capsys):
    csv = short_csv(tmp_path)
    lines = csv.read_text().splitlines()
    csv.write_text("\n".join(line if line.startswith("#") else
                             ",".join(cell for k, cell in enumerate(line.split(",")) if k != 2)
                             for line in lines) + "\n")
    assert main(["ingest", str(csv), "-o", str(tmp_path / "r.nc")]) == 0
    capsys.readouterr()
    refused(capsys, ["fit", tmp_path / "r.nc", "-o", out / "f.json", *SETTINGS,
                     "normal_load_n=85"],
            r"test 'hl050': no N channel: the fit compares T/\|N\| at each slip, and a "
            r"nominal normal_load_n cannot stand in")


def test_a_saturated_drive_sensor_is_said_and_left_out(tmp_path, capsys):
    # DT clipped at 2.5 mm from about 60 s: the ingest says so, the drive is measured
    # on the samples before, and a given stiffness is not asked for again
    clip = 2.5

    def saturate(header: list[str], rows: list[str]) -> None:
        for k, row in enumerate(rows):
            cells = row.split(",")
            cells[5] = f"{min(float(cells[5]), clip):.6g}"
            rows[k] = ",".join(cells)

    full = short_csv(tmp_path, "full.csv")
    csv = short_csv(tmp_path, "clipped.csv", edit=saturate)
    assert main(["ingest", str(full), "-o", str(tmp_path / "full.nc")]) == 0
    assert main(["ingest", str(csv), "-o", str(tmp_path / "r.nc")]) == 0
    err = capsys.readouterr().err
    assert re.search(r"clipped.csv: DT: stays at 2.5 mm from line \d+ on, as a sensor at the "
                     r"end of its range does", err), err
    from slipwave.setup import read_test_setup

    cells = {"youngs_modulus_mpa": "7", "poisson_ratio": "0.48", "edge_reference": "frame"}
    truth = read_test_setup(read_dataset(tmp_path / "full.nc"), cells)
    clipped = read_test_setup(read_dataset(tmp_path / "r.nc"), cells)
    assert clipped["speed_mm_s"] == pytest.approx(truth["speed_mm_s"], rel=0.02)
    assert clipped["machine_stiffness_n_mm"] == pytest.approx(
        truth["machine_stiffness_n_mm"], rel=0.05)
    given = read_test_setup(read_dataset(tmp_path / "r.nc"),
                            {**cells, "machine_stiffness_n_mm": "40"})
    assert given["machine_stiffness_n_mm"] == 40.0
    assert given.settings["speed_mm_s"].source.startswith("measured")


def test_no_normal_channel_with_the_normal_load_given(made):
    from slipwave.setup import read_test_setup

    recording = read_dataset(made["rec.nc"]).drop_vars("N")
    setup = read_test_setup(recording, {"youngs_modulus_mpa": "7", "poisson_ratio": "0.48",
                                        "edge_reference": "frame", "normal_load_n": "85"})
    assert setup["normal_load_n"] == 85.0
    assert setup.settings["loading_time_s"].source == "no N channel: the time T starts to rise"
    assert 0 < setup["loading_time_s"] < 20


def test_a_solver_failure_names_the_test_and_its_setup():
    from slipwave.errors import SlipwaveError, SolverError
    from slipwave.setup import Setting, TestSetup
    from slipwave.solver import Coulomb

    settings = {key: Setting(item["value"], item["source"])
                for key, item in valid_fit()["setup"].items() if isinstance(item, dict)}
    setup = TestSetup("hard", settings, "frame")
    import slipwave.setup as module

    def failing(*args, **kwargs):
        raise SolverError(55, float("nan"), "no convergence")

    original, module.simulate = module.simulate, failing
    try:
        with pytest.raises(SlipwaveError, match=r"test 'hard': the solver failed at step 55: "
                           r"no convergence .* check youngs_modulus_mpa 7 \(campaign table\)"):
            setup.simulate(Coulomb(fs=0.8, fd=0.6), 16)
    finally:
        module.simulate = original


# --- the cases: the cache, killed writers -------------------------------------

def test_a_damaged_or_foreign_cache_file_is_rebuilt(tmp_path, capsys):
    cache = tmp_path / "cache"
    argv = ["simulate", "--fs", "0.5", "--elements", "8", "--cache-dir", str(cache)]
    assert main([*argv, "-o", str(tmp_path / "first.nc")]) == 0
    (stored,) = cache.glob("condensed-*.npz")
    first = read_dataset(tmp_path / "first.nc")
    stored.write_bytes(stored.read_bytes()[:100])  # truncated
    assert main([*argv, "-o", str(tmp_path / "second.nc")]) == 0
    assert read_dataset(tmp_path / "second.nc")["T"].equals(first["T"])
    assert stored.stat().st_size > 100  # rebuilt
    # another geometry's (valid) file under this key's name
    assert main(["simulate", "--fs", "0.5", "--elements", "10", "--cache-dir",
                 str(tmp_path / "other"), "-o", str(tmp_path / "other.nc")]) == 0
    (foreign,) = (tmp_path / "other").glob("condensed-*.npz")
    shutil.copy(foreign, stored)
    assert main([*argv, "-o", str(tmp_path / "third.nc")]) == 0
    assert read_dataset(tmp_path / "third.nc")["T"].equals(first["T"])
    capsys.readouterr()


def test_the_part_of_a_killed_writer_is_removed(tmp_path):
    from slipwave.io.atomic import _host

    folder = tmp_path / "reports"
    folder.mkdir()
    dead = folder / f".hl050.html.{_host()}-999999999-0a1b2c.part"
    alive = folder / f".hl075.html.{_host()}-{os.getpid()}-0a1b2c.part"
    elsewhere = folder / ".hl025.html.node17-4242-0a1b2c.part"  # a cluster node's job
    for part in (dead, alive, elsewhere):
        part.write_text("")
    assert remove_stale_parts([folder, tmp_path / "missing"]) == [dead]
    assert alive.exists() and elsewhere.exists() and not dead.exists()
    assert sorted(remove_stale_parts([folder], nothing_runs=True)) == sorted([alive, elsewhere])


def test_a_killed_report_leaves_nothing_after_the_workflow_starts(made, tmp_path):
    # SIGKILL while the page is written: the .part stays until remove_stale_parts
    output = tmp_path / "reports" / "hl050.html"
    output.parent.mkdir()
    command = [sys.executable, "-c", "import os, signal, sys; from slipwave.cli import main; "
               "from slipwave.io import atomic_output\n"
               "import slipwave.report as report\n"
               "def killed(*args, **kwargs):\n"
               "    with atomic_output(args[1]) as part:\n"
               "        part.write_text('half')\n"
               "        os.kill(os.getpid(), signal.SIGKILL)\n"
               "report.write_test_page = killed\n"
               f"sys.exit(main(['report', {str(made['rec.nc'])!r}, '-o', {str(output)!r}]))"]
    subprocess.run(command, check=False, timeout=120)
    assert not output.exists()
    assert len(list(output.parent.glob(".hl050.html.*.part"))) == 1
    remove_stale_parts([output.parent])
    assert not list(output.parent.iterdir())


# --- the cases: the campaign table and config, through the workflow -----------

BIN = Path(sys.executable).parent
ENV = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
TABLE = "test_id\tcsv\tframes\tyoungs_modulus_mpa\tpoisson_ratio\tedge_reference\n"
CSV = str(BENCH / "hl050.csv")

WORKFLOW_CASES = {
    "id-campaign": (TABLE + f"campaign\t{CSV}\t\t7\t0.48\tframe\n",
                    r"t.tsv, line 2 \(test 'campaign'\): test_id 'campaign' is the name of a "
                    r"campaign product \(reports/campaign.html\): rename the test"),
    "id-summary": (TABLE + f"summary.csv\t{CSV}\t\t7\t0.48\tframe\n",
                   r"t.tsv, line 2 \(test 'summary.csv'\): test_id 'summary.csv' is the name "
                   r"of a campaign product \(results/summary.csv\)"),
    "id-case": (TABLE + f"hl050\t{CSV}\t\t7\t0.48\tframe\nHL050\t{CSV}\t\t7\t0.48\tframe\n",
                r"t.tsv, line 3 \(test 'HL050'\): test_id 'HL050' differs from 'hl050' only "
                r"by case"),
    "poisson": (TABLE + f"a\t{CSV}\t\t7\t0.6\tframe\n",
                r"t.tsv, line 2 \(test 'a'\): poisson_ratio: 0.6 is greater than or equal to "
                r"the maximum of 0.5"),
    "modulus": (TABLE + f"a\t{CSV}\t\t1e12\t0.48\tframe\n",
                r"t.tsv, line 2 \(test 'a'\): youngs_modulus_mpa: 1000000000000.0 is greater "
                r"than the maximum of 1000000.0"),
}


def _workflow(folder: Path, table: str, config: str = "tests: t.tsv\n",
              *arguments: str) -> subprocess.CompletedProcess[str]:
    for item in ("Snakefile", "workflow", "config"):
        source = ROOT / item
        (shutil.copytree if source.is_dir() else shutil.copy)(source, folder / item)
    (folder / "t.tsv").write_text(table)
    (folder / "c.yaml").write_text(config)
    return subprocess.run([str(BIN / "snakemake"), "--configfile", "c.yaml", *arguments],
                          cwd=folder, capture_output=True, text=True, timeout=600, check=False,
                          env=ENV)


@pytest.mark.slow
def test_a_bad_campaign_table_stops_the_workflow_before_any_job(tmp_path):
    table, expected = WORKFLOW_CASES["id-campaign"]
    run = _workflow(tmp_path, table, "tests: t.tsv\n", "-n")
    output = run.stdout + run.stderr
    assert run.returncode != 0 and re.search(expected, output), output
    assert not (tmp_path / "results").exists()


@pytest.mark.parametrize("name", list(WORKFLOW_CASES))
def test_a_bad_campaign_table_is_refused_naming_its_line(tmp_path, capsys, name):
    # the Snakefile's own checks (above), run by check-config without Snakemake
    table, expected = WORKFLOW_CASES[name]
    (tmp_path / "t.tsv").write_text(table)
    config = tmp_path / "c.yaml"
    config.write_text(f"tests: {tmp_path / 't.tsv'}\n")
    refused(capsys, ["check-config", config, "--workflow-config", ROOT / "config/config.yaml"],
            expected)


@pytest.mark.slow
def test_the_config_schema_caps_the_fit_elements(tmp_path):
    run = _workflow(tmp_path, TABLE + f"a\t{CSV}\t\t7\t0.48\tframe\n",
                    "tests: t.tsv\nfit: {elements: 100000}\n", "-n")
    assert run.returncode != 0
    assert re.search(r"c.yaml, line 2: fit.elements: 100000 is greater than the maximum of "
                     r"1280", run.stdout + run.stderr)


@pytest.mark.slow
def test_hostile_frame_paths_are_one_argument_and_run_nothing(tmp_path):
    # a frames path that would run a command in a shell, and one with a space: the
    # kymograph rule reads each as one file (and says it is not a video)
    for name in ("v$(>PWNED).mkv", "my video.mkv"):
        (tmp_path / name).write_text("not a video")
    table = TABLE + "".join(f"{test}\t{CSV}\t{tmp_path / name}\t7\t0.48\tframe\n"
                            for test, name in (("a", "v$(>PWNED).mkv"), ("b", "my video.mkv")))
    run = _workflow(tmp_path, table, "tests: t.tsv\n", "--cores", "1", "--keep-going",
                    "results/a/kymograph.nc", "results/b/kymograph.nc")
    assert run.returncode != 0
    assert not (tmp_path / "PWNED").exists() and not Path("PWNED").exists()
    for test, name in (("a", r"v\$\(>PWNED\).mkv"), ("b", "my video.mkv")):
        log = (tmp_path / "results" / "logs" / "kymograph" / f"{test}.log").read_text()
        assert re.search(name + r": not a readable video", log), log
        assert "unrecognized arguments" not in log
    assert not list((tmp_path / "results").rglob("kymograph.nc"))


def test_check_config_names_the_line_of_a_python_tag(tmp_path, capsys):
    config = tmp_path / "c.yaml"
    config.write_text("tests: t.tsv\nfit: !!python/object/apply:os.system ['touch PWNED']\n")
    refused(capsys, ["check-config", config, "--workflow-config", ROOT / "config/config.yaml"],
            r"c.yaml, line 2: not valid YAML: could not determine a constructor for the tag "
            r"'tag:yaml.org,2002:python/object/apply:os.system'")
    assert not (tmp_path / "PWNED").exists()


def test_check_config_checks_the_campaign_table(tmp_path, capsys):
    (tmp_path / "t.tsv").write_text(TABLE + f"campaign\t{CSV}\t\t7\t0.48\tframe\n")
    config = tmp_path / "c.yaml"
    config.write_text(f"tests: {tmp_path / 't.tsv'}\n")
    refused(capsys, ["check-config", config, "--workflow-config", ROOT / "config/config.yaml"],
            r"t.tsv, line 2 \(test 'campaign'\): test_id 'campaign' is the name of a campaign "
            r"product")


def test_every_campaign_product_name_is_reserved():
    # the campaign's own outputs, as the rules write them, against the reserved ids
    from slipwave.campaign import RESERVED_TEST_IDS

    text = "\n".join(path.read_text() for path in [ROOT / "Snakefile",
                                                   *(ROOT / "workflow/rules").glob("*.smk")])
    names = set()
    for folder, rest in re.findall(r"\"(results|reports)/([^\"{]+)\"", text):
        first = rest.split("/")[0]
        names.add(first.rsplit(".", 1)[0] if folder == "reports" else first)
    config = (ROOT / "src/slipwave/schemas/config.schema.json").read_text()
    names.add(json.loads(config)["properties"]["cache_dir"]["default"].split("/")[1])
    assert names and names <= set(RESERVED_TEST_IDS), names - set(RESERVED_TEST_IDS)

