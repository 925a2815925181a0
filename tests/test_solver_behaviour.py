"""The interface's succession of events, read from the zone history (issue 14)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from slipwave.solver import Coulomb, LoadPath, Slab, SolverCache, describe_behaviour, simulate

# Codes of a synthetic history: the letters of node_conditions' conditions.
CACHE = SolverCache()  # the slabs of this file, condensed once

_STATE = {"O": (0, 0), "S": (1, 0), "b": (2, -1), "f": (2, 1)}


def history(*rows: str, T: list[float] | None = None) -> xr.Dataset:
    """A simulation-like dataset from rows of letters (O open, S stick, b slip -x, f slip +x).

    The first row is the end of the normal loading, the last one gross sliding.
    """
    state = np.array([[_STATE[c][0] for c in row] for row in rows], dtype=np.int8)
    direction = np.array([[_STATE[c][1] for c in row] for row in rows], dtype=np.int8)
    steps, nodes = state.shape
    T = T or [2.0 * k for k in range(steps)]
    phase = ["normal"] + ["tangential"] * (steps - 1)
    wave = ["none"] * (steps - 1) + ["gross"]
    return xr.Dataset(
        {"state": (("step", "x"), state), "slip_direction": (("step", "x"), direction),
         "phase": ("step", phase), "wave": ("step", wave), "T": ("step", np.array(T)),
         "N": ("step", np.full(steps, 10.0))},
        coords={"x": np.arange(nodes, dtype=float)},
    )


def test_a_sweep_from_the_right_edge_after_an_opening_is_zd():
    ds = history("SSSSSSSSSS",
                 "SSSSSSSSSO",
                 "SSSSSSSSOO",
                 "SSSSSSbbOO",
                 "SSSbbbbbOO",
                 "bbbbbbbbOO")
    behaviour = describe_behaviour(ds, min_size=1.5, min_sweep=2.0)
    assert behaviour.sequence == ("opening right", "slip zone from right edge sweeps "
                                  "right-to-left", "gross sliding")
    assert behaviour.paper_name == "ZD" and behaviour.opens_right_first
    # the opening dates from its first node (step 1), although it counted from step 2
    assert behaviour.events[0]["step"] == 1 and behaviour.first_opening_x == 8.5
    assert behaviour.ratio_at_gross == pytest.approx(1.0)


def test_a_zone_starting_inside_and_growing_right_is_zg():
    ds = history("SSSSSSSSSSSS",
                 "SSSSbbSSSSSS",
                 "SSSSbbbbSSSS",
                 "SSSbbbbbbbSS",
                 "bbbbbbbbbbbb")
    behaviour = describe_behaviour(ds, min_size=1.5, min_sweep=2.0)
    assert behaviour.sequence == ("slip zone inside sweeps left-to-right", "gross sliding")
    assert behaviour.paper_name == "ZG" and not behaviour.opens_right_first
    slip = behaviour.events[0]
    assert (slip["swept_left"], slip["swept_right"]) == (1.0, 4.0)


def test_unloading_slip_and_small_zones_do_not_enter_the_succession():
    ds = history("SSSSSSSSSSSS",
                 "SSSSSSSSSSff",  # outward slip at the right edge as T unloads it
                 "SSbSSSSSSSff",  # a one-node flicker: smaller than the size
                 "SSSSSSSSbbbb",
                 "SSSSSbbbbbbb",
                 "bbbbbbbbbbbb")
    behaviour = describe_behaviour(ds, min_size=1.5, min_sweep=2.0)
    assert behaviour.sequence == ("slip zone from right edge sweeps right-to-left",
                                  "gross sliding")
    assert [e["event"] for e in behaviour.events][:2] == ["unloading slip", "slip"]


def test_merges_and_re_sticking_are_events_in_order():
    ds = history("SSSSSSSSSSSS",
                 "bbbSSSSSSSSS",  # from the left edge
                 "bbbbbSSSSSbb",  # and from the right edge
                 "bbbbbbSSbbbb",
                 "bbbbbbbbbbbb",  # they merge (the contact has not slid yet: T grows)
                 "bbbbbbbbbbbb")
    merged = describe_behaviour(ds, min_size=1.5, min_sweep=2.0)
    assert merged.sequence == ("slip zone from left edge sweeps left-to-right",
                               "slip zone from right edge sweeps right-to-left",
                               "slip zones merge", "gross sliding")
    ds = history("SSSSSSSSSSSS",
                 "SSSSSSSSSbbb",
                 "SSSSSSSSSSSS",  # the slip zone sticks again
                 "SSbbbbSSSSSS",
                 "bbbbbbbbbbbb")
    restuck = describe_behaviour(ds, min_size=1.5, min_sweep=2.0)
    assert restuck.sequence == ("slip zone from right edge sweeps in place",
                                "slip zone from right edge sticks again",
                                "slip zone inside sweeps in place", "gross sliding")


def test_the_normal_loadings_edge_slip_going_on_is_named_so():
    ds = history("bbbSSSSSSfff",  # the normal loading left both edges slipping outward
                 "bbbbSSSSSSSS",
                 "bbbbbbbSSSSS",
                 "bbbbbbbbbbbb")
    behaviour = describe_behaviour(ds, min_size=1.5, min_sweep=2.0)
    assert behaviour.sequence == ("slip zone from left edge, continuing the normal loading's "
                                  "slip sweeps left-to-right", "gross sliding")
    assert behaviour.paper_name is None


def test_behaviour_serialises():
    ds = history("SSSSSSSSSS", "SSSSSSSSSO", "SSSSSSbbOO", "bbbbbbbbOO")
    data = json.loads(describe_behaviour(ds, min_size=1.5, min_sweep=2.0).to_json())
    assert data["text"] == " -> ".join(data["sequence"]) and data["L"] is True
    assert data["events"][-1]["event"] == "gross sliding"


@pytest.fixture(scope="module")
def paper_case():
    """The paper's setting at H/L = 0.5 (80 elements): N held, frictionless approach."""

    def run(fs: float, height: float = 40.0, **path: object) -> xr.Dataset:
        slab = Slab(height=height, elements=80)
        options = {"normal_control": "force", "normal_friction": False, **path}
        return simulate(slab, Coulomb(fs=fs), LoadPath(**options), cache=CACHE)

    return run


@pytest.mark.parametrize("fs", [0.9, 1.0, 1.1])
def test_the_bench_geometry_opens_right_then_sweeps_right_to_left(paper_case, fs):
    """Acceptance: H/L 0.5, f 0.9-1.1: first opening at the right edge (L), then ZD."""
    behaviour = describe_behaviour(paper_case(fs))
    assert behaviour.opens_right_first and behaviour.paper_name == "ZD"
    assert behaviour.main_slip == ("right edge", "right-to-left")
    assert behaviour.end == "gross sliding"
    assert behaviour.ratio_at_gross == pytest.approx(fs, rel=1e-6)


def test_friction_during_the_normal_loading_brings_zg_at_the_bench_geometry(paper_case):
    """Issue 14, item 4: the locked-in shear of a frictional approach makes slip start inside."""
    behaviour = describe_behaviour(paper_case(1.0, normal_friction=True))
    assert behaviour.paper_name == "ZG" and behaviour.opens_right_first
    inside = [e for e in behaviour.events if e["event"] == "slip" and e["origin"] == "inside"]
    assert inside and inside[0]["x"] < 0 and inside[0]["swept_right"] > inside[0]["swept_left"]


def test_held_normal_displacement_slides_or_jams(paper_case):
    slides = paper_case(1.0, normal_control="displacement")
    assert slides.attrs["gross_sliding"] == "reached"
    assert float(slides["N"][-1]) > 150.0  # the held approach: N grew with T
    jams = paper_case(1.4, normal_control="displacement")
    assert jams.attrs["gross_sliding"].startswith("jammed")
    assert describe_behaviour(jams).end == "jammed"
    tangential = jams["phase"].values == "tangential"
    assert not np.any(jams["wave"].values[tangential] == "gross")
    # With N held the contact always slides, at T = f N
    held = paper_case(1.4)
    assert held.attrs["gross_sliding"] == "reached"
    assert float(held["T"][-1] / held["N"][-1]) == pytest.approx(1.4, rel=1e-6)


# One case of each of the 24 behaviours of the default map (160 elements, N held,
# frictionless approach): the case deepest inside its region, with its succession.
MAP_BEHAVIOURS = [
    (0.8, 0.72, 'ZD', (
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'gross sliding',
    )),
    (0.6, 1.18, 'ZD', (
        'opening right',
        'slip zone from right edge sweeps right-to-left',
        'gross sliding',
    )),
    (0.8, 0.15, 'ZD', (
        'slip zone from right edge sweeps right-to-left',
        'slip zone from left edge sweeps left-to-right',
        'gross sliding',
    )),
    (0.2, 1.38, 'ZG', (
        'opening right',
        'slip zone from right edge sweeps right-to-left',
        'slip zone inside sweeps left-to-right',
        'slip zones merge',
        'gross sliding',
    )),
    (0.1, 0.7, 'ZG', (
        'slip zone from right edge sweeps right-to-left',
        'slip zone inside sweeps left-to-right',
        'opening right',
        'gross sliding',
    )),
    (0.3, 1.05, 'ZD', (
        'opening right',
        'slip zone from right edge sweeps right-to-left',
        'slip zone inside sweeps in place',
        'slip zones merge',
        'gross sliding',
    )),
    (0.2, 0.29, None, (
        'slip zone from right edge sweeps right-to-left',
        'slip zone from left edge sweeps left-to-right',
        'opening right',
        'gross sliding',
    )),
    (0.1, 0.18, None, (
        'slip zone from left edge sweeps left-to-right',
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'gross sliding',
    )),
    (1.0, 0.24, 'ZD', (
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'slip zone from left edge sweeps left-to-right',
        'gross sliding',
    )),
    (0.1, 1.19, 'ZG', (
        'slip zone inside sweeps left-to-right',
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'slip zones merge',
        'gross sliding',
    )),
    (0.7, 0.21, 'ZD', (
        'slip zone from right edge sweeps right-to-left',
        'gross sliding',
    )),
    (0.2, 0.55, 'ZD', (
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'slip zone inside sweeps left-to-right',
        'gross sliding',
    )),
    (0.1, 0.87, 'ZG', (
        'slip zone from right edge sweeps right-to-left',
        'slip zone inside sweeps left-to-right',
        'opening right',
        'slip zones merge',
        'gross sliding',
    )),
    (0.2, 0.66, 'ZG', (
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'slip zone inside sweeps left-to-right',
        'slip zones merge',
        'gross sliding',
    )),
    (0.1, 1.32, 'ZG', (
        'slip zone inside sweeps left-to-right',
        'slip zone from right edge sweeps right-to-left',
        'slip zones merge',
        'opening right',
        'gross sliding',
    )),
    (0.3, 0.62, 'ZD', (
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'slip zone inside sweeps in place',
        'slip zones merge',
        'gross sliding',
    )),
    (0.1, 1.05, 'ZG', (
        'slip zone inside sweeps left-to-right',
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'gross sliding',
    )),
    (0.1, 1.39, 'ZG', (
        'slip zone inside sweeps left-to-right',
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'slip zone from right edge sticks again',
        'gross sliding',
    )),
    (0.2, 0.73, 'ZG', (
        'opening right',
        'slip zone from right edge sweeps right-to-left',
        'slip zone inside sweeps left-to-right',
        'gross sliding',
    )),
    (0.2, 0.39, 'ZD', (
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'slip zone inside sweeps in place',
        'gross sliding',
    )),
    (0.2, 0.35, None, (
        'slip zone from right edge sweeps right-to-left',
        'opening right',
        'slip zone inside sweeps both ways',
        'gross sliding',
    )),
    (0.3, 1.35, 'ZD', (
        'opening right',
        'slip zone from right edge sweeps right-to-left',
        'slip zone inside sweeps both ways',
        'slip zones merge',
        'gross sliding',
    )),
    (1.5, 0.1, 'ZD', (
        'slip zone from left edge sweeps left-to-right',
        'slip zone from right edge sweeps right-to-left',
        'gross sliding',
    )),
    (0.2, 0.32, 'ZG', (
        'slip zone from right edge sweeps right-to-left',
        'slip zone from left edge sweeps left-to-right',
        'slip zone inside sweeps left-to-right',
        'opening right',
        'slip zones merge',
        'gross sliding',
    )),
]


@pytest.mark.slow
@pytest.mark.parametrize(("height_ratio", "fs", "paper", "sequence"), MAP_BEHAVIOURS,
                         ids=[f"hl{c[0]:g}-f{c[1]:.2f}" for c in MAP_BEHAVIOURS])
def test_each_behaviour_of_the_map_on_a_case_that_shows_it(height_ratio, fs, paper, sequence):
    slab = Slab(height=80.0 * height_ratio)
    ds = simulate(slab, Coulomb(fs=fs), LoadPath(normal_control="force", normal_friction=False),
                  cache=CACHE)
    behaviour = describe_behaviour(ds)
    assert behaviour.sequence == sequence
    assert behaviour.paper_name == paper
    assert behaviour.end == "gross sliding"
