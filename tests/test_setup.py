"""A test's configuration from its own files (issue 15, item 1)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from slipwave.errors import SlipwaveError
from slipwave.io import read_acquisition
from slipwave.setup import drive, normal_load_plateau, normal_loading_time, read_test_setup

RAW = Path(__file__).parents[1] / "raw_data" / "bench"
MATERIAL = {"youngs_modulus_mpa": "7", "poisson_ratio": "0.48", "edge_reference": "frame"}


@pytest.fixture(scope="module")
def hl075():
    return read_acquisition(RAW / "hl075.csv")


def test_drive_and_normal_load_are_measured_on_the_recording(hl075):
    # the virtual bench's truth (raw_data/bench/campaign.yaml): 0.048 mm/s, 40 N/mm, 85 N
    speed, stiffness = drive(hl075)
    assert speed == pytest.approx(0.048, rel=0.01)
    assert stiffness == pytest.approx(40.0, rel=0.02)
    assert normal_load_plateau(hl075) == pytest.approx(85.0, rel=0.01)


def test_a_spike_during_the_normal_loading_is_no_tangential_start(hl075):
    # a virtual-bench test had one sample of T 3.4 N high while N rose: taken for the
    # tangential loading's start, it read the normal load at half its plateau
    spiked = hl075.copy(deep=True)
    time, T, N = (spiked[name].values for name in ("time", "T", "N"))
    rising = int(np.searchsorted(time, 5.0))
    assert abs(N[rising]) < 0.7 * 85.0  # still pressing
    T[rising] += 0.2 * (np.nanpercentile(T, 99) - np.nanpercentile(T, 1))
    N[rising + 100] = -90.0  # and a spike of N above the plateau before it is reached
    clean = read_test_setup(hl075, {"test_id": "hl075", **MATERIAL})
    setup = read_test_setup(spiked, {"test_id": "hl075", **MATERIAL})
    assert normal_load_plateau(spiked) == pytest.approx(85.0, rel=0.01)
    for key in ("normal_load_n", "loading_time_s", "speed_mm_s", "machine_stiffness_n_mm"):
        assert setup[key] == pytest.approx(clean[key], rel=1e-3), key
    spikes_only = hl075.copy(deep=True)
    spikes_only["N"].values[:] = 0.0
    spikes_only["N"].values[::10] = -85.0  # never held: no loading to time
    with pytest.raises(SlipwaveError, match="N never holds its plateau"):
        normal_loading_time(spikes_only, 85.0)


def test_setup_reads_the_header_then_the_table_and_says_where_from(hl075):
    setup = read_test_setup(hl075, {"test_id": "hl075", **MATERIAL})
    assert setup["height_mm"] == 60.0 and setup.settings["height_mm"].source == \
        "recording header"
    assert setup.settings["youngs_modulus_mpa"].source == "campaign table"
    assert setup.settings["speed_mm_s"].source.startswith("measured")
    assert setup.settings["normal_load_n"].source.startswith("measured")
    assert setup.edge_reference == "frame"
    overridden = read_test_setup(hl075, {"test_id": "hl075", **MATERIAL, "height_mm": "59.5",
                                    "machine_stiffness_n_mm": "38"})
    assert overridden["height_mm"] == 59.5
    assert overridden.settings["machine_stiffness_n_mm"].source == "campaign table"
    data = overridden.to_dict()
    assert data["height_mm"] == {"value": 59.5, "source": "campaign table"}


def test_what_cannot_be_read_or_measured_names_the_column_to_add(hl075):
    bare = hl075.copy()
    bare.attrs = {k: v for k, v in hl075.attrs.items() if k != "height_mm"}
    with pytest.raises(SlipwaveError, match=r"test 'hl075': the slab height H, mm .* add the "
                                            r"column height_mm"):
        read_test_setup(bare, {"test_id": "hl075", **MATERIAL})
    with pytest.raises(SlipwaveError, match="column youngs_modulus_mpa"):
        read_test_setup(hl075, {"test_id": "hl075", "edge_reference": "flat"})
    with pytest.raises(SlipwaveError, match="edge_reference to frame or flat"):
        read_test_setup(hl075, {"test_id": "hl075", **MATERIAL, "edge_reference": ""})
    with pytest.raises(SlipwaveError, match="column width_mm: 'ten' is not a number"):
        read_test_setup(hl075, {"test_id": "hl075", **MATERIAL, "width_mm": "ten"})
    without_dt = hl075.drop_vars("DT")
    with pytest.raises(SlipwaveError, match="speed_mm_s and machine_stiffness_n_mm"):
        read_test_setup(without_dt, {"test_id": "hl075", **MATERIAL})
    given = read_test_setup(without_dt, {"test_id": "hl075", **MATERIAL, "speed_mm_s": "0.05",
                                    "machine_stiffness_n_mm": "40"})
    assert given["speed_mm_s"] == 0.05


def test_a_spring_that_does_not_give_way_is_refused(hl075):
    rigid = hl075.copy()
    rigid["DT"] = ("time", 0.048 * rigid["time"].values + np.random.default_rng(0).normal(
        0, 1e-4, rigid.sizes["time"]))
    rigid["T"] = ("time", -rigid["T"].values)  # DT no longer gives way as T rises
    with pytest.raises(SlipwaveError, match="machine_stiffness_n_mm"):
        drive(rigid)


@pytest.mark.slow
def test_the_setup_runs_the_test_again_through_the_solver(hl075):
    """The bench's own law on the setup read from hl075's files: its gross slips again."""
    import pandas as pd

    from slipwave.bench.generate import setup_bench_test, simulate_test
    from slipwave.solver import Coulomb

    setup = read_test_setup(hl075, {"test_id": "hl075", **MATERIAL})
    assert setup["loading_time_s"] == pytest.approx(10.0, abs=0.2)
    result = simulate_test(setup_bench_test(setup, Coulomb(fs=0.9, fd=0.6, fs_final=1.2,
                                                           runin_slips=4), elements=160),
                           seed=0)
    truth = pd.read_csv(RAW / "truth" / "hl075_events.csv")
    simulated = result.events[result.events["kind"] == "gross_slip"]
    measured = truth[truth["kind"] == "gross_slip"]
    assert len(simulated) == len(measured) == 8
    np.testing.assert_allclose(simulated["ratio_before"], measured["ratio_before"], atol=0.01)
    np.testing.assert_allclose(simulated["t_start"], measured["t_start"], atol=1.5)
