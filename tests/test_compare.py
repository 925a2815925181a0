"""The simulate and compare stages: a test run again in the measurement's shape, and judged."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from slipwave.bench.generate import BenchTest, simulate_test
from slipwave.compare import (
    COMPARISON_COLUMNS,
    EVENT_FEATURES,
    FIRST_WAVE_START,
    FOLLOWED,
    ORIGIN,
    SCATTER_STEP,
    WAVE_FEATURES,
    WAVE_SPEED,
    WAVE_SPEED_SPREAD,
    WHOLE_CONTACT,
    compare_test,
    compare_waves,
    event_features,
    first_wave,
    place_on_map,
    verdict_counts,
)
from slipwave.errors import SlipwaveError, SolverError
from slipwave.events import detect_events
from slipwave.io import CHANNELS, read_table, write_table
from slipwave.setup import read_test_setup
from slipwave.simulate import left_out_neighbours, replay_test, sequence_scatter
from slipwave.solver import Coulomb

CELLS = {"test_id": "v", "youngs_modulus_mpa": "7", "poisson_ratio": "0.48",
         "edge_reference": "frame"}


@pytest.fixture(scope="module")
def test_and_replay():
    # 110 s: two gross slips, so that their recurrence is measured and compared
    spec = BenchTest("v", elements=24, duration=110.0, video="none", fs=0.9, fd=0.6,
                     fs_final=None)
    result = simulate_test(spec, seed=3)
    setup = read_test_setup(result.recording, CELLS)
    return result, setup, replay_test(setup, Coulomb(fs=0.9, fd=0.6), min_drop=0.3, elements=24)


def test_replay_is_a_recording_with_its_contact_history(test_and_replay):
    result, _, replay = test_and_replay
    recording = replay.recording
    assert set(CHANNELS) - {"time"} <= set(recording.data_vars)
    assert recording.sizes["time"] == result.recording.sizes["time"]
    assert recording["T"].attrs["units"] == "N" and recording["time"].attrs["units"] == "s"
    # the threshold lies between the simulated partial slips' edge ratios and the gross
    # slips' (a gross slip moves the far edge at least as much as the near one)
    simulated = detect_events(recording, min_drop=0.3, edge_convention="x_axis",
                              gross_edge_ratio=recording.attrs["gross_edge_ratio"])
    gross = replay.simulation["wave"].values == "gross"
    assert (simulated["kind"] == "gross_slip").sum() == (
        gross & (replay.simulation["phase"].values == "tangential")).sum()
    contact = replay.contact
    assert contact["state"].dims == ("time", "x") and set(np.unique(contact["state"])) <= {
        0, 1, 2}
    assert np.all(np.diff(contact["time"].values) > 0)
    assert contact["intensity"].dims == ("time", "x_image")
    assert 0 <= float(contact["intensity"].min()) < float(contact["intensity"].max()) <= 255
    assert contact["frame"].shape[0] == 4 and contact["frame"].dtype == np.uint8
    assert list(contact["frame_label"].values)[-1] == "after the gross slip"


def test_replay_in_the_flat_reference_subtracts_the_travel(test_and_replay):
    _, setup, replay = test_and_replay
    flat = type(setup)(setup.test_id, setup.settings, "flat")
    again = replay_test(flat, Coulomb(fs=0.9, fd=0.6), min_drop=0.3, elements=24, kymograph=False)
    assert np.allclose(again.recording["DG"] + again.recording["DT"], replay.recording["DG"])
    assert "intensity" not in again.contact


def test_a_test_against_its_own_law_agrees_on_every_compared_feature(test_and_replay):
    result, _, replay = test_and_replay
    measured = detect_events(result.recording,
                             gross_edge_ratio=replay.recording.attrs["gross_edge_ratio"])
    table = compare_test(measured, replay.recording, replay.simulation, min_drop=0.3)
    assert list(table.columns) == list(COMPARISON_COLUMNS)
    counts = verdict_counts(table)
    assert counts["differs"] == 0, table[table["verdict"] == "differs"]
    assert counts["agrees"] >= 10
    assert set(table.loc[table["verdict"] == "not compared", "note"]) == {"no video"}


def test_a_wrong_law_is_flagged(test_and_replay):
    result, setup, _ = test_and_replay
    wrong = replay_test(setup, Coulomb(fs=1.3, fd=0.45), min_drop=0.3, elements=24, kymograph=False)
    measured = detect_events(result.recording,
                             gross_edge_ratio=wrong.recording.attrs["gross_edge_ratio"])
    table = compare_test(measured, wrong.recording, wrong.simulation, min_drop=0.3)
    verdicts = table.set_index("feature")["verdict"]
    assert verdicts["T/|N| at gross slips, after (dynamic)"] == "differs"
    assert verdict_counts(table)["differs"] >= 3


def test_the_law_s_neighbours_give_the_simulation_s_own_scatter(test_and_replay):
    result, setup, replay = test_and_replay
    threshold = replay.recording.attrs["gross_edge_ratio"]
    scatter = sequence_scatter(setup, Coulomb(fs=0.9, fd=0.6), min_drop=0.3, elements=24,
                               gross_edge_ratio=threshold)
    assert np.allclose(scatter[["fs", "fd"]], [
        [0.9 * (1 - SCATTER_STEP), 0.6], [0.9 * (1 + SCATTER_STEP), 0.6],
        [0.9, 0.6 * (1 - SCATTER_STEP)], [0.9, 0.6 * (1 + SCATTER_STEP)]])
    assert {feature.name for feature in EVENT_FEATURES} < set(scatter.columns)
    assert (scatter["gross slips"] > 0).all()
    measured = detect_events(result.recording, gross_edge_ratio=threshold)
    alone = compare_test(measured, replay.recording, replay.simulation, min_drop=0.3)
    table = compare_test(measured, replay.recording, replay.simulation, min_drop=0.3,
                         scatter=scatter)
    compared = table["verdict"] != "not compared"
    assert (table.loc[compared, "scatter"] >= 0).all()
    assert (table.loc[compared, "tolerance"] >= alone.loc[compared, "tolerance"] - 1e-12).all()
    assert verdict_counts(table)["differs"] == 0


def test_a_neighbour_the_solver_does_not_follow_is_left_out_and_named(test_and_replay,
                                                                      monkeypatch, tmp_path):
    _, setup, replay = test_and_replay
    follows = type(setup).simulate

    def stops_above_fd(self, friction, elements, **keywords):  # as a law past a cycle
        if friction.dynamic > 0.6:
            raise SlipwaveError("the solver failed") from SolverError(
                438, float("nan"), "no convergence after 6 sub-step levels")
        return follows(self, friction, elements, **keywords)

    monkeypatch.setattr(type(setup), "simulate", stops_above_fd)
    scatter = sequence_scatter(setup, Coulomb(fs=0.9, fd=0.6), min_drop=0.3, elements=24,
                               gross_edge_ratio=replay.recording.attrs["gross_edge_ratio"])
    assert np.allclose(scatter[["fs", "fd"]], [
        [0.9 * (1 - SCATTER_STEP), 0.6], [0.9 * (1 + SCATTER_STEP), 0.6],
        [0.9, 0.6 * (1 - SCATTER_STEP)]])
    assert scatter.attrs["left_out"] == (
        f"fs 0.9, fd {0.6 * (1 + SCATTER_STEP):.6g} (stopped at step 438: no convergence "
        "after 6 sub-step levels (relative residual nan))")
    assert {feature.name for feature in EVENT_FEATURES} < set(scatter.columns)
    # and the comparison finds which, from the table as written (6 figures)
    written = tmp_path / "scatter.csv"
    write_table(scatter, written)
    assert left_out_neighbours(Coulomb(fs=0.9, fd=0.6), SCATTER_STEP, read_table(written)) == [
        {"fs": 0.9, "fd": 0.6 * (1 + SCATTER_STEP)}]


def test_a_difference_within_the_law_s_scatter_agrees_and_says_so(test_and_replay):
    result, setup, _ = test_and_replay
    wrong = replay_test(setup, Coulomb(fs=1.3, fd=0.45), min_drop=0.3, elements=24, kymograph=False)
    measured = detect_events(result.recording,
                             gross_edge_ratio=wrong.recording.attrs["gross_edge_ratio"])
    dynamic = "T/|N| at gross slips, after (dynamic)"
    alone = compare_test(measured, wrong.recording, wrong.simulation, min_drop=0.3)
    difference = float(alone.set_index("feature").loc[dynamic, "difference"])
    # neighbours whose T/|N| after gross slips spreads as far as the difference
    simulated = event_features(alone.attrs["simulated_events"])[dynamic]
    scatter = pd.DataFrame({dynamic: [simulated - difference, simulated + difference]})
    table = compare_test(measured, wrong.recording, wrong.simulation, min_drop=0.3,
                         scatter=scatter).set_index("feature")
    assert alone.set_index("feature").loc[dynamic, "verdict"] == "differs"
    assert table.loc[dynamic, "verdict"] == "agrees"
    assert table.loc[dynamic, "note"] == "within the law's own scatter"
    others = table.index != dynamic
    assert np.allclose(table.loc[others, "tolerance"].astype(float),
                       alone.set_index("feature").loc[others, "tolerance"].astype(float),
                       equal_nan=True)


def test_the_first_wave_is_the_first_the_video_could_see(test_and_replay):
    result, _, replay = test_and_replay
    simulation = replay.simulation
    x, order = simulation["x"].values, simulation["cascade_round"].values
    origin, way = first_wave(simulation)
    assert way in ("left_to_right", "right_to_left")
    waves = np.flatnonzero((simulation["phase"].values == "tangential")
                           & (simulation["wave"].values != "none"))
    spans = [np.ptp(x[order[k] >= 0]) / np.ptp(x) for k in waves]
    seen = next(k for k, span in zip(waves, spans, strict=True) if span >= 0.25)
    assert spans[0] < 0.25 < spans[list(waves).index(seen)]  # an edge's slip comes first
    assert origin != first_wave(simulation, min_extent=0.0)[0]
    assert x[order[seen] >= 0].min() <= origin <= x[order[seen] >= 0].max()
    # a video whose first wave was too fast to tell its origin: not compared, and said
    measured = detect_events(result.recording,
                             gross_edge_ratio=replay.recording.attrs["gross_edge_ratio"])
    video = pd.DataFrame({"x_start": [39.0, -30.0], "kind": ["unresolved", "gross"],
                          "direction": ["unresolved", way], "speed": [np.nan, 200.0]})
    table = compare_test(measured, replay.recording, simulation, video,
                         min_drop=0.3).set_index("feature")
    row = table.loc[ORIGIN.name]
    assert row["verdict"] == "not compared" and "too fast" in row["note"]
    assert row["simulated"] == origin
    assert table.loc["way gross slips sweep (video vs zones)", "verdict"] == "agrees"


def test_place_on_map_picks_the_nearest_case():
    names = np.array(["ZD", "ZG"], dtype=object)
    behaviour_map = xr.Dataset(
        {"behaviour": (("height_ratio", "friction"), np.array([[1, 2], [2, 2]])),
         "sequence": (("height_ratio", "friction"),
                      np.array([["a", "b"], ["b", "b"]], dtype=object)),
         "behaviour_name": ("behaviour_id", names)},
        coords={"height_ratio": [0.25, 0.5], "friction": [0.5, 1.0], "behaviour_id": [1, 2]})
    place = place_on_map(behaviour_map, 0.3, 0.6)
    assert place["behaviour"] == "ZD" and place["map_friction"] == 0.5
    assert place["inside_map"] and not place_on_map(behaviour_map, 0.3, 1.6)["inside_map"]
    assert not place["in_mesh_band"]  # a map without its band
    behaviour_map["mesh_band"] = (("height_ratio", "friction"), np.array([[0, 1], [0, 0]]))
    assert not place_on_map(behaviour_map, 0.3, 0.6)["in_mesh_band"]
    assert place_on_map(behaviour_map, 0.3, 0.9)["in_mesh_band"]


def _waves(speeds: np.ndarray, *, kinds: list[str] | None = None, start: float = 38.0,
           direction: str = "right_to_left") -> pd.DataFrame:
    return pd.DataFrame({"speed": speeds, "x_start": start, "direction": direction,
                         "kind": kinds if kinds is not None else ["partial"] * len(speeds)})


def test_wave_speeds_from_one_law_agree_as_often_as_their_standard_errors_say() -> None:
    rng = np.random.default_rng(37)
    agree = {WAVE_SPEED.name: 0, WAVE_SPEED_SPREAD.name: 0}
    draws = 400
    for _ in range(draws):
        table = compare_waves(_waves(rng.normal(220.0, 30.0, 30)),
                              _waves(rng.normal(220.0, 30.0, 30)))
        for feature in agree:
            agree[feature] += table.set_index("feature").loc[feature, "verdict"] == "agrees"
    # twice the standard error: about 95 % of same-law pairs agree
    assert 0.9 <= agree[WAVE_SPEED.name] / draws <= 0.99
    assert 0.9 <= agree[WAVE_SPEED_SPREAD.name] / draws <= 0.995


def test_waves_forty_times_faster_differ_and_the_rest_is_read_row_by_row() -> None:
    rng = np.random.default_rng(1)
    video = _waves(rng.normal(220.0, 30.0, 12), kinds=["gross"] * 12)
    simulated = _waves(rng.normal(6000.0, 900.0, 9), kinds=["partial"] * 9, start=-13.0,
                       direction="left_to_right")
    table = compare_waves(video, simulated).set_index("feature")["verdict"]
    assert list(table.index) == list(WAVE_FEATURES)
    assert (table.drop(FOLLOWED.name) == "differs").all()
    assert table[FOLLOWED.name] == "agrees"  # every wave followed, on either side
    assert compare_waves(video, simulated).set_index("feature").loc[
        WHOLE_CONTACT.name, "measured"] == 1.0
    same = compare_waves(video, video).set_index("feature")
    assert (same["verdict"] == "agrees").all()


def test_a_film_whose_slips_the_camera_cannot_follow_differs_though_its_few_speeds_agree(
        ) -> None:
    # hl050 on the default campaign: the video followed 32 of its 55 waves at about
    # 220 mm/s; the film of a law of metres-per-second fronts, 3 of 179, read at the
    # speeds of a slab relaxing over three frames
    rng = np.random.default_rng(3)
    video = _waves(np.concatenate([rng.normal(220.0, 30.0, 32), np.full(23, np.nan)]),
                   kinds=["gross"] * 32 + ["unresolved"] * 23)
    film = _waves(np.concatenate([[190.0, 185.0, 27.0], np.full(176, np.nan)]),
                  kinds=["partial"] * 3 + ["unresolved"] * 176)
    table = compare_waves(video, film).set_index("feature")
    assert table.loc[WAVE_SPEED.name, "verdict"] == "agrees"
    assert table.loc[FOLLOWED.name, "verdict"] == "differs"
    assert table.loc[FOLLOWED.name, "measured"] == pytest.approx(32 / 55)


def test_waves_without_a_speed_are_not_compared() -> None:
    video = _waves(np.array([np.nan]), kinds=["unresolved"])
    table = compare_waves(video, _waves(np.array([6000.0, 6100.0]))).set_index("feature")
    assert table.loc[WAVE_SPEED.name, "verdict"] == "not compared"
    assert table.loc[FIRST_WAVE_START.name, "verdict"] == "not compared"
    assert table.loc[WHOLE_CONTACT.name, "verdict"] == "agrees"
