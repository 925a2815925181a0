"""Mesh convergence: the features a fit compares, against the element count.

A friction law is only worth fitting where what it predicts does not depend on the
mesh. Under Coulomb's law with fs > fd the coefficient falls at once, with no length,
and the slab's corner concentrates the shear: where the first slip starts and how far
a cascade runs follow the element size. Linear slip-weakening over a slip Dc brings a
length, the cohesive (process) zone of a slip front (Palmer and Rice 1973),

    Lambda = G* Dc / ((fs - fd) sigma),   G* = G / (1 - nu),

which a mesh resolves with a few elements (Day et al. 2005). This module simulates a
test along its load path at several meshes, reads each simulation's features as the
fit does (:func:`slipwave.fit.simulated_events`, :func:`slipwave.fit.slip_features`)
and tabulates how each moves when the mesh is doubled (a slip-weakening law's
process zone: :meth:`slipwave.setup.TestSetup.process_zone`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd
import xarray as xr

from slipwave.compare import recurrence
from slipwave.events.detect import DEFAULT_DETECTION, DetectionSettings
from slipwave.fit import SlipFeatures, edge_threshold, simulated_events, slip_features
from slipwave.setup import TestSetup
from slipwave.solver import Coulomb, SolverCache

RATIO_SIGMA = 0.005
"""A T/|N| at a slip is measured to this (the card's noise over a few samples, the onset's
sampling)."""
SEQUENCE_SIGMA = 0.015
"""T/|N| before slips also moves by this with the cycle a law settles in (which partial
slips came before): one slip more or fewer moves a median by about as much."""
TIME_SIGMA_S = 1.0
"""A slip's time, s."""
COUNT_SIGMA = 0.25
"""A count of slips and the gross slips' recurrence, relative: the cycle's number of slips
jumps as the coefficients move, several small slips merge in one detected drop."""
PARTIAL_DROP_SIGMA = 0.2
"""The median drop of slips, relative (which slips merge into one detected drop)."""

FEATURES: dict[str, str] = {
    "gross_slips": "gross slips (number)",
    "partial_slips": "partial slips (number)",
    "ratio_before_gross": "T/|N| before gross slips (median)",
    "ratio_after_gross": "T/|N| after gross slips (median)",
    "gross_drop_n": "T drop of gross slips (median, N)",
    "partial_drop_n": "T drop of partial slips (median, N)",
    "recurrence_s": "recurrence of gross slips (median interval, s)",
    "first_slip_s": "time of the first slip (s)",
    "first_slip_ratio": "T/|N| before the first slip",
    "first_slip_place": "centre of the first slip zone (x / L, 0 at the contact's centre)",
}
"""The features a fit compares, summed up one number each, and what they are."""


def feature_uncertainty(name: str, value: float) -> float:
    """The uncertainty a mesh study gives a feature of this value (what counts as a change).

    T/|N| after gross slips: :data:`RATIO_SIGMA`; before them and before the first slip,
    with the cycle's :data:`SEQUENCE_SIGMA` in quadrature; counts: :data:`COUNT_SIGMA`
    of the count, at least 1 gross or 3 partial slips; drops: :data:`PARTIAL_DROP_SIGMA`
    of the drop; times: :data:`TIME_SIGMA_S`, the recurrence at least ``COUNT_SIGMA`` of
    itself. The first slip's place is not fitted: NaN.

    Parameters
    ----------
    name
        A key of :data:`FEATURES`.
    value
        The feature's value.

    Returns
    -------
    float
        In the feature's unit.

    Examples
    --------
    >>> feature_uncertainty("gross_slips", 14.0), feature_uncertainty("partial_slips", 2.0)
    (3.5, 3.0)
    """
    size = abs(value)
    before = float(np.hypot(RATIO_SIGMA, SEQUENCE_SIGMA))
    scales = {
        "gross_slips": max(1.0, COUNT_SIGMA * size),
        "partial_slips": max(3.0, COUNT_SIGMA * size),
        "ratio_before_gross": before,
        "ratio_after_gross": RATIO_SIGMA,
        "gross_drop_n": PARTIAL_DROP_SIGMA * size,
        "partial_drop_n": PARTIAL_DROP_SIGMA * size,
        "recurrence_s": max(TIME_SIGMA_S, COUNT_SIGMA * size),
        "first_slip_s": TIME_SIGMA_S,
        "first_slip_ratio": before,
        "first_slip_place": float("nan"),
    }
    return scales[name]


def first_slip_x(simulation: xr.Dataset) -> float:
    """Centre of the first slip zone of the tangential loading, mm.

    The nodes that slipped in the first round of the first step with a wave.

    Parameters
    ----------
    simulation
        From :func:`slipwave.solver.simulate`.

    Returns
    -------
    float
        Its centre, mm from the contact's centre (NaN: no slip).

    """
    tangential = simulation["phase"].values == "tangential"
    waves = np.flatnonzero(tangential & (simulation["wave"].values != "none"))
    if waves.size == 0:
        return float("nan")
    first = simulation["cascade_round"].values[waves[0]] == 0
    return float(simulation["x"].values[first].mean())


def feature_summary(features: SlipFeatures) -> dict[str, float]:
    """One number per feature of :data:`FEATURES` (but the first slip's place).

    Parameters
    ----------
    features
        From :func:`slipwave.fit.slip_features`.

    Returns
    -------
    dict
        By :data:`FEATURES`' names; NaN where there is nothing to sum up.

    """
    gross = features.gross

    def median(column: str) -> float:
        values = gross[column].to_numpy(dtype=float)
        return float(np.median(values)) if values.size else float("nan")

    drops = features.partial_drops
    return {
        "gross_slips": float(len(gross)),
        "partial_slips": float(features.partial_slips),
        "ratio_before_gross": median("ratio_before"),
        "ratio_after_gross": median("ratio_after"),
        "gross_drop_n": median("drop"),
        "partial_drop_n": float(np.median(drops)) if drops.size else float("nan"),
        "recurrence_s": float(recurrence(gross)),
        "first_slip_s": features.first_time,
        "first_slip_ratio": features.first_ratio,
    }


def simulated_summary(setup: TestSetup, friction: Coulomb, elements: int, *,
                      min_drop: float, sample_rate: float,
                      detection: DetectionSettings = DEFAULT_DETECTION,
                      cache: SolverCache | None = None,
                      profile: Callable[[np.ndarray], np.ndarray] | None = None,
                      ) -> dict[str, float]:
    """The test simulated at one mesh, its features read as the fit reads them.

    Parameters
    ----------
    setup
        The test.
    friction
        The law.
    elements
        Elements along the contact.
    min_drop
        The smallest T drop that counts, N (the detection's).
    sample_rate
        Of the simulated recording, Hz.
    detection
        The detection's settings.
    cache
        The solver's cache.
    profile
        The slab's initial gap (e.g. :func:`slipwave.solver.slab.rounded_corners`);
        ``None``: flat, sharp corners.

    Returns
    -------
    dict
        :func:`feature_summary` and ``first_slip_place``.

    """
    simulation = setup.simulate(friction, elements, cache=cache, profile=profile)
    events = simulated_events(simulation, setup, min_drop=min_drop, sample_rate=sample_rate,
                              detection=detection)
    threshold = edge_threshold(simulation, edge_reference=setup.edge_reference)
    features = slip_features(events, gross_edge_ratio=threshold, min_drop=min_drop,
                             duration=setup["duration_s"], sample_rate=sample_rate)
    return {**feature_summary(features),
            "first_slip_place": first_slip_x(simulation) / setup["length_mm"]}


def mesh_changes(table: pd.DataFrame) -> pd.DataFrame:
    """How far each feature moves when the mesh is doubled.

    Parameters
    ----------
    table
        One row per law and mesh: ``law``, ``elements`` and the features of
        :data:`FEATURES`.

    Returns
    -------
    pandas.DataFrame
        ``law``, ``feature``, ``elements`` (the coarser mesh of each pair),
        ``value``, ``finer`` (at twice the elements), ``change`` (finer - value)
        and ``sigmas`` (the change in units of the fit's uncertainty of the finer
        value, :func:`feature_uncertainty`; 0 where the feature is absent at both
        meshes, NaN where at one only, and for the first slip's place).

    Examples
    --------
    >>> table = pd.DataFrame({"law": ["a", "a", "a"], "elements": [40, 80, 160],
    ...                       "gross_slips": [10.0, 12.0, 13.0]})
    >>> mesh_changes(table)[["elements", "change", "sigmas"]].to_numpy().tolist()
    [[40.0, 2.0, 0.6666666666666666], [80.0, 1.0, 0.3076923076923077]]
    """
    rows = []
    features = [name for name in FEATURES if name in table.columns]
    for law, group in table.groupby("law", sort=False):
        by_mesh = group.set_index("elements").sort_index()
        values = by_mesh[features].to_numpy(dtype=float)
        row_of = {int(n): k for k, n in enumerate(by_mesh.index)}
        for coarse, k in row_of.items():
            if 2 * coarse not in row_of:
                continue
            for j, feature in enumerate(features):
                value, finer = float(values[k, j]), float(values[row_of[2 * coarse], j])
                sigma = feature_uncertainty(feature, finer)
                sigmas = (finer - value) / sigma if sigma > 0 else np.nan
                if np.isnan(value) and np.isnan(finer):
                    sigmas = 0.0  # absent at both meshes (no partial slip, say)
                rows.append({"law": law, "feature": feature, "elements": coarse,
                             "value": value, "finer": finer, "change": finer - value,
                             "sigmas": sigmas})
    return pd.DataFrame(rows)


def converged_from(changes: pd.DataFrame, *, within: float = 1.0) -> pd.Series:
    """The coarsest mesh from which every doubling moves every feature by little.

    Parameters
    ----------
    changes
        From :func:`mesh_changes`.
    within
        The largest change allowed, in the fit's uncertainties (``sigmas``); a
        feature missing at either mesh of a pair (NaN) is a change beyond it.

    Returns
    -------
    pandas.Series
        By law: the element count from which every doubling studied stays within,
        or NaN where the finest doubling does not.

    Examples
    --------
    >>> changes = pd.DataFrame({"law": ["a"] * 3, "feature": ["f"] * 3,
    ...                         "elements": [40, 80, 160], "sigmas": [3.0, 0.5, 0.2]})
    >>> converged_from(changes).to_dict()
    {'a': 80.0}
    """
    result = {}
    for law, group in changes.groupby("law", sort=False):
        fitted = group[group["feature"] != "first_slip_place"]
        # a feature present at one mesh and not the other has moved by all it has
        moved = fitted["sigmas"].abs().fillna(np.inf)
        ok = (moved <= within).groupby(fitted["elements"]).all()
        start = float("nan")
        for elements in sorted(ok.index, reverse=True):
            if not ok[elements]:
                break
            start = float(elements)
        result[law] = start
    return pd.Series(result, dtype=float)
