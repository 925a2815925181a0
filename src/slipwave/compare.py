"""The compare stage: a test's measurement against its simulation, feature by feature.

:func:`compare_test` puts the measured events (detected with the threshold the
simulation set) beside the simulated recording's events, detected the same way, and
the video's waves beside the simulated zones: one row per feature with the measured
value, the simulated one, their difference, the tolerance and a verdict (``agrees``,
``differs``, or ``not compared`` with the reason). :func:`place_on_map` puts the test
on the behaviour map by its H/L and fitted static coefficient.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from slipwave.events.detect import detect_events

COMPARISON_COLUMNS = ("feature", "unit", "measured", "simulated", "difference", "tolerance",
                      "verdict", "note")
"""Columns of :func:`compare_test`."""


def _median(events: pd.DataFrame, column: str) -> float:
    values = events[column].to_numpy(dtype=float) if len(events) else np.array([])
    values = values[np.isfinite(values)]
    return float(np.median(values)) if values.size else float("nan")


def _row(feature: str, unit: str, measured: float, simulated: float, tolerance: float,
         relative: bool = False, note: str = "") -> dict[str, Any]:
    """One feature: the verdict from |simulated - measured| against the tolerance."""
    difference = simulated - measured
    allowed = tolerance * abs(measured) if relative else tolerance
    if relative and np.isfinite(measured):
        allowed = max(allowed, 1e-12)
    if not (np.isfinite(measured) and np.isfinite(simulated)):
        verdict = "not compared"
        note = note or ("not measured" if not np.isfinite(measured) else "not simulated")
    else:
        verdict = "agrees" if abs(difference) <= allowed else "differs"
    return {"feature": feature, "unit": unit, "measured": measured, "simulated": simulated,
            "difference": difference, "tolerance": allowed, "verdict": verdict, "note": note}


def _count_row(feature: str, measured: int, simulated: int, *, floor: float,
               fraction: float) -> dict[str, Any]:
    row = _row(feature, "1", float(measured), float(simulated),
               max(floor, fraction * measured))
    return row


def _first_wave(simulation: xr.Dataset) -> tuple[float, str]:
    """Where the first wave of the tangential loading began, and the way gross slips swept."""
    wave = simulation["wave"].values
    tangential = simulation["phase"].values == "tangential"
    order = simulation["cascade_round"].values
    x = simulation["x"].values
    steps = np.flatnonzero(tangential & (wave != "none"))
    if not steps.size:
        return float("nan"), ""
    first = order[steps[0]]
    origin = float(x[(first >= 0) & (first <= np.quantile(first[first >= 0], 0.1))].mean())
    ways = []
    for k in np.flatnonzero(tangential & (wave == "gross")):
        slipped = order[k] >= 0
        start = x[slipped & (order[k] <= np.quantile(order[k][slipped], 0.1))].mean()
        end = x[slipped & (order[k] >= np.quantile(order[k][slipped], 0.9))].mean()
        ways.append("right_to_left" if end < start else "left_to_right")
    way = max(set(ways), key=ways.count) if ways else ""
    return origin, way


def compare_test(measured: pd.DataFrame, simulated_recording: xr.Dataset,
                 simulation: xr.Dataset | None = None, waves: pd.DataFrame | None = None,
                 *, min_drop: float | None = None) -> pd.DataFrame:
    """Measured against simulated, one row per feature.

    Parameters
    ----------
    measured
        The test's events (``slipwave detect`` with the simulation's
        ``gross_edge_ratio``).
    simulated_recording
        The simulated recording (:func:`slipwave.bench.replay.replay_test`), whose
        attrs carry ``gross_edge_ratio``.
    simulation
        The solver's steps, for where the first wave began and the way gross slips
        swept; ``None``: those rows are not compared.
    waves
        The video's waves (``slipwave waves``); ``None``: no video rows.
    min_drop
        The measurement's smallest drop (N), used for the simulated events too.

    Returns
    -------
    pandas.DataFrame
        :data:`COMPARISON_COLUMNS`; ``attrs["simulated_events"]`` holds the simulated
        events.

    """
    simulated = detect_events(simulated_recording, min_drop=min_drop, edge_convention="x_axis",
                              gross_edge_ratio=float(
                                  simulated_recording.attrs.get("gross_edge_ratio", 0.9)))
    m_gross = measured[measured["kind"] == "gross_slip"]
    s_gross = simulated[simulated["kind"] == "gross_slip"]
    m_partial = measured[measured["kind"] == "partial_slip"]
    s_partial = simulated[simulated["kind"] == "partial_slip"]
    rows = [
        _count_row("gross slips", len(m_gross), len(s_gross), floor=1, fraction=0.1),
        _count_row("partial slips", len(m_partial), len(s_partial), floor=3, fraction=0.3),
        _row("T/|N| at gross slips, before (static)", "1", _median(m_gross, "ratio_before"),
             _median(s_gross, "ratio_before"), 0.02),
        _row("T/|N| at gross slips, after (dynamic)", "1", _median(m_gross, "ratio_after"),
             _median(s_gross, "ratio_after"), 0.02),
        _row("T drop of gross slips (median)", "N", _median(m_gross, "drop"),
             _median(s_gross, "drop"), 0.1, relative=True),
        _row("T drop of partial slips (median)", "N", _median(m_partial, "drop"),
             _median(s_partial, "drop"), 0.3, relative=True),
        _row("recurrence of gross slips (median interval)", "s",
             float(np.median(np.diff(m_gross["t_start"]))) if len(m_gross) > 1 else np.nan,
             float(np.median(np.diff(s_gross["t_start"]))) if len(s_gross) > 1 else np.nan,
             0.1, relative=True),
    ]
    first_m = float(m_gross["t_start"].min()) if len(m_gross) else np.nan
    first_s = float(s_gross["t_start"].min()) if len(s_gross) else np.nan
    rows.append(_row("time of the first gross slip", "s", first_m, first_s,
                     max(2.0, 0.05 * first_m) if np.isfinite(first_m) else 2.0))
    for channel in ("DG", "DD"):
        rows.append(_row(f"{channel} jump at gross slips (median, along +x)", "mm",
                         _median(m_gross, f"{channel}_jump"), _median(s_gross, f"{channel}_jump"),
                         0.2, relative=True))
    rows.append(_row("DG/DD jump ratio at gross slips (median)", "1",
                     _median(m_gross, "edge_ratio"), _median(s_gross, "edge_ratio"), 0.2,
                     relative=True))
    origin, way = _first_wave(simulation) if simulation is not None else (np.nan, "")
    if waves is not None and len(waves):
        rows.append(_row("first slip: where the first wave began (video)", "mm",
                         float(waves["x_start"].iloc[0]), origin, 10.0))
        seen = waves.loc[waves["kind"] == "gross", "direction"]
        measured_way = seen.mode().iloc[0] if len(seen) else ""
        same = bool(measured_way) and bool(way) and measured_way == way
        rows.append({"feature": "way gross slips sweep (video vs zones)", "unit": "",
                     "measured": measured_way or "none seen", "simulated": way or "none",
                     "difference": "", "tolerance": "same way",
                     "verdict": ("agrees" if same else "differs") if measured_way and way
                     else "not compared", "note": ""})
        rows.append({"feature": "wave speed (video)", "unit": "mm/s",
                     "measured": _median(waves, "speed"), "simulated": float("nan"),
                     "difference": float("nan"), "tolerance": float("nan"),
                     "verdict": "not compared",
                     "note": "the solver is quasi-static: its slips have no speed"})
    else:
        for feature in ("first slip: where the first wave began (video)",
                        "way gross slips sweep (video vs zones)", "wave speed (video)"):
            rows.append({"feature": feature, "unit": "", "measured": float("nan"),
                         "simulated": float("nan"), "difference": float("nan"),
                         "tolerance": float("nan"), "verdict": "not compared",
                         "note": "no video"})
    table = pd.DataFrame(rows, columns=list(COMPARISON_COLUMNS))
    table.attrs["simulated_events"] = simulated
    return table


def place_on_map(behaviour_map: xr.Dataset, height_ratio: float, friction: float
                 ) -> dict[str, Any]:
    """The test's place on the behaviour map: the nearest case to its H/L and f.

    Parameters
    ----------
    behaviour_map
        ``results/map/map.nc`` (:func:`slipwave.map.assemble_map`).
    height_ratio
        The slab's H/L.
    friction
        The fitted static coefficient.

    Returns
    -------
    dict
        ``height_ratio``, ``friction`` (the test's), ``map_height_ratio``,
        ``map_friction`` (the case's), ``behaviour``, ``sequence``, ``inside_map``.

    """
    case = behaviour_map.sel(height_ratio=height_ratio, friction=friction, method="nearest")
    number = int(case["behaviour"])  # numbered from 1, along behaviour_id
    name = str(behaviour_map["behaviour_name"].sel(behaviour_id=number).values)
    h = behaviour_map["height_ratio"].values
    f = behaviour_map["friction"].values
    return {"height_ratio": height_ratio, "friction": friction,
            "map_height_ratio": float(case["height_ratio"]),
            "map_friction": float(case["friction"]), "behaviour": name,
            "sequence": str(case["sequence"].values),
            "inside_map": bool(h.min() <= height_ratio <= h.max()
                               and f.min() <= friction <= f.max())}


def verdict_counts(table: pd.DataFrame) -> Mapping[str, int]:
    """How many features agree, differ, or were not compared.

    Parameters
    ----------
    table
        From :func:`compare_test`.

    Returns
    -------
    dict
        ``agrees``, ``differs``, ``not compared``: counts.

    """
    return {verdict: int((table["verdict"] == verdict).sum())
            for verdict in ("agrees", "differs", "not compared")}
