"""The simulate stage on a fit.json: the chosen law along the test's load path, and its
neighbours a load cell's calibration apart (the fit's own)."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from fuzzing import valid_fit
from slipwave.cli import main
from slipwave.io import read_dataset


def fit_json(folder, **changes):
    path = folder / "fit.json"
    path.write_text(json.dumps(valid_fit(**changes)))
    return path


def test_the_neighbours_lie_the_fits_load_calibration_apart(tmp_path):
    path = fit_json(tmp_path)
    assert main(["simulate", "--fit", str(path), "-o", str(tmp_path / "s.nc"),
                 "--scatter", str(tmp_path / "scatter.csv")]) == 0
    scatter = pd.read_csv(tmp_path / "scatter.csv", comment="#")
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
