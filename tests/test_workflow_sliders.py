"""The spring-slider campaign through Snakemake: a reduced Colas campaign, run for real."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from slipwave.io import read_dataset

ROOT = Path(__file__).parents[1]
SHARED = ROOT.parent / "shared"
BIN = Path(sys.executable).parent
ENV = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
pytestmark = [
    pytest.mark.workflow, pytest.mark.slow,
    pytest.mark.skipif(not (SHARED / "data" / "colas2019").is_dir(),
                       reason=f"{SHARED / 'data' / 'colas2019'} is not there"),
]

# two short records fitted, one held out, a small search: the full campaign is
# config/colas.tsv with the schema's settings (benchmarks/bench_colas.py)
REDUCED = """record_id\tmat\trole\tstiffness_n_m\tdrive_speed_um_s\tmass_g\tnormal_load_n\twindow_s
k168_v1100\t../shared/data/colas2019/k168Nm_v1100.mat\tfit\t168\t1100\t30.7\t\t1
k1002_v4300\t../shared/data/colas2019/k1002Nm_v4300.mat\tfit\t1002\t4300\t30.7\t\t0.5
k2254_v4300\t../shared/data/colas2019/k2254Nm_v4300.mat\tpredict\t2254\t4300\t30.7\t\t0.5
"""
SMALL = ("kind: spring_slider\nsliders:\n  records: config/reduced.tsv\n  members: 2\n"
         "  design: 2\n  acquisitions: 0\n  samples: 200\n  draws: 2\n")


@pytest.fixture
def workdir(tmp_path: Path) -> Path:
    work = tmp_path / "repo"
    work.mkdir()
    for name in ["Snakefile", "workflow", "config", "profiles"]:
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, work / name)
        else:
            shutil.copy(source, work / name)
    (tmp_path / "shared").symlink_to(SHARED)  # ../shared beside the copy, as beside the repo
    (work / "config/reduced.tsv").write_text(REDUCED)
    (work / "config/reduced.yaml").write_text(SMALL)
    return work


def test_the_reduced_colas_campaign_fits_two_records_and_predicts_the_third(workdir):
    run = subprocess.run([str(BIN / "snakemake"), "--cores", "2", "--configfile",
                          "config/reduced.yaml"], cwd=workdir, capture_output=True, text=True,
                         timeout=900, check=False, env=ENV)
    assert run.returncode == 0, run.stderr[-3000:]
    fit = json.loads((workdir / "results/sliders/fit.json").read_text())
    assert fit["records"] == ["k168_v1100", "k1002_v4300"]  # the held-out record is not read
    assert fit["guesses"] == 8  # the sliders section's settings, not the slab fit's
    assert fit["settings"]["members"] == 2
    for name in ("a", "b", "dc", "mu0"):
        low, high = fit["parameters"][name]["low"], fit["parameters"][name]["high"]
        assert low <= fit["parameters"][name]["median"] <= high
    record = read_dataset(workdir / "results/sliders/k2254_v4300/record.nc")
    assert record.attrs["role"] == "predict"
    assert record.attrs["normal_load_n"] == pytest.approx(0.0307 * 9.81)
    prediction = json.loads((workdir / "results/sliders/k2254_v4300/prediction.json").read_text())
    assert prediction["role"] == "predict" and not prediction["fitted_on_it"]
    assert prediction["regime"]["measured"] in ("stick-slip", "mixed", "sliding")
    page = (workdir / "reports/sliders.html").read_text()
    assert "k2254_v4300" in page and "held out" in page
    assert "regimes predicted right" in page
