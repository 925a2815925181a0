"""The simulate-waves stage: a filmed test run quasi-dynamically, its waves in the video's
columns on the test's clock, and what it refuses."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from fuzzing import valid_fit
from slipwave.cli import main
from slipwave.io import read_dataset, read_table
from slipwave.io.tables import WAVE_COLUMNS
from slipwave.plot import WAVE_COLOURS, plot_simulated_fronts
from slipwave.setup import TestSetup
from slipwave.simulate_waves import rate_state_law, simulate_waves

LAW = {"a": 0.01, "b": 0.015, "dc_um": 2.0, "mu0": 0.9, "v0_um_s": 1.0}


@pytest.fixture(scope="module")
def ran() -> tuple[TestSetup, xr.Dataset, pd.DataFrame]:
    setup = TestSetup.from_dict(valid_fit()["setup"])
    run, waves = simulate_waves(setup, rate_state_law(LAW), elements=40, field_rate=10.0,
                                sample_rate=20.0)
    return setup, run, waves


def test_a_test_runs_on_its_own_clock(ran: tuple[TestSetup, xr.Dataset, pd.DataFrame]
                                      ) -> None:
    setup, run, waves = ran
    loading = setup["loading_time_s"]
    assert float(run["time"][0]) == loading
    assert float(run["time"][-1]) == pytest.approx(setup["duration_s"])
    assert float(run["field_time"][0]) == loading
    # the waves of the drive (its first slips come some 20 s in at 0.1 mm/s)
    assert len(waves) >= 3
    assert (waves["t_start"] > loading + 10).all()
    assert np.all(run["crossing_time"].values >= loading)
    assert np.isfinite(waves["speed"]).all() and (waves["speed"] > 0).all()


def test_the_command_writes_the_run_and_its_waves_under_the_test_s_identity(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fit_path = tmp_path / "fit.json"
    fit_path.write_text(json.dumps(valid_fit()))
    run_path, waves_path = tmp_path / "qd.nc", tmp_path / "waves.csv"
    assert main(["simulate-waves", "--fit", str(fit_path), "--elements", "40",
                 "--sample-rate", "20", "-o", str(run_path), "--waves", str(waves_path)]) == 0
    run = read_dataset(run_path, "quasi-dynamic run")
    assert run.attrs["test_id"] == "small" and run.attrs["recording_sha256"] == "0" * 64
    waves = read_table(waves_path)
    assert tuple(waves.columns) == WAVE_COLUMNS and len(waves) >= 3
    assert waves.attrs["test_id"] == "small"
    assert "waves, median front speed" in capsys.readouterr().out


@pytest.mark.parametrize(("option", "value", "said"), [
    ("--a", "0", "simulate_waves.a"),
    ("--dc-um", "-2", "simulate_waves.dc_um"),
    ("--elements", "5", "simulate_waves.elements"),
])
def test_a_law_or_mesh_out_of_the_config_s_bounds_is_refused_before_anything_runs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], option: str, value: str,
        said: str) -> None:
    fit_path = tmp_path / "fit.json"
    fit_path.write_text(json.dumps(valid_fit()))
    with pytest.raises(SystemExit) as stop:
        main(["simulate-waves", "--fit", str(fit_path), option, value, "-o",
              str(tmp_path / "qd.nc"), "--waves", str(tmp_path / "waves.csv")])
    assert stop.value.code == 2
    assert said in capsys.readouterr().err
    assert sorted(path.name for path in tmp_path.iterdir()) == ["fit.json"]


def test_a_fit_without_its_setup_is_named(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    fit = valid_fit()
    del fit["setup"]
    fit_path = tmp_path / "fit.json"
    fit_path.write_text(json.dumps(fit))
    status = main(["simulate-waves", "--fit", str(fit_path), "--elements", "40", "-o",
                   str(tmp_path / "qd.nc"), "--waves", str(tmp_path / "waves.csv")])
    err = capsys.readouterr().err
    assert status == 1 and "fit.json" in err and "setup" in err
    assert sorted(path.name for path in tmp_path.iterdir()) == ["fit.json"]


def test_the_fronts_figure_draws_each_wave_in_its_direction_s_colour(
        ran: tuple[TestSetup, xr.Dataset, pd.DataFrame]) -> None:
    _, run, waves = ran
    whole, first = plot_simulated_fronts(run, waves).axes
    paths = [line for line in whole.get_lines() if line.get_linestyle() == "-"]
    assert len(paths) == len(waves)
    assert [line.get_color() for line in paths] == [WAVE_COLOURS[d] for d in waves["direction"]]
    assert "m/s" in first.get_title(loc="left")
    # the first wave's arrivals span its extent, within a few of its milliseconds
    arrivals = first.get_lines()[0].get_xdata()
    assert arrivals.min() >= 0.0 and arrivals.max() <= 1e3 * (
        waves["t_end"].iloc[0] - waves["t_start"].iloc[0]) + 1e-6
