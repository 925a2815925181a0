"""The behaviour map: rows, assembly, names, figures and the command (issue 14)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from slipwave.cli import main
from slipwave.errors import SlipwaveError
from slipwave.io import read_dataset
from slipwave.map import (
    MAP_CASE_VARIABLES,
    PAPER_FRICTIONS,
    PAPER_HEIGHT_RATIOS,
    assemble_map,
    behaviour_legend,
    contiguity,
    deal_rows,
    friction_grid,
    map_agreement,
    map_meshes,
    map_row,
    map_table,
    mesh_band,
    place_tests,
    representative_cases,
    shard,
    shard_count,
)
from slipwave.plot import plot_map, plot_zone_histories
from slipwave.solver import Coulomb, LoadPath, Slab, describe_behaviour, simulate
from slipwave.solver.behaviour import BEHAVIOUR_VARIABLES

PAPER_PATH = LoadPath(normal_control="force", normal_friction=False)


def test_the_papers_grid_has_1572_cases():
    assert len(PAPER_FRICTIONS) * len(PAPER_HEIGHT_RATIOS) == 1572
    assert PAPER_FRICTIONS[0] == 0.10 and PAPER_FRICTIONS[-1] == 1.40
    np.testing.assert_array_equal(friction_grid(0.10, 1.40, 0.01), PAPER_FRICTIONS)
    with pytest.raises(SlipwaveError, match="need 0 < start <= stop"):
        friction_grid(1.0, 0.5, 0.1)


@pytest.fixture(scope="module")
def small_map() -> xr.Dataset:
    rows = [map_row(hl, [0.2, 0.6, 1.0], elements=40, path=PAPER_PATH) for hl in (0.2, 0.5)]
    return assemble_map(rows)


def test_a_map_case_keeps_what_its_description_reads():
    slab = Slab(height=20.0, elements=40)
    path = LoadPath(normal_control="force", normal_friction=False)
    whole = simulate(slab, Coulomb(fs=0.6), path)
    kept = simulate(slab, Coulomb(fs=0.6), path, variables=MAP_CASE_VARIABLES)
    assert set(BEHAVIOUR_VARIABLES) <= set(MAP_CASE_VARIABLES)
    assert describe_behaviour(kept) == describe_behaviour(whole)


def test_rows_hold_every_case_with_its_succession(small_map):
    assert small_map.sizes == {"height_ratio": 2, "friction": 3,
                               "behaviour_id": small_map.sizes["behaviour_id"]}
    assert set(small_map["end"].values.ravel()) == {"gross sliding"}
    assert float(small_map["max_residual"].max()) < 1e-8
    np.testing.assert_allclose(small_map["ratio_at_gross"].values,
                               np.tile([0.2, 0.6, 1.0], (2, 1)), rtol=1e-6)
    # numbers follow the successions: equal successions, equal numbers
    for number, sequence in zip(small_map["behaviour_id"].values,
                                small_map["behaviours"].values, strict=True):
        where = small_map["behaviour"].values == number
        assert set(small_map["sequence"].values[where]) == {sequence}
    assert int(small_map["cases"].sum()) == 6
    zd = small_map.sel(height_ratio=0.5, friction=1.0)
    assert str(zd["paper_name"].values) == "ZD" and int(zd["L"]) == 1
    assert small_map["first_opening_x"].attrs["units"] == "mm"


def test_table_legend_and_representatives(small_map):
    table = map_table(small_map)
    assert len(table) == 6 and {"height_ratio", "friction", "behaviour", "sequence"} <= set(
        table.columns)
    legend = behaviour_legend(small_map).splitlines()
    assert len(legend) == small_map.sizes["behaviour_id"]
    assert legend[0].startswith("- **") and "->" in legend[0]
    cases = representative_cases(small_map)
    assert list(cases["behaviour"]) == list(small_map["behaviour_id"].values)
    for case in cases.itertuples():
        found = small_map.sel(height_ratio=case.height_ratio, friction=case.friction)
        assert int(found["behaviour"]) == case.behaviour


def test_contiguity_and_agreement():
    grid = xr.Dataset({"sequence": (("height_ratio", "friction"),
                                    np.array([["a", "a", "b"], ["a", "c", "b"]], dtype=object))},
                      coords={"height_ratio": [0.1, 0.2], "friction": [0.1, 0.2, 0.3]})
    assert contiguity(grid) == pytest.approx(5 / 6)  # "c" has no like neighbour
    other = grid.copy(deep=True)
    other["sequence"].values[1, 1] = "a"
    assert map_agreement(grid, other) == pytest.approx(5 / 6)
    with pytest.raises(SlipwaveError, match="share no case"):
        map_agreement(grid, grid.assign_coords(friction=[0.5, 0.6, 0.7]))


def _sequences(rows: list[str], frictions: list[float]) -> xr.Dataset:
    return xr.Dataset({"sequence": (("height_ratio", "friction"),
                                    np.array([list(r) for r in rows], dtype=object))},
                      coords={"height_ratio": np.arange(1, len(rows) + 1) / 10,
                              "friction": frictions})


def test_the_band_holds_each_moved_case_and_its_neighbours_in_f_only():
    frictions = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]
    fine = _sequences(["aaaabbb", "aaaaaaa"], frictions)
    coarse = _sequences(["aabbbbb", "aaaaaac"], frictions)  # two moves at H/L 0.1, one at 0.2
    assert mesh_band(fine, coarse, 0).values.tolist() == [[0, 0, 1, 1, 0, 0, 0],
                                                          [0, 0, 0, 0, 0, 0, 1]]
    band = mesh_band(fine, coarse, 2)
    assert band.values.tolist() == [[1, 1, 1, 1, 1, 1, 0], [0, 0, 0, 0, 1, 1, 1]]
    assert band.dims == ("height_ratio", "friction") and band.attrs["units"] == "1"
    assert not mesh_band(fine, fine, 3).values.any()
    with pytest.raises(SlipwaveError, match="different friction"):
        mesh_band(fine, coarse.assign_coords(friction=np.array(frictions) + 0.01), 1)
    with pytest.raises(SlipwaveError, match="need 0 or more"):
        mesh_band(fine, coarse, -1)


def test_the_band_comes_from_a_coarser_mesh_or_none():
    assert map_meshes(320, 160) == [320, 160]
    assert map_meshes(40, 0) == [40]
    with pytest.raises(SlipwaveError, match="band_elements 320: the band is drawn from a "
                                            "coarser map"):
        map_meshes(320, 320)


def test_tests_are_placed_by_their_slenderness_and_measured_ratio():
    summary = pd.DataFrame({"test_id": ["a", "b", "c"], "static_ratio_mean": [1.0, 0.8, np.nan],
                            "static_ratio_ci_low": [0.95, 0.7, np.nan],
                            "static_ratio_ci_high": [1.05, 0.9, np.nan]})
    placed = place_tests(summary, {"a": 0.5, "c": 0.75})
    assert placed[["test_id", "height_ratio", "ratio"]].values.tolist() == [["a", 0.5, 1.0]]


def test_figures_draw(small_map, tmp_path):
    tests = pd.DataFrame({"test_id": ["t"], "height_ratio": [0.5], "ratio": [1.0],
                          "ci_low": [0.9], "ci_high": [1.1]})
    figure = plot_map(small_map, tests)
    axes = figure.axes[0]
    assert axes.get_xlabel().startswith("slab height") and "friction" in axes.get_ylabel()
    assert "ZD" in [t.get_text() for t in axes.texts]
    path = tmp_path / "map.png"
    figure.savefig(path)
    assert path.stat().st_size > 10_000
    assert not [p for p in axes.patches if p.get_hatch()]
    # the band hatched, one patch per run along f, and named in the legend
    banded = small_map.copy()
    banded["mesh_band"] = (("height_ratio", "friction"), np.array([[1, 1, 0], [0, 0, 1]]))
    banded.attrs.update(band_elements=20, contact_elements=40)
    axes = plot_map(banded).axes[0]
    assert len([p for p in axes.patches if p.get_hatch() == "////"]) == 2
    assert [t.get_text() for t in axes.get_legend().get_texts()] == [
        "still moves with the mesh (20 -> 40 elements)"]
    assert "at 40 elements" in axes.get_title()
    with pytest.raises(SlipwaveError, match="no simulation"):
        plot_zone_histories([])


def test_map_command_rows_then_assembly(tmp_path, capsys):
    rows = []
    for hl in ("0.3", "0.6"):
        rows.append(tmp_path / f"hl{hl}.nc")
        assert main(["map", "row", "--height-ratio", hl, "--frictions", "0.5", "1.0", "0.25",
                     "--elements", "40", "-o", str(rows[-1])]) == 0
    summary = tmp_path / "summary.csv"
    summary.write_text("test_id,static_ratio_mean,static_ratio_ci_low,static_ratio_ci_high\n"
                       "t,0.9,0.85,0.95\n")
    out = {name: tmp_path / name for name in ("map.nc", "map.csv", "legend.md", "map.png",
                                              "zones.png")}
    assert main(["map", "assemble", *map(str, rows), "-o", str(out["map.nc"]),
                 "--csv", str(out["map.csv"]), "--legend", str(out["legend.md"])]) == 0
    assert main(["map", "figures", str(out["map.nc"]), "--figure", str(out["map.png"]),
                 "--zones", str(out["zones.png"]), "--summary", str(summary),
                 "--test-ratio", "t=0.5"]) == 0
    assert main(["map", "figures", str(out["map.nc"]), "--figure", str(out["map.png"]),
                 "--summary", str(summary), "--test-ratio", "t=half"]) == 1
    printed = capsys.readouterr().out
    assert "6 cases" in printed and "0 without gross sliding" in printed
    assert "1 tests placed" in printed
    whole = read_dataset(out["map.nc"])
    assert whole["friction"].values.tolist() == [0.5, 0.75, 1.0]
    assert whole.attrs["normal_control"] == "force" and whole.attrs["normal_friction"] == 0
    assert len(pd.read_csv(out["map.csv"])) == 6
    assert all(out[name].stat().st_size > 5_000 for name in ("map.png", "zones.png"))
    # the band from the same rows at a coarser mesh: the cases whose succession moved
    coarse = tmp_path / "coarse.nc"
    assert main(["map", "row", "--height-ratio", "0.3", "0.6", "--frictions", "0.5", "1.0",
                 "0.25", "--elements", "16", "-o", str(coarse)]) == 0
    assert main(["map", "assemble", *map(str, rows), "--band-rows", str(coarse),
                 "--band-steps", "0", "-o", str(tmp_path / "banded.nc"), "--csv",
                 str(tmp_path / "banded.csv"), "--legend", str(tmp_path / "banded.md")]) == 0
    banded = read_dataset(tmp_path / "banded.nc")
    moved = banded["sequence"].values != read_dataset(coarse)["sequence"].values
    assert (banded["mesh_band"].values == moved).all()
    assert banded.attrs["band_elements"] == 16 and banded.attrs["band_steps"] == 0
    assert f"{int(moved.sum())} successions differ between 16 and 40 elements" in (
        capsys.readouterr().out)
    assert "mesh_band" in pd.read_csv(tmp_path / "banded.csv").columns
    # the same rows computed by one job, in one file: the same map
    both = tmp_path / "both.nc"
    assert main(["map", "row", "--height-ratio", "0.6", "0.3", "--frictions", "0.5", "1.0",
                 "0.25", "--elements", "40", "-o", str(both)]) == 0
    assert read_dataset(both)["height_ratio"].values.tolist() == [0.6, 0.3]
    assert main(["map", "assemble", str(both), "-o", str(tmp_path / "again.nc"),
                 "--csv", str(tmp_path / "again.csv"), "--legend",
                 str(tmp_path / "again.md")]) == 0
    again = read_dataset(tmp_path / "again.nc")
    for name in ("sequence", "behaviour", "ratio_at_gross", "steps"):
        assert (again[name].values == whole[name].values).all(), name


@pytest.mark.parametrize("jobs", [1, 2, 3, 5, 12, 40])
def test_the_rows_are_dealt_to_jobs_whole_and_about_evenly(jobs):
    dealt = deal_rows(PAPER_HEIGHT_RATIOS, jobs)
    assert len(dealt) == min(jobs, len(PAPER_HEIGHT_RATIOS))
    assert sorted(r for job in dealt for r in job) == sorted(PAPER_HEIGHT_RATIOS)
    costs = [sum(2 + r for r in job) for job in dealt]
    assert max(costs) - min(costs) <= 2 + max(PAPER_HEIGHT_RATIOS)  # at most one row apart
    with pytest.raises(SlipwaveError, match="at least 1"):
        deal_rows(PAPER_HEIGHT_RATIOS, 0)


def test_a_failing_case_is_named(monkeypatch):
    import slipwave.solver as solver  # map_row imports simulate from it when it runs

    def broken(*args, **kwargs):
        raise SlipwaveError("step 3: no convergence")

    monkeypatch.setattr(solver, "simulate", broken)
    with pytest.raises(SlipwaveError, match=r"map case H/L 0.5, f 0.7: step 3"):
        map_row(0.5, [0.7], elements=20)


def test_the_map_is_the_same_whatever_its_sharding():
    frictions = friction_grid(0.4, 1.0, 0.2)
    path = LoadPath(normal_load=76.0, tangential_step=4.0)
    whole = map_row(0.5, frictions, elements=24, path=path)
    pieces = [map_row(0.5, shard(frictions, k, 3), elements=24, path=path)
              for k in range(shard_count(frictions, 3))]
    assert [p.sizes["friction"] for p in pieces] == [3, 1]
    once, sharded = assemble_map([whole]), assemble_map(pieces[::-1])
    for name in ("sequence", "behaviour", "ratio_at_gross", "first_slip_x"):
        assert (once[name].values == sharded[name].values).all(), name
    with pytest.raises(SlipwaveError, match="overlap in f"):
        assemble_map([whole, pieces[0]])
    with pytest.raises(SlipwaveError, match="lies beyond the row"):
        shard(frictions, 2, 3)
