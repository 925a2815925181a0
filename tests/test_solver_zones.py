"""Zones followed from step to step: the history the behaviour map reads (issue 14)."""

from __future__ import annotations

import numpy as np

from slipwave.solver import Coulomb, LoadPath, Slab, simulate
from slipwave.solver.zones import (
    CONDITIONS,
    node_conditions,
    track_zones,
    zone_events,
    zone_runs,
    zone_sweeps,
)


def test_runs_absorb_what_is_smaller_than_the_size():
    codes = np.array([1, 1, 1, 2, 1, 1, 1, 1, 0, 0, 0, 0])
    assert zone_runs(codes, 0.5, 1.0) == [(1, 0, 7), (0, 8, 11)]  # one node: not a zone
    assert zone_runs(codes, 0.5, 0.5) == [(1, 0, 2), (2, 3, 3), (1, 4, 7), (0, 8, 11)]
    assert zone_runs(np.array([2, 2]), 0.5, 5.0) == [(2, 0, 1)]  # all of it, however small


def test_a_zone_keeps_its_identity_through_growth_merge_and_split():
    codes = np.array([
        [1, 1, 1, 1, 1, 1, 1, 1, 1, 1],
        [2, 2, 1, 1, 1, 1, 1, 1, 2, 2],  # slip enters at both edges
        [2, 2, 2, 2, 1, 1, 2, 2, 2, 2],  # and grows
        [2, 2, 2, 2, 2, 2, 2, 2, 2, 2],  # they merge: the whole contact slips
        [2, 2, 2, 1, 1, 1, 1, 2, 2, 2],  # it splits: stick comes back in the middle
    ])
    zones = track_zones(codes, np.arange(10.0), min_size=1.5)
    slip = zones[zones["condition"] == "slip_back"]
    assert slip[slip["step"] == 1]["zone"].tolist() == [1, 2]
    whole = slip[slip["step"] == 3]
    assert len(whole) == 1 and whole["merged"].iloc[0] in ("1", "2")
    assert len(set(slip[slip["step"] == 4]["zone"])) == 2
    events = zone_events(zones)
    appear = events[(events["event"] == "appear") & (events["condition"] == "slip_back")]
    assert appear[["step", "where"]].values.tolist()[:2] == [[1, "left_edge"], [1, "right_edge"]]
    assert (events["event"] == "merge").sum() == 1
    assert events[events["event"] == "vanish"]["condition"].tolist() == ["stick"]


def test_conditions_tell_the_drag_from_the_outward_slip():
    state = np.array([2, 1, 1, 2])
    direction = np.array([-1, 0, 0, 1])
    assert [CONDITIONS[c] for c in node_conditions(state, direction)] == [
        "slip_back", "stick", "stick", "slip_forward"]


def test_the_right_edge_unloads_outward_before_the_drag_slips_it():
    """H/L = 0.5, f = 1, 40 elements: the right edge first slips outward (towards +x, the
    normal loading's slip unloading) and opens; slip the drag drives comes after."""
    ds = simulate(Slab(elements=40), Coulomb(fs=1.0), LoadPath())
    codes = node_conditions(ds["state"].values, ds["slip_direction"].values)
    tangential = np.flatnonzero(ds["phase"].values == "tangential")
    zones = track_zones(codes[tangential], ds["x"].values, min_size=4.0)
    events = zone_events(zones)
    later = events[events["step"] > 0]
    appear = later[later["event"] == "appear"]
    first = appear.iloc[0]
    assert (first["condition"], first["where"]) == ("slip_forward", "right_edge")
    opening = appear[appear["condition"] == "open"]["step"].min()
    dragged = appear[appear["condition"] == "slip_back"]["step"].min()
    assert first["step"] < opening < dragged


def test_sweeps_say_where_a_zone_went():
    codes = np.array([
        [1] * 10,
        [1] * 4 + [2] * 2 + [1] * 4,  # slip appears inside
        [1] * 2 + [2] * 6 + [1] * 2,  # and grows both ways
        [1] * 8 + [0] * 2,            # then sticks again; the right edge opens
    ])
    sweeps = zone_sweeps(track_zones(codes, np.arange(10.0), min_size=1.5), min_size=1.5)
    slip = sweeps[sweeps["condition"] == "slip_back"].iloc[0]
    assert (slip["first_step"], slip["last_step"], slip["sweep"]) == (1, 2, "both_ways")
    assert (slip["x_min"], slip["x_max"], slip["swept"]) == (2.0, 7.0, 4.0)
    opened = sweeps[sweeps["condition"] == "open"].iloc[0]
    assert (opened["first_step"], opened["sweep"]) == (3, "none")
