"""The Snakemake workflow, run for real in a copy of the repository."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from slipwave.bench.sawtooth import SawtoothBench, sawtooth_recording
from slipwave.campaign import read_campaign
from slipwave.compare import FOLLOWED, WHOLE_CONTACT
from slipwave.io import read_dataset

ROOT = Path(__file__).parents[1]
BIN = Path(sys.executable).parent
SNAKEMAKE = str(BIN / "snakemake")
# Rules call the `slipwave` command: the environment's bin folder goes first on PATH.
ENV = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
pytestmark = [pytest.mark.workflow, pytest.mark.slow]


# The map runs on a small grid here (the paper's 1572 cases are benchmarked in
# benchmarks/bench_map.py): two H/L, four f, 20 elements and its band from 10.
SMALL_MAP = ("map:\n  height_ratios: [0.25, 0.5]\n  frictions: [0.4, 1.0, 0.2]\n"
             "  elements: 20\n  band_elements: 10\n")
# and each test's fit is Coulomb's alone, a short search (the full fit is benchmarked), on
# the fit's default mesh, without the search again at twice it (tests/test_report.py runs
# it through to the page)
SMALL_FIT = ("fit:\n  laws: [coulomb]\n  elements: 80\n  members: 2\n  design: 4\n"
             "  refinements: 2\n  predictive_members: 3\n  mesh_check: false\n")
# and each filmed test's quasi-dynamic run on a coarse mesh (the converged 320 elements'
# time is benchmarked in benchmarks/bench_quasi_dynamic.py)
SMALL_WAVES = "simulate_waves:\n  elements: 40\n"
NO_FIT = "fit:\n  enabled: false\n"


@pytest.fixture
def workdir(tmp_path: Path) -> Path:
    for name in ["Snakefile", "workflow", "config", "profiles", "raw_data"]:
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, tmp_path / name)
        else:
            shutil.copy(source, tmp_path / name)
    with open(tmp_path / "config/config.yaml", "a") as config:
        config.write(SMALL_MAP + SMALL_FIT + SMALL_WAVES)
    return tmp_path


def snakemake(workdir: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([SNAKEMAKE, *args], cwd=workdir, capture_output=True, text=True,
                          timeout=600, check=False, env=ENV)


def test_dry_run_and_lint(workdir):
    dry = snakemake(workdir, "-n")
    assert dry.returncode == 0, dry.stderr
    assert "ingest" in dry.stdout + dry.stderr
    lint = snakemake(workdir, "--lint")
    assert lint.returncode == 0, lint.stdout + lint.stderr


def test_full_run_on_default_campaign(workdir):
    run = snakemake(workdir, "--cores", "2")
    assert run.returncode == 0, run.stderr
    ids = list(read_campaign(workdir / "config/tests.tsv")["test_id"])
    assert ids == ["hl050", "hl025", "hl075"]
    summary = pd.read_csv(workdir / "results/summary.csv").set_index("test_id")
    assert list(summary.index) == ids
    for test_id in ids:
        recording = read_dataset(workdir / f"results/{test_id}/recording.nc")
        assert recording.attrs["test_id"] == test_id
        events = pd.read_csv(workdir / f"results/{test_id}/events.csv", comment="#")
        truth = pd.read_csv(workdir / f"raw_data/bench/truth/{test_id}_events.csv")
        visible = truth[truth["visible"]]
        # the default campaign's detection finds every visible event, each test's
        # gross/partial threshold read off its own simulation's events (no hand-set value
        # in the table). The split is exact with the default fit (run-in chosen for hl050
        # and hl075); with this short Coulomb-only fit, hl075 (a run-in whose partial
        # slips that reach the far edge read DG/DD 1.02-1.05, its gross slips 1.6 and up)
        # may be simulated by a Coulomb law whose own partial slips set the threshold
        # below 1.02: its split follows the fitted law, every true gross slip still gross
        simulated = read_dataset(workdir / f"results/{test_id}/simulated/recording.nc")
        threshold = simulated.attrs["gross_edge_ratio"]
        assert f"threshold from the simulation: {threshold:.3g}" in (
            workdir / f"results/logs/detect/{test_id}.log").read_text()
        counts = events["kind"].value_counts().to_dict()
        truth_counts = visible["kind"].value_counts().to_dict()
        assert len(events) == len(visible)
        if test_id == "hl075":
            assert counts["gross_slip"] >= truth_counts["gross_slip"]
        else:
            assert counts == truth_counts
        assert summary.loc[test_id, "gross_slip_waves"] == (events["kind"] == "gross_slip").sum()
        page = (workdir / f"reports/{test_id}.html").read_text()
        assert f"Test {test_id}" in page
        assert "<h2>Events</h2>" in page and "<h2>Video</h2>" in page
        assert "<h2>Comparison</h2>" in page and "<h2>Space and time</h2>" in page
        assert (workdir / f"reports/{test_id}.pdf").read_bytes().startswith(b"%PDF")
        comparison = pd.read_csv(workdir / f"results/{test_id}/comparison.csv", comment="#")
        assert set(comparison["verdict"]) <= {"agrees", "differs", "not compared"}
        assert len(comparison) == 19
        # every filmed test's waves against its quasi-dynamic run's film's, rows judged
        waves_rows = comparison[comparison["feature"].str.endswith("(video vs quasi-dynamic)")]
        assert len(waves_rows) == 6
        verdicts = waves_rows.set_index("feature")["verdict"]
        assert verdicts[[WHOLE_CONTACT.name, FOLLOWED.name]].isin(["agrees", "differs"]).all()
        # the config's law slips in fronts of metres per second: its film shows slips the
        # tracker cannot follow, where the video (waves at 200 mm/s) follows most
        assert verdicts[FOLLOWED.name] == "differs"
        assert "The waves simulated quasi-dynamically" in page
        assert "filmed by the virtual bench's" in page
        # the page says the run's mesh, and that this test's convergence is not checked
        assert "The run has 40 elements along the contact" in page
        simulated = workdir / f"results/{test_id}/simulated"
        fronts = pd.read_csv(simulated / "fronts.csv", comment="#")
        assert len(fronts) > 0 and (fronts["speed"] > 0).all()
        filmed = pd.read_csv(simulated / "waves.csv", comment="#")
        film = read_dataset(simulated / "kymograph.nc")
        assert len(filmed) > 0 and film.sizes["time"] > 6000
        fit = json.loads((workdir / f"results/{test_id}/fit.json").read_text())
        assert fit["setup"]["edge_reference"] == "frame" and fit["chosen"] == "coulomb"
        for rule in ("ingest", "detect", "kymograph", "waves", "report", "fit", "simulate",
                     "simulate_waves", "compare"):
            assert (workdir / f"results/logs/{rule}/{test_id}.log").exists()
        kymo = read_dataset(workdir / f"results/{test_id}/kymograph.nc")
        assert kymo.sizes["time"] > 6900 and kymo["x"].attrs["units"] == "mm"
        fused = pd.read_csv(workdir / f"results/{test_id}/events_video.csv", comment="#")
        assert (fused["source"] != "video").sum() == len(events)
        clock = json.loads((workdir / f"results/{test_id}/clock.json").read_text())
        assert clock["pairs"] >= 30
    campaign = (workdir / "reports/campaign.html").read_text()
    assert all(f'href="./{test_id}.html"' in campaign for test_id in ids)
    assert (workdir / "reports/campaign.pdf").read_bytes().startswith(b"%PDF")
    fits = pd.read_csv(workdir / "results/fits.csv")
    assert list(fits["test_id"]) == ids and (workdir / "results/fits.png").stat().st_size > 1000
    # the behaviour map: its rows dealt to two jobs (the taller row to job 0), the map, its
    # figures with the tests on them
    whole = read_dataset(workdir / "results/map/map.nc")
    assert whole["height_ratio"].values.tolist() == [0.25, 0.5]
    assert whole["friction"].values.tolist() == [0.4, 0.6, 0.8, 1.0]
    assert set(whole["end"].values.ravel()) == {"gross sliding"}
    assert whole.attrs["contact_elements"] == 20 and whole.attrs["band_elements"] == 10
    coarse = read_dataset(workdir / "results/map/rows/10/job0-0.nc")
    assert coarse.attrs["contact_elements"] == 10 and "mesh_band" in whole
    assert len(pd.read_csv(workdir / "results/map/map.csv")) == 8
    for name in ("map.png", "zones.png", "legend.md"):
        assert (workdir / "results/map" / name).stat().st_size > 100
    for log in ("20/job0-0", "20/job1-0", "10/job0-0", "10/job1-0", "map", "map_figures"):
        assert (workdir / f"results/logs/map/{log}.log").exists()
    assert "3 tests placed" in (workdir / "results/logs/map/map_figures.log").read_text()
    assert "successions differ between 10 and 20 elements" in (
        workdir / "results/logs/map/map.log").read_text()
    assert "H/L 0.5: 100%" in (workdir / "results/logs/map/20/job0-0.log").read_text()


def test_column_map_from_config(workdir):
    csv = workdir / "raw_data" / "odd.csv"
    csv.write_text("Elapsed (ms),Shear force (N),Clamp force (N)\n0,1,-50\n10,2,-50\n")
    (workdir / "odd.tsv").write_text("test_id\tcsv\tframes\tcolumns\nodd\traw_data/odd.csv\t\t"
                                     "labview_en\n")
    (workdir / "odd.yaml").write_text("tests: odd.tsv\ncolumn_maps:\n  labview_en:\n"
                                      "    Elapsed: time\n    Shear force: T\n"
                                      "    Clamp force: N\n" + NO_FIT)
    # the recording alone: the rest of the workflow is the full run's
    run = snakemake(workdir, "results/odd/recording.nc", "--cores", "1", "--configfile",
                    "odd.yaml")
    assert run.returncode == 0, run.stderr
    assert read_dataset(workdir / "results/odd/recording.nc")["time"].values.tolist() == [0, 0.01]


def test_force_only_recording_runs_to_a_page_and_a_summary_row(workdir):
    """A spring-slider's record: time and T only (issue 13)."""
    saw = sawtooth_recording(SawtoothBench(), seed=3)
    lines = "".join(f"{a:.2f},{b:.4f}\n" for a, b in zip(saw["time"].values, saw["T"].values,
                                                        strict=True))
    (workdir / "raw_data" / "force.csv").write_text("time [s],T [N]\n" + lines)
    (workdir / "force.tsv").write_text("test_id\tcsv\nforce\traw_data/force.csv\n")
    (workdir / "force.yaml").write_text("tests: force.tsv\n" + NO_FIT)
    # the page and the summary (the map is the full run's); targets before --configfile,
    # which takes several files
    run = snakemake(workdir, "results/summary.csv", "reports/force.html", "--cores", "2",
                    "--configfile", "force.yaml")
    assert run.returncode == 0, run.stderr
    summary = pd.read_csv(workdir / "results/summary.csv").set_index("test_id")
    row = summary.loc["force"]
    assert row["unclassified_waves"] > 0 and row["unclassified_slip_s"] > 0
    assert row["partial_slip_waves"] == row["gross_slip_waves"] == 0
    assert row["partial_slip_s"] == row["gross_slip_s"] == 0
    assert np.isnan(row["static_ratio_mean"]) and "no usable N channel" in row["warnings"]
    page = (workdir / "reports/force.html").read_text()
    assert "T drops of unknown kind" in page and "No gross slip is known" in page


@pytest.mark.parametrize(
    ("config", "table", "message"),
    [
        ("tests: t.tsv\ncolumn_maps:\n  x:\n    Foo: Tangential\n", None,
         "'Tangential' is not one of"),
        ("tests: t.tsv\nspeed: 3\n", None, "Additional properties are not allowed"),
        ("tests: t.tsv\n", "test_id\tcsv\nbad id\tx.csv\n", "does not match"),
        ("tests: t.tsv\n", "test_id\tcsv\tframes\tcolumns\na\tx.csv\t\tnope\n",
         "column map 'nope' is not in the config's column_maps"),
        ("tests: missing.tsv\n", None, "missing.tsv: campaign table not found"),
        ("tests: t.tsv\ndetection:\n  thresold: 5\n", None,
         "Additional properties are not allowed ('thresold' was unexpected)"),
        ("tests: t.tsv\n", "test_id\tcsv\tedge_reference\na\tx.csv\tceiling\n",
         "'ceiling' does not match"),
    ],
    ids=["bad-channel", "unknown-key", "bad-test-id", "unknown-map", "no-table",
         "unknown-detection-key", "bad-edge-reference"],
)
def test_wrong_config_fails_before_any_job(workdir, config, table, message):
    (workdir / "bad.yaml").write_text(config)
    (workdir / "t.tsv").write_text(table or "test_id\tcsv\na\traw_data/bench/hl050.csv\n")
    run = snakemake(workdir, "--cores", "1", "--configfile", "bad.yaml")
    assert run.returncode != 0
    assert message in run.stdout + run.stderr
    assert not (workdir / "results").exists()
