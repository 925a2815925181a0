"""The mesh study's pieces: features summed up, their changes, the process zone."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from slipwave.convergence import (
    FEATURES,
    converged_from,
    feature_summary,
    mesh_changes,
    simulated_summary,
)
from slipwave.errors import SlipwaveError
from slipwave.fit import SlipFeatures
from slipwave.setup import Setting, TestSetup
from slipwave.solver import Coulomb, SlipWeakening
from slipwave.solver.contact import OPEN
from slipwave.solver.slab import rounded_corners


def _setup(duration: float = 120.0) -> TestSetup:
    values = {"length_mm": 80.0, "height_mm": 40.0, "width_mm": 10.0,
              "youngs_modulus_mpa": 7.0, "poisson_ratio": 0.48, "normal_load_n": 85.0,
              "speed_mm_s": 0.048, "machine_stiffness_n_mm": 40.0, "duration_s": duration,
              "loading_time_s": 10.0}
    return TestSetup("t", {k: Setting(v, "test") for k, v in values.items()}, "frame")


def test_feature_summary_takes_medians_of_the_gross_slips_and_counts_the_partial_ones():
    gross = pd.DataFrame({"t_start": [10.0, 20.0, 40.0], "ratio_before": [0.7, 0.8, 0.9],
                          "ratio_after": [0.6, 0.6, 0.5], "drop": [5.0, 6.0, 9.0]})
    summary = feature_summary(SlipFeatures(gross, 4, 0.5, 60.0, 100.0, 3.0, 0.55,
                                           np.array([1.0, 2.0, 4.0])))
    assert summary == {"gross_slips": 3.0, "partial_slips": 4.0, "ratio_before_gross": 0.8,
                       "ratio_after_gross": 0.6, "gross_drop_n": 6.0, "partial_drop_n": 2.0,
                       "recurrence_s": 15.0, "first_slip_s": 3.0, "first_slip_ratio": 0.55}


def test_a_simulation_is_summed_up_feature_by_feature_its_first_slip_at_the_right_corner():
    summary = simulated_summary(_setup(), Coulomb(fs=0.9, fd=0.6), 40, min_drop=0.5,
                                sample_rate=100.0)
    assert list(summary) == list(FEATURES)
    assert summary["gross_slips"] >= 1
    # the flat drags the slab towards +x: the trailing (right) corner slips first
    assert 0.4 < summary["first_slip_place"] <= 0.5
    assert 0.5 < summary["first_slip_ratio"] < 0.9


def test_rounded_corners_lift_the_contact_ends_off_the_flat():
    setup = _setup()
    corners = rounded_corners(4.0, 80.0)
    rounded = setup.simulate(Coulomb(fs=0.9, fd=0.6), 40, profile=corners)
    sharp = setup.simulate(Coulomb(fs=0.9, fd=0.6), 40)
    # the last 4 mm (two elements) curve up by 4 mm: the end nodes never touch the flat
    assert (rounded["state"].values[:, [0, -1]] == OPEN).all()
    assert not (sharp["state"].values[:, [0, -1]] == OPEN).all()
    assert rounded.attrs["slab_profile"] != "flat"
    # the first slip where the face meets the flat, at the rounding's start (36 mm)
    first = simulated_summary(setup, Coulomb(fs=0.9, fd=0.6), 40, min_drop=0.5,
                              sample_rate=100.0, profile=corners)["first_slip_place"]
    assert first == pytest.approx(36.0 / 80.0)
    with pytest.raises(SlipwaveError, match="need 0 < radius < L/2 = 40 mm"):
        rounded_corners(40.0, 80.0)


def test_the_process_zone_grows_with_dc_and_shrinks_with_the_friction_drop():
    setup = _setup()
    base = setup.process_zone(SlipWeakening(fs=0.9, fd=0.6, dc=0.1))
    assert setup.process_zone(SlipWeakening(fs=0.9, fd=0.6, dc=0.2)) == pytest.approx(2 * base)
    assert setup.process_zone(SlipWeakening(fs=0.9, fd=0.75, dc=0.1)) == pytest.approx(2 * base)
    assert setup.process_zone(Coulomb(fs=0.9, fd=0.6)) == 0.0


def test_a_feature_present_at_one_mesh_only_has_not_converged():
    table = pd.DataFrame({"law": ["a"] * 3, "elements": [40, 80, 160],
                          "partial_drop_n": [np.nan, 2.0, 2.1],
                          "ratio_after_gross": [0.60, 0.601, 0.601]})
    changes = mesh_changes(table)
    assert np.isnan(changes.query("elements == 40 and feature == 'partial_drop_n'")["sigmas"]
                    ).all()
    assert converged_from(changes)["a"] == 80.0
    table["partial_drop_n"] = np.nan  # absent at every mesh: nothing moved
    assert converged_from(mesh_changes(table))["a"] == 40.0
