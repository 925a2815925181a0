"""The simulate-waves stage: a filmed test simulated quasi-dynamically, its waves with a speed.

The simulate stage's solver is quasi-static: its slips have no duration and its waves no
speed. Here the test's slab, normal load and drive are run through the quasi-dynamic
contact (:func:`slipwave.solver.quasi_dynamic.simulate_quasi_dynamic`) under a
rate-and-state law, and its waves are read from its fronts
(:func:`slipwave.solver.fronts.front_waves`) in the video's columns, on the test's clock
(the drive starts when the normal loading ends), so that the compare stage sets them
beside the video's (:func:`slipwave.compare.compare_waves`).

What it leaves out, as the solver does: the actuator's machine spring (the flat's travel
is prescribed at the test's speed) and the slab's inertia beyond radiation damping.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pandas as pd
import xarray as xr

from slipwave.setup import TestSetup
from slipwave.solver.fronts import front_waves
from slipwave.solver.quasi_dynamic import (
    Drive,
    record_times,
    simulate_quasi_dynamic,
    slab_body,
)
from slipwave.solver.rate_state import RateState
from slipwave.video.waves import MIN_EXTENT

UM_PER_M = 1e6


def rate_state_law(settings: Mapping[str, Any]) -> RateState:
    """The config's rate-and-state law (the ``simulate_waves`` section), in the solver's units.

    Parameters
    ----------
    settings
        ``a``, ``b``, ``dc_um`` (um), ``mu0`` and ``v0_um_s`` (um/s).

    Returns
    -------
    RateState
        The aging law with those parameters.

    Examples
    --------
    >>> rate_state_law({"a": 0.01, "b": 0.015, "dc_um": 2.0, "mu0": 0.9, "v0_um_s": 1.0}).dc
    2e-06
    """
    return RateState(a=float(settings["a"]), b=float(settings["b"]),
                     dc=float(settings["dc_um"]) / UM_PER_M, mu0=float(settings["mu0"]),
                     v0=float(settings["v0_um_s"]) / UM_PER_M)


def law_text(law: RateState) -> str:
    """The law as a reader writes it, in the config's units.

    Parameters
    ----------
    law
        An aging law of one state (:func:`rate_state_law`'s).

    Returns
    -------
    str
        Its a, b, D_c, mu0 and v0.

    Examples
    --------
    >>> law_text(rate_state_law({"a": 0.01, "b": 0.015, "dc_um": 2.0, "mu0": 0.9,
    ...                          "v0_um_s": 1.0}))
    'aging law, a 0.01, b 0.015, D_c 2 um, mu0 0.9, v0 1 um/s'
    """
    return (f"{law.evolution} law, a {law.a:g}, b {law.b:g}, D_c {law.dc * UM_PER_M:g} um, "
            f"mu0 {law.mu0:g}, v0 {law.v0 * UM_PER_M:g} um/s")


def simulate_waves(setup: TestSetup, law: RateState, *, elements: int,
                   field_rate: float, sample_rate: float
                   ) -> tuple[xr.Dataset, pd.DataFrame]:
    """A test run quasi-dynamically: the run, and its waves in the video's columns.

    Parameters
    ----------
    setup
        The test's configuration (its slab, normal load, speed, duration, loading time).
    law
        The interface's law.
    elements
        Elements along the contact.
    field_rate
        Records of the nodes' slip rate, state and stresses per second.
    sample_rate
        Records of the loads and sensors per second.

    Returns
    -------
    tuple
        The run (:func:`~slipwave.solver.quasi_dynamic.simulate_quasi_dynamic`'s
        dataset, its times shifted onto the test's clock) and its waves
        (:func:`~slipwave.solver.fronts.front_waves`, at least the video's smallest
        extent), on the test's clock.

    Examples
    --------
    >>> from slipwave.setup import Setting
    >>> values = {"length_mm": 80.0, "height_mm": 40.0, "width_mm": 50.0,
    ...           "youngs_modulus_mpa": 7.0, "poisson_ratio": 0.48, "normal_load_n": 76.0,
    ...           "speed_mm_s": 0.048, "machine_stiffness_n_mm": 40.0, "duration_s": 20.0,
    ...           "loading_time_s": 10.0}
    >>> setup = TestSetup("demo", {k: Setting(v, "example") for k, v in values.items()},
    ...                   "frame")
    >>> law = rate_state_law({"a": 0.01, "b": 0.015, "dc_um": 2.0, "mu0": 0.9,
    ...                       "v0_um_s": 1.0})
    >>> run, waves = simulate_waves(setup, law, elements=40, field_rate=10.0,
    ...                             sample_rate=10.0)
    >>> float(run["time"][0]), len(waves)  # the drive starts at 10 s; no wave by 20 s
    (10.0, 0)
    """
    loading = setup["loading_time_s"]
    driven = setup["duration_s"] - loading
    run = simulate_quasi_dynamic(
        slab_body(setup.slab(elements)), law,
        Drive(normal_load=setup["normal_load_n"], drive_speed=setup["speed_mm_s"],
              normal_control="force"),
        duration=driven, sample_rate=sample_rate,
        field_times=record_times(driven, field_rate))
    waves = front_waves(run, min_extent=MIN_EXTENT)
    waves[["t_start", "t_end"]] += loading
    run = run.assign_coords(time=run["time"] + loading, field_time=run["field_time"] + loading)
    run["crossing_time"] = run["crossing_time"] + loading
    for name in ("time", "field_time"):
        run[name].attrs.update(units="s", long_name="time on the test's clock")
    run.attrs.update(loading_time=loading, law_text=law_text(law))
    return run, waves
