"""The tangential phase driven by an actuator through the machine's spring."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from slipwave.errors import SlipwaveError
from slipwave.solver import Coulomb, LoadPath, Slab, SolverCache, simulate
from slipwave.solver.simulate import RESIDUAL_TOLERANCE
from slipwave.solver.slab import condense

CACHE = SolverCache()  # the slabs of this file, condensed once

MACHINE = 100.0  # N/mm
SLAB = Slab(height=40.0, elements=80)


@pytest.fixture(scope="module")
def driven() -> xr.Dataset:
    path = LoadPath(normal_load=85.0, normal_control="force", machine_stiffness=MACHINE,
                    max_travel=5.0, travel_step=0.04)
    return simulate(SLAB, Coulomb(fs=1.0, fd=0.85), path, cache=CACHE)


def test_spring_law_every_step(driven):
    tangential = driven["phase"].values == "tangential"
    X = driven["actuator"].values[tangential]
    T = driven["T"].values[tangential]
    DT = driven["DT"].values[tangential]
    np.testing.assert_allclose(T, MACHINE * (X - DT), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(driven["N"].values[tangential], 85.0, rtol=1e-10)
    assert float(driven["residual"].max()) < RESIDUAL_TOLERANCE
    assert np.all(np.isnan(driven["actuator"].values[~tangential]))


def test_slips_release_load_and_the_flat_jumps(driven):
    gross = np.flatnonzero(driven["wave"].values == "gross")
    assert gross.size >= 3
    before = driven["T_before_wave"].values[gross]
    after = driven["T"].values[gross]
    assert np.all(before - after > 1.0)  # each gross slip drops T
    # The released load moves the flat forwards by the drop over the machine stiffness.
    jump = driven["DT"].values[gross] - driven["DT_before_wave"].values[gross]
    np.testing.assert_allclose(jump, (before - after) / MACHINE, rtol=1e-9)
    # T at gross slips never exceeds fs N, and after them sits at fd N or above.
    N = driven["N"].values[gross]
    assert np.all(before <= 1.0 * N + 1e-9) and np.all(after >= 0.85 * N - 1e-9)


def test_a_gross_slip_lands_on_its_actuator_step():
    # a slip lands on the step it happens in: every step, a gross slip's too, ends where
    # the actuator's step ends (the solver once cut gross slips at their onset, off it)
    path = LoadPath(normal_load=85.0, normal_control="force", machine_stiffness=40.0,
                    max_travel=6.0, travel_step=0.03)
    cycle = simulate(Slab(height=40.0, elements=40), Coulomb(fs=0.9, fd=0.6), path,
                     cache=CACHE)
    tangential = cycle["phase"].values == "tangential"
    steps = cycle["actuator"].values[tangential] / 0.03
    assert (cycle["substeps"].values[tangential] == 1).all()
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-9)
    assert (cycle["wave"].values[tangential] == "gross").sum() >= 3


def test_before_wave_equals_after_without_a_wave(driven):
    quiet = driven["wave"].values == "none"
    for name in ["T", "N", "DG", "DD", "DT"]:
        np.testing.assert_allclose(driven[f"{name}_before_wave"].values[quiet],
                                   driven[name].values[quiet], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(driven["ux_before_wave"].values[quiet],
                               driven["ux"].values[quiet], atol=1e-15)


def test_sensors_follow_the_contact_displacements(driven):
    sensors = condense(SLAB, cache=CACHE).sensors
    u = np.concatenate([driven["ux"].values, driven["uy"].values], axis=1)
    np.testing.assert_allclose(u @ sensors[0], driven["DG"].values, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(u @ sensors[1], driven["DD"].values, rtol=1e-10, atol=1e-12)
    u_before = np.concatenate([driven["ux_before_wave"].values,
                               driven["uy_before_wave"].values], axis=1)
    np.testing.assert_allclose(u_before @ sensors[0], driven["DG_before_wave"].values,
                               rtol=1e-10, atol=1e-12)


def test_machine_drive_needs_travel():
    with pytest.raises(SlipwaveError, match="machine drive needs"):
        LoadPath(machine_stiffness=100.0)
