"""The spring-slider commands end to end on virtual records: ingest, fit, predict, report."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from slipwave.cli import main
from slipwave.io import read_dataset
from slipwave.solver.rate_state import RateState, steady_friction
from slipwave.solver.spring_slider import SpringSlider, simulate_spring_slider

LAW = RateState(a=0.01, b=0.015, dc=1e-6, mu0=0.35)
SMALL = ["--members", "2", "--design", "2", "--acquisitions", "0", "--samples", "200"]


def _mat(path: Path, stiffness: float, speed_um_s: float, seed: int) -> Path:
    """Three seconds of a virtual Colas bench saved as the Colas records are."""
    bench = SpringSlider(mass=0.0307, stiffness=stiffness, drive_speed=speed_um_s * 1e-6,
                         normal_load=0.0307 * 9.81)
    start = float(steady_friction(LAW, bench.drive_speed)) - 1e-3
    made = simulate_spring_slider(bench, LAW, duration=4.0, sample_rate=2000.0,
                                  initial_ratio=start).sel(time=slice(1.0, None))
    noise = np.random.default_rng(seed).normal(0.0, 0.002, made.sizes["time"])
    scipy.io.savemat(path, {"t": made.time.values[:, None] + 90.0,
                            "Fnorm": (made.friction_ratio.values + noise)[:, None]})
    return path


@pytest.fixture(scope="module")
def records(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("sliders")
    out = {}
    for name, stiffness, role in [("a", 1002.0, "fit"), ("b", 168.0, "fit"),
                                  ("c", 2254.0, "predict")]:
        mat = _mat(folder / f"{name}.mat", stiffness, 1100.0, seed=len(out))
        out[name] = folder / f"{name}.nc"
        assert main(["slider-ingest", str(mat), "-o", str(out[name]), "--record-id", name,
                     "--role", role, "--stiffness", str(stiffness), "--drive-speed", "1100",
                     "--mass", "30.7", "--window", "0.5"]) == 0
    return out


def test_ingest_stores_the_bench_and_the_role(records: dict[str, Path]) -> None:
    record = read_dataset(records["c"], "spring-slider record")
    assert record.attrs["role"] == "predict"
    assert record.attrs["stiffness_n_m"] == 2254.0
    assert record.attrs["drive_speed_m_s"] == pytest.approx(1.1e-3)
    assert record.attrs["normal_load_n"] == pytest.approx(0.0307 * 9.81)
    assert float(record.time[0]) == 0.0


@pytest.mark.parametrize("law", [[], ["--cutoff"]])
def test_fit_predict_and_report(records: dict[str, Path], tmp_path: Path,
                                law: list[str]) -> None:
    fit, posterior = tmp_path / "fit.json", tmp_path / "posterior.nc"
    assert main(["slider-fit", str(records["a"]), str(records["b"]), "-o", str(fit),
                 "--posterior", str(posterior), *SMALL, *law]) == 0
    result = json.loads(fit.read_text())
    assert result["records"] == ["a", "b"] and result["settings"]["cutoff"] == bool(law)
    assert result["guesses"] == (10 if law else 8)  # two design guesses per parameter
    assert ("cutoff_speed" in result["parameters"]) == bool(law)
    predictions = []
    for name in ("a", "c"):
        predictions.append(tmp_path / f"{name}.json")
        assert main(["slider-predict", str(records[name]), "--posterior", str(posterior),
                     "-o", str(predictions[-1]), "--draws", "2", "--members", "2"]) == 0
    held_out = json.loads(predictions[-1].read_text())
    assert held_out["role"] == "predict" and not held_out["fitted_on_it"]
    assert json.loads(predictions[0].read_text())["fitted_on_it"]
    page = tmp_path / "sliders.html"
    assert main(["slider-report", "--fit", str(fit), *map(str, predictions),
                 "-o", str(page)]) == 0
    html = page.read_text()
    assert "held out" in html and "regimes predicted right" in html
    assert 'src="data:image/png;base64,' in html
    assert ("cut-off speed vc" in html) == bool(law)


def test_the_fit_refuses_a_record_held_out(records: dict[str, Path], tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["slider-fit", str(records["a"]), str(records["c"]), "-o",
                 str(tmp_path / "f.json"), "--posterior", str(tmp_path / "p.nc"), *SMALL])
    assert code != 0
    assert "whose role is not fit" in capsys.readouterr().err
    assert not (tmp_path / "f.json").exists()


def test_predict_refuses_a_record_as_posterior(records: dict[str, Path], tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["slider-predict", str(records["a"]), "--posterior", str(records["b"]),
                 "-o", str(tmp_path / "x.json")])
    assert code != 0
    assert "not a spring-slider posterior" in capsys.readouterr().err


def test_check_config_reads_a_spring_slider_campaign(capsys: pytest.CaptureFixture[str],
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(Path(__file__).parents[1])
    assert main(["check-config", "config/colas.yaml"]) == 0
    assert "9 spring-slider records in config/colas.tsv (6 to fit)" in capsys.readouterr().out
