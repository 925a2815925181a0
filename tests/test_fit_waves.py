"""The fit of a filmed test's rate-and-state law: its statistic, likelihood and search."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from threadpoolctl import threadpool_limits

from fuzzing import valid_fit
from slipwave import fit_waves
from slipwave.cli import main
from slipwave.errors import SlipwaveError
from slipwave.identity import stamp
from slipwave.io import read_dataset, read_table, write_dataset, write_table
from slipwave.report import render_test_page, video_summary
from slipwave.setup import Setting, TestSetup
from slipwave.simulate_waves import WavesRun, law_text, rate_state_law, simulate_waves
from slipwave.video import ClockFit

# A slab of the bench's (H 40 mm, 85 N, 0.048 mm/s) under a law of slow fronts: slips every
# 12-13 s from about 58 s after the drive starts, fronts the camera follows
LAW = {"a": 0.01, "b": 0.04, "dc_um": 80.0, "mu0": 0.9, "v0_um_s": 1.0}
TRUTH = np.array([0.01, 0.03, np.log10(80e-6), 0.9])


def setup_of(duration: float) -> TestSetup:
    values = {"length_mm": 80.0, "height_mm": 40.0, "width_mm": 10.0,
              "youngs_modulus_mpa": 7.0, "poisson_ratio": 0.48, "normal_load_n": 85.0,
              "speed_mm_s": 0.048, "machine_stiffness_n_mm": 40.0, "duration_s": duration,
              "loading_time_s": 10.0}
    return TestSetup("slow", {k: Setting(v, "test") for k, v in values.items()}, "frame")


def card(run: xr.Dataset, setup: TestSetup) -> xr.Dataset:
    from slipwave.solver.signals import quasi_dynamic_signals

    recording = quasi_dynamic_signals(run, loading=setup["loading_time_s"],
                                      duration=setup["duration_s"], sample_rate=100.0)
    recording.attrs["test_id"] = setup.test_id
    return recording


@pytest.fixture(scope="module")
def made() -> tuple[TestSetup, WavesRun]:
    """A test made by the stage at 40 elements (the run kept whole), filmed."""
    setup = setup_of(230.0)
    return setup, simulate_waves(setup, rate_state_law(LAW), elements=40, field_rate=25.0,
                                 sample_rate=100.0, frame_rate=25.0)


def video_waves(run: WavesRun) -> pd.DataFrame:
    """The film's waves as the waves stage writes a video's: the film's clock is the card's."""
    return run.waves.assign(t_start_card=run.waves["t_start"])


@pytest.fixture(scope="module")
def observed(made: tuple[TestSetup, WavesRun]) -> fit_waves.FilmedTest:
    setup, run = made
    return fit_waves.filmed_test(setup, card(run.run, setup), video_waves(run), frame_rate=25.0)


def test_a_filmed_test_is_cut_into_windows_of_three_recurrences(observed):
    assert observed.windows >= 2
    assert 30.0 < observed.window < 45.0  # three recurrences of 12-13 s
    peak, drop, recurrence = observed.observed
    assert 0.7 < peak < 0.85 and 0.02 < drop < 0.1
    assert np.exp(recurrence) == pytest.approx(observed.window / 3, rel=0.2)
    assert observed.followed >= 2 and 100.0 < np.median(observed.speeds) < 1000.0


@pytest.mark.slow
def test_the_likelihood_prefers_the_law_that_made_the_test(observed):
    # the same mesh and the camera's noise of another seed: the law that made it against
    # one of D_c three times shorter (faster fronts, shorter cycle) and one weakening less
    runs = {name: fit_waves.simulate_guess(observed, fit_waves.law_at(point), elements=40,
                                           members=3, seed=7)
            for name, point in {"truth": TRUTH,
                                "short dc": TRUTH - [0.0, 0.0, np.log10(3.0), 0.0],
                                "less weakening": TRUTH - [0.0, 0.01, 0.0, 0.0]}.items()}
    at = {name: fit_waves.loglik(observed, run) for name, run in runs.items()}
    assert np.isfinite(at["truth"])
    assert at["truth"] > at["short dc"] + 3.0 and at["truth"] > at["less weakening"] + 3.0
    # the emulator's likelihood, given the runs' own features exactly, orders them alike
    emulated = fit_waves.emulated_loglik(observed, fit_waves.RunScatter.of(list(runs.values())),
                                         fit_waves.mesh_error(None, None), members=3)
    features = np.array([fit_waves.run_features(run) for run in runs.values()])
    # a run the camera followed too few waves of has no speed: it stands at the fastest
    # followed, as the emulator takes it where too few runs have one
    features = np.where(np.isnan(features), fit_waves.ABSENT_FEATURES, features)
    truth, short, weaker = emulated(features, np.zeros_like(features))
    assert truth > short + 3.0 and truth > weaker + 3.0


def test_a_failed_run_or_a_run_without_slips_has_no_likelihood(observed):
    assert fit_waves.loglik(observed, None) == -np.inf
    empty = fit_waves.Simulated(np.full((3, 3), np.nan), 0, 0, np.zeros(0))
    assert fit_waves.loglik(observed, empty) == -np.inf


def test_windows_like_the_test_s_score_higher_than_shifted_ones(observed):
    rng = np.random.default_rng(0)
    spread = np.asarray(observed.spread) + 1e-3
    like = np.asarray(observed.observed) + rng.normal(0.0, 1.0, (6, 3)) * spread
    speeds = np.asarray(observed.speeds)
    alike = fit_waves.Simulated(like, observed.waves, observed.followed, speeds)
    higher = fit_waves.Simulated(like + np.array([0.05, 0.0, 0.0]), observed.waves,
                                 observed.followed, speeds)
    faster = fit_waves.Simulated(like, observed.waves, observed.followed, 3.0 * speeds)
    # none followed: taken at the fastest speed the frames follow, far above these
    unfollowed = fit_waves.Simulated(like, observed.waves, 0, np.zeros(0))
    best = fit_waves.loglik(observed, alike)
    for other in (higher, faster, unfollowed):
        assert fit_waves.loglik(observed, other) < best - 5.0


def test_a_test_with_too_few_slips_is_refused_with_its_name():
    setup = setup_of(60.0)
    time = np.arange(0.0, 60.0, 0.01)
    recording = xr.Dataset({"T": ("time", 0.5 * time), "N": ("time", np.full(time.size, -85.0)),
                            "DG": ("time", 0.001 * time), "DD": ("time", 0.001 * time),
                            "DT": ("time", 0.048 * time)}, coords={"time": time},
                           attrs={"test_id": "steady"})
    with pytest.raises(SlipwaveError, match="test 'steady': 0 slips"):
        fit_waves.filmed_test(setup, recording, pd.DataFrame(), frame_rate=25.0)


# the smallest search that runs: three guesses per parameter at 20 elements, none after
SMALL_SEARCH = ["--elements", "20", "--members", "2", "--design", "3", "--refinements", "0",
                "--samples", "200", "--mesh-checks", "0"]


@pytest.fixture(scope="module")
def products(made: tuple[TestSetup, WavesRun], tmp_path_factory: pytest.TempPathFactory
             ) -> dict[str, Path]:
    """The made test's products as the workflow's stages write them, under one identity."""
    setup, run = made
    folder = tmp_path_factory.mktemp("filmed")
    identity = {"test_id": "slow", "recording_sha256": "1" * 64}
    paths = {name: folder / name for name in ("fit.json", "recording.nc", "kymograph.nc",
                                              "waves.csv")}
    paths["fit.json"].write_text(json.dumps(valid_fit(setup=setup.to_dict(), **identity)))
    recording = card(run.run, setup)
    stamp(recording.attrs, "recording", identity)
    write_dataset(recording, paths["recording.nc"])
    film = run.film.copy()
    stamp(film.attrs, "kymograph", identity)
    write_dataset(film, paths["kymograph.nc"])
    write_table(video_waves(run), paths["waves.csv"], identity)
    return paths


def fit_command(products: dict[str, Path], output: Path, *options: str) -> list[str]:
    return ["fit-waves", "--fit", str(products["fit.json"]), "--recording",
            str(products["recording.nc"]), "--waves", str(products["waves.csv"]),
            "--kymograph", str(products["kymograph.nc"]), *options, "-o", str(output)]


@pytest.mark.slow
def test_the_command_writes_the_fit_and_the_stage_runs_the_test_under_it(
        products, tmp_path, capsys):
    fitted_path = tmp_path / "fit_waves.json"
    assert main(fit_command(products, fitted_path, *SMALL_SEARCH)) == 0
    fitted = fit_waves.read_waves_fit(fitted_path)
    assert (fitted["test_id"], fitted["recording_sha256"]) == ("slow", "1" * 64)
    assert fitted["guesses"] == 12 and fitted["settings"]["elements"] == 20
    assert fitted["test"]["windows"] >= 2 and fitted["test"]["followed"] >= 2
    parameters = fitted["parameters"]
    for name, (low, high) in {"a": (0.005, 0.02), "b_minus_a": (0.005, 0.035),
                              "dc_um": (10.0, 200.0), "mu0": (0.6, 1.2)}.items():
        interval = parameters[name]
        assert low <= interval["low"] <= interval["value"] <= interval["high"] <= high
    # the law run is the posterior's medians (b: a's plus b - a's; D_c's is log10 D_c's,
    # which differs from D_c's own by the two middle samples' mean taken before or after)
    law = fitted["law"]
    for name in ("a", "dc_um", "mu0"):
        assert law[name] == pytest.approx(parameters[name]["value"], rel=1e-3)
    assert law["b"] == pytest.approx(parameters["a"]["value"]
                                     + parameters["b_minus_a"]["value"], rel=1e-9)
    assert law["v0_um_s"] == 1.0
    out = capsys.readouterr().out
    assert "7 windows" in out or "windows of" in out
    assert f"-> {fitted_path}: a " in out
    # the quasi-dynamic stage under that law
    stage = ["simulate-waves", "--fit", str(products["fit.json"]), "--kymograph",
             str(products["kymograph.nc"]), "--elements", "20", "--sample-rate", "20",
             "-o", str(tmp_path / "qd.nc"), "--film", str(tmp_path / "film.nc"),
             "--waves", str(tmp_path / "waves.csv"), "--fronts", str(tmp_path / "fronts.csv")]
    assert main([*stage, "--law-fit", str(fitted_path)]) == 0
    run = read_dataset(tmp_path / "qd.nc", "quasi-dynamic run")
    assert run.attrs["law_text"] == law_text(rate_state_law(law))
    # the test's page lists the fitted intervals and says the run is the fitted law's
    film = read_dataset(products["kymograph.nc"], "kymograph")
    simulated = {"quasi_dynamic": run, "simulated_waves": read_table(tmp_path / "waves.csv"),
                 "simulated_fronts": read_table(tmp_path / "fronts.csv"),
                 "simulated_film": read_dataset(tmp_path / "film.nc", "kymograph")}
    clock = ClockFit(offset=0.0, rate=1.0, residual=0.0, method="the film's own", pairs=0)
    waves = read_table(products["waves.csv"])
    video = video_summary(film, waves, clock, **simulated, waves_fit=fitted)
    page = render_test_page(read_dataset(products["recording.nc"]), video=video)
    assert "The rate-and-state law fitted on this test" in page
    assert f"under the fitted law at its medians ({run.attrs['law_text']})" in page
    dc = parameters["dc_um"]
    assert f"[{dc['low']:.3g}, {dc['high']:.3g}]" in page and "which no fit has set" not in page
    unfitted = render_test_page(read_dataset(products["recording.nc"]),
                                video=video_summary(film, waves, clock, **simulated))
    assert "which no fit has set" in unfitted and "fitted on this test" not in unfitted
    # fitted at another mesh than the run's: the page says a differing row may be the mesh's
    assert "moved with the mesh" not in page
    coarser = {**fitted, "settings": {**fitted["settings"], "elements": 10}}
    other_mesh = render_test_page(read_dataset(products["recording.nc"]),
                                  video=video_summary(film, waves, clock, **simulated,
                                                      waves_fit=coarser))
    assert "fitted on runs of 10 elements" in other_mesh and "moved with the mesh" in other_mesh
    other_law = {**fitted, "law": {**law, "a": 2.0 * law["a"]}}
    with pytest.raises(SlipwaveError, match="not the fitted"):
        video_summary(film, waves, clock, **simulated, waves_fit=other_law)
    # the law given twice, or another test's fit: refused, naming why
    assert main([*stage, "--law-fit", str(fitted_path), "--a", "0.01"]) == 1
    assert "--law-fit gives the law" in capsys.readouterr().err
    other = tmp_path / "other.json"
    other.write_text(json.dumps({**json.loads(fitted_path.read_text()), "test_id": "fast"}))
    assert main([*stage, "--law-fit", str(other)]) == 1
    assert "fast" in capsys.readouterr().err


def test_a_file_that_is_not_a_fit_of_waves_is_named_with_what_it_lacks(tmp_path):
    broken = tmp_path / "fit_waves.json"
    broken.write_text(json.dumps({"test_id": "slow", "recording_sha256": "1" * 64}))
    with pytest.raises(SlipwaveError, match=r"fit_waves\.json: the top level: 'parameters' is "
                                            r"a required property"):
        fit_waves.read_waves_fit(broken)


def test_a_waves_table_of_another_test_is_refused_before_any_run(products, tmp_path, capsys):
    other = tmp_path / "waves.csv"
    other.write_text(products["waves.csv"].read_text().replace("# test_id: slow",
                                                               "# test_id: fast"))
    argv = fit_command({**products, "waves.csv": other}, tmp_path / "out.json", *SMALL_SEARCH)
    assert main(argv) == 1
    assert "fast" in capsys.readouterr().err and not (tmp_path / "out.json").exists()


@pytest.mark.slow
def test_a_guess_s_run_is_the_same_whatever_the_caller_s_blas_threads(observed):
    # a chaotic cycle turns the last bits of a product summed on two threads into another
    # run: a workflow's job (Snakemake sets BLAS's threads to the job's) would fit
    # otherwise than the same command in a shell
    law = fit_waves.law_at(TRUTH)

    def features(run: fit_waves.Simulated | None) -> list:
        assert run is not None
        return [run.windows.round(12).tolist(), np.sort(run.speeds).round(9).tolist()]

    ran = {}
    for threads in (1, 2):
        with threadpool_limits(limits=threads):
            ran[threads] = features(fit_waves.simulate_guess(observed, law, elements=80,
                                                             members=2))
            unpinned = features(fit_waves._simulated(observed, law, elements=80, members=2,
                                                     seed=0))
        ran[f"unpinned {threads}"] = unpinned
    assert ran[1] == ran[2] == ran["unpinned 1"]
    if ran["unpinned 2"] == ran["unpinned 1"]:
        pytest.skip("this machine's BLAS sums these products alike on one and two threads")
