"""The simulate stage on a fit.json: the chosen law along the test's load path, and its
neighbours a load cell's calibration apart (the fit's own)."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from slipwave.cli import main
from slipwave.io import read_dataset

SETUP = {"test_id": "small", "edge_reference": "frame",
         **{key: {"value": value, "source": "campaign table"} for key, value in {
             "length_mm": 80.0, "height_mm": 40.0, "width_mm": 10.0,
             "youngs_modulus_mpa": 7.0, "poisson_ratio": 0.48, "normal_load_n": 85.0,
             "speed_mm_s": 0.1, "machine_stiffness_n_mm": 40.0, "duration_s": 60.0,
             "loading_time_s": 5.0}.items()}}


def fit_json(folder, **changes):
    fit = {"test_id": "small", "setup": SETUP, "elements": 16, "load_calibration": 0.02,
           "detection": {"threshold": 8.0, "max_spike": 2, "max_duration": None,
                         "min_fall_rate": 1.2, "edge_convention": "auto"},
           "measured": {"slips": 3, "gross_slips": 2, "min_drop_n": 0.3},
           "chosen": "coulomb", "parameters": {"fs": 0.8, "fd": 0.6}, **changes}
    path = folder / "fit.json"
    path.write_text(json.dumps(fit))
    return path


def test_the_neighbours_lie_the_fits_load_calibration_apart(tmp_path):
    path = fit_json(tmp_path)
    assert main(["simulate", "--fit", str(path), "-o", str(tmp_path / "s.nc"),
                 "--scatter", str(tmp_path / "scatter.csv")]) == 0
    scatter = pd.read_csv(tmp_path / "scatter.csv")
    assert scatter["fs"].tolist() == pytest.approx([0.8 * 0.98, 0.8 * 1.02, 0.8, 0.8])
    assert scatter["fd"].tolist() == pytest.approx([0.6, 0.6, 0.6 * 0.98, 0.6 * 1.02])
    recording = read_dataset(tmp_path / "s.nc")
    assert recording.attrs["test_id"] == "small" and recording.sizes["time"] == 6000


def test_a_fit_made_with_other_detection_settings_is_refused(tmp_path, capsys):
    path = fit_json(tmp_path)
    assert main(["simulate", "--fit", str(path), "-o", str(tmp_path / "s.nc"),
                 "--threshold", "12"]) == 1
    err = capsys.readouterr().err
    assert "fit.json: fitted with the detection settings" in err and "fit the test again" in err
    assert not (tmp_path / "s.nc").exists()
