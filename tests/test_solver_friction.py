"""Friction laws: Coulomb (fs, fd), run-in, linear slip-weakening (issue 15, item 2)."""

from __future__ import annotations

import numpy as np
import pytest

from slipwave.bench.generate import BenchTest, simulate_test
from slipwave.errors import SlipwaveError
from slipwave.solver import Coulomb, LoadPath, Slab, SlipWeakening, SolverCache, simulate
from slipwave.solver.contact import SLIP

SLAB = Slab(height=40.0, elements=80)
STICK_SLIP = LoadPath(normal_control="force", max_travel=3.0)


@pytest.fixture(scope="module")
def runs():
    cache = SolverCache()
    laws = {"coulomb": Coulomb(fs=1.0, fd=0.7), "dc 1e-4": SlipWeakening(fs=1.0, fd=0.7, dc=1e-4),
            "dc 0.05": SlipWeakening(fs=1.0, fd=0.7, dc=0.05),
            "dc 0.2": SlipWeakening(fs=1.0, fd=0.7, dc=0.2),
            "dc 2": SlipWeakening(fs=1.0, fd=0.7, dc=2.0)}
    return {name: simulate(SLAB, law, STICK_SLIP, cache=cache)
            for name, law in laws.items()}


def test_a_vanishing_distance_is_coulomb(runs):
    np.testing.assert_allclose(runs["dc 1e-4"]["T"].values, runs["coulomb"]["T"].values,
                               atol=1e-9)
    assert runs["dc 2"].attrs["friction_law"] == "linear slip-weakening"
    assert runs["dc 2"].attrs["friction_dc"] == 2.0
    assert runs["coulomb"].attrs["friction_law"] == "Coulomb"


def test_slipping_nodes_follow_the_law(runs):
    law = SlipWeakening(fs=1.0, fd=0.7, dc=0.2)
    ds = runs["dc 0.2"]
    state, rounds = ds["state"].values, ds["cascade_round"].values
    p, q, slip = ds["p"].values, ds["q"].values, ds["slip"].values
    checked = 0
    for k in np.flatnonzero(ds["wave"].values != "none"):
        if k == 0 or ds["phase"].values[k] != "tangential" or ds["substeps"].values[k] > 1:
            continue  # a sub-stepped step is several waves, each with its own slip
        # nodes of the wave still slipping at its end, pressed enough to read q/p
        nodes = (state[k] == SLIP) & (rounds[k] >= 0) & (p[k] > 0.05 * p[k].max())
        moved = np.abs(slip[k] - slip[k - 1])[nodes]
        np.testing.assert_allclose(np.abs(q[k][nodes]) / p[k][nodes], law.weakening(moved),
                                   rtol=1e-6, atol=1e-7)
        checked += int(nodes.sum())
    assert checked > 100
    assert float(ds["residual"].max()) < 1e-8


def test_a_longer_distance_holds_more_load_and_drops_it_further(runs):
    # weakening over a longer slip keeps the coefficient near fs through small slips:
    # the contact carries more before a wave gets through, and sheds more when it does
    names = ("coulomb", "dc 0.05", "dc 0.2", "dc 2")
    peaks = [float(runs[name]["T"].max()) for name in names]
    drops = [float(-np.diff(runs[name]["T"].values).min()) for name in names]
    assert peaks == sorted(peaks) and peaks[-1] > 1.2 * peaks[0]
    assert drops == sorted(drops) and drops[-1] > 4 * drops[0]


def test_the_law_is_checked():
    with pytest.raises(SlipwaveError, match="dc > 0"):
        SlipWeakening(fs=1.0, fd=0.7, dc=0.0)
    with pytest.raises(SlipwaveError, match="fs > fd"):
        SlipWeakening(fs=1.0, fd=1.0, dc=0.1)
    assert SlipWeakening(fs=1.0, fd=0.6, dc=0.2).weakening(np.array([0.0, 0.1, 9.0])).tolist() \
        == pytest.approx([1.0, 0.8, 0.6])


def test_the_virtual_bench_writes_a_slip_weakening_test():
    spec = BenchTest("sw", height=40.0, fs=1.0, fd=0.7, fs_final=None, dc=0.1, duration=60.0,
                     loading_time=5.0, elements=40, video="none")
    assert spec.friction() == SlipWeakening(fs=1.0, fd=0.7, dc=0.1)
    result = simulate_test(spec, seed=1)
    assert result.recording.sizes["time"] > 5000
    assert len(result.events) >= 5
    assert result.simulation.attrs["friction_law"] == "linear slip-weakening"


def test_a_run_in_goes_its_share_of_the_way_per_gross_slip():
    assert Coulomb(fs=0.9, fd=0.6, fs_final=1.2, runin_slips=4.0).static_after(2) == \
        pytest.approx(1.05)
    # not whole: 2 slips of 2.5 are 80 % of the way; a falling run-in as well
    assert Coulomb(fs=0.9, fd=0.6, fs_final=1.2, runin_slips=2.5).static_after(2) == \
        pytest.approx(0.9 + 0.8 * 0.3)
    assert Coulomb(fs=0.9, fd=0.6, fs_final=0.7, runin_slips=2.5).static_after(5) == 0.7
    with pytest.raises(SlipwaveError, match="runin_slips > 0"):
        Coulomb(fs=0.9, fd=0.6, fs_final=1.2, runin_slips=0)


def test_a_run_in_that_turns_goes_to_its_peak_then_back():
    law = Coulomb(fs=0.8, fd=0.6, fs_peak=1.4, fs_final=0.9, runin_slips=2.0)
    assert [law.static_after(g) for g in range(6)] == pytest.approx(
        [0.8, 1.1, 1.4, 1.15, 0.9, 0.9])
    with pytest.raises(SlipwaveError, match="turn needs fs_final"):
        Coulomb(fs=0.8, fd=0.6, fs_peak=1.4)
    with pytest.raises(SlipwaveError, match="fs_peak >= fd"):
        Coulomb(fs=0.8, fd=0.6, fs_peak=0.5, fs_final=0.9, runin_slips=2.0)


def test_the_virtual_bench_records_a_run_in_that_turns():
    spec = BenchTest("turn", height=40.0, fs=0.8, fd=0.6, fs_peak=1.4, fs_final=0.8,
                     runin_slips=2, elements=40, video="none")
    simulation = simulate_test(spec, seed=1).simulation
    assert simulation.attrs["friction_fs_peak"] == 1.4
    gross = np.flatnonzero(simulation["wave"].values == "gross")
    starts = gross[np.r_[True, np.diff(gross) > 1]]
    assert simulation["static_friction"].values[starts][:6].tolist() == pytest.approx(
        [0.8, 1.1, 1.4, 1.1, 0.8, 0.8])
