"""The compare stage: a test's measurement against its simulation, feature by feature.

:func:`compare_test` puts the measured events (detected with the threshold the
simulation set) beside the simulated recording's events, detected the same way, and
the video's waves beside the simulated zones: one row per feature with the measured
value, the simulated one, the simulation's own scatter, their difference, the
tolerance and a verdict (``agrees``, ``differs``, or ``not compared`` with the
reason). :func:`place_on_map` puts the test on the behaviour map by its H/L and fitted
static coefficient.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from slipwave.defaults import LOAD_CALIBRATION
from slipwave.errors import SlipwaveError
from slipwave.events.detect import DEFAULT_DETECTION, DetectionSettings, detect_events
from slipwave.validation import read_json
from slipwave.video.waves import MIN_EXTENT

COMPARISON_COLUMNS = ("feature", "unit", "measured", "simulated", "scatter", "difference",
                      "tolerance", "verdict", "note")
"""Columns of :func:`compare_test`."""


@dataclass(frozen=True)
class Feature:
    """A feature of a test's events, and how closely it must be reproduced.

    Attributes
    ----------
    name, unit
        As the comparison names it.
    tolerance
        What the measurement itself allows: absolute, or a fraction of the measured
        value with ``relative``, at least ``floor``.
    relative, floor
        See ``tolerance``.

    """

    name: str
    unit: str
    tolerance: float
    relative: bool = False
    floor: float = 0.0

    def allowed(self, measured: float) -> float:
        """The measurement's own tolerance at a measured value.

        Parameters
        ----------
        measured
            The measured value.

        Returns
        -------
        float
            The tolerance (NaN where nothing was measured).

        """
        if not np.isfinite(measured):
            return float("nan")
        return max(self.floor, self.tolerance * abs(measured) if self.relative
                   else self.tolerance)


EVENT_FEATURES = (
    Feature("gross slips", "1", 0.1, relative=True, floor=1.0),
    Feature("partial slips", "1", 0.3, relative=True, floor=3.0),
    Feature("T/|N| at gross slips, before (static)", "1", 0.02),
    Feature("T/|N| at gross slips, after (dynamic)", "1", 0.02),
    Feature("T drop of gross slips (median)", "N", 0.1, relative=True, floor=1e-12),
    Feature("T drop of partial slips (median)", "N", 0.3, relative=True, floor=1e-12),
    Feature("recurrence of gross slips (median interval)", "s", 0.1, relative=True,
            floor=1e-12),
    Feature("time of the first gross slip", "s", 0.05, relative=True, floor=2.0),
    Feature("DG jump at gross slips (median, along +x)", "mm", 0.2, relative=True,
            floor=1e-12),
    Feature("DD jump at gross slips (median, along +x)", "mm", 0.2, relative=True,
            floor=1e-12),
    Feature("DG/DD jump ratio at gross slips (median)", "1", 0.2, relative=True, floor=1e-12),
)
"""The features read off the events of a recording (:func:`event_features`), in the
comparison's order."""

ORIGIN = Feature("first slip: where the first wave began (video)", "mm", 10.0)
"""Where the first wave began: the video's against the simulated zones'."""

SCATTER_STEP = LOAD_CALIBRATION
"""How far apart the coefficients of :func:`slipwave.simulate.sequence_scatter`'s
neighbouring simulations are by default (relative): the load cells' calibration, within
which no measurement tells two coefficients apart (the simulate stage takes the fit's,
``fit.load_calibration``)."""


def _median(events: pd.DataFrame, column: str) -> float:
    values = events[column].to_numpy(dtype=float) if len(events) else np.array([])
    values = values[np.isfinite(values)]
    return float(np.median(values)) if values.size else float("nan")


def recurrence(gross: pd.DataFrame) -> float:
    """The median interval between gross slips.

    Parameters
    ----------
    gross
        The gross slips' events (``t_start``, s).

    Returns
    -------
    float
        The median interval, s (NaN with fewer than two slips).

    """
    times = gross["t_start"].to_numpy(dtype=float)
    return float(np.median(np.diff(times))) if times.size > 1 else float("nan")


def event_features(events: pd.DataFrame) -> dict[str, float]:
    """The values of :data:`EVENT_FEATURES` in one recording's events.

    Parameters
    ----------
    events
        Classified events (:func:`~slipwave.events.detect_events`).

    Returns
    -------
    dict
        Feature name to value (NaN where the events have none: a median of no gross
        slip, a recurrence of one).

    Examples
    --------
    >>> events = pd.DataFrame({"kind": ["partial_slip", "gross_slip", "gross_slip"],
    ...                        "t_start": [5.0, 10.0, 40.0], "drop": [0.5, 8.0, 6.0],
    ...                        "ratio_before": [0.8, 0.9, 0.95], "ratio_after": [0.78, 0.6, 0.62],
    ...                        "DG_jump": [0.0, 1.0, 1.2], "DD_jump": [0.1, 1.0, 1.0],
    ...                        "edge_ratio": [0.0, 1.0, 1.2]})
    >>> features = event_features(events)
    >>> features["gross slips"], features["recurrence of gross slips (median interval)"]
    (2.0, 30.0)
    """
    gross = events[events["kind"] == "gross_slip"]
    partial = events[events["kind"] == "partial_slip"]
    times = gross["t_start"].to_numpy(dtype=float)
    values = [float(len(gross)), float(len(partial)), _median(gross, "ratio_before"),
              _median(gross, "ratio_after"), _median(gross, "drop"), _median(partial, "drop"),
              recurrence(gross), float(times.min()) if times.size else float("nan"),
              _median(gross, "DG_jump"), _median(gross, "DD_jump"), _median(gross, "edge_ratio")]
    return dict(zip((feature.name for feature in EVENT_FEATURES), values, strict=True))


def spread(values: Sequence[float]) -> float:
    """A feature's standard deviation over neighbouring simulations.

    Parameters
    ----------
    values
        The feature's values, the simulation's and its neighbours'.

    Returns
    -------
    float
        Their sample standard deviation, non-finite values left out (0 with fewer
        than two finite ones).

    Examples
    --------
    >>> spread([10.0, 8.0, float("nan"), 9.0])
    1.0
    """
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    return float(np.std(finite, ddof=1)) if finite.size > 1 else 0.0


def _row(feature: Feature, measured: float, simulated: float, scatter: float,
         unknown: str = "not measured", *, tolerance: float | None = None,
         untold: str = "") -> dict[str, Any]:
    """One feature: the verdict from |simulated - measured| against the tolerance.

    The tolerance joins what the measurement allows with twice the simulation's own
    scatter (``scatter``, a standard deviation), in quadrature; ``unknown`` is the note
    when nothing was measured. A ``tolerance`` given stands for what the measurement
    allows (two samples' own error); where it is not finite the feature is not
    compared, ``untold`` saying why.
    """
    difference = simulated - measured
    own = feature.allowed(measured) if tolerance is None else tolerance
    allowed = float(np.hypot(own, 2.0 * scatter))
    note = ""
    if not (np.isfinite(measured) and np.isfinite(simulated)):
        verdict = "not compared"
        note = unknown if not np.isfinite(measured) else "not simulated"
    elif not np.isfinite(allowed):
        verdict, note = "not compared", untold
    else:
        verdict = "agrees" if abs(difference) <= allowed else "differs"
        if verdict == "agrees" and abs(difference) > own:
            note = "within the law's own scatter"
    return {"feature": feature.name, "unit": feature.unit, "measured": measured,
            "simulated": simulated, "scatter": scatter, "difference": difference,
            "tolerance": allowed, "verdict": verdict, "note": note}


def first_wave(simulation: xr.Dataset, *, min_extent: float = MIN_EXTENT
               ) -> tuple[float, str]:
    """Where the first wave the video could see began, and the way gross slips swept.

    Parameters
    ----------
    simulation
        The solver's steps (:func:`slipwave.solver.simulate`).
    min_extent
        The smallest part of the contact a wave's slip must span to count, as the
        video's tracker (:func:`slipwave.video.track_waves`) asks: the first slips of
        the tangential loading are a few nodes at an edge, which no video shows.

    Returns
    -------
    tuple
        The first such wave's origin along x (mm: where its cascade's first tenth of
        rounds slipped; NaN without one) and the way most gross slips swept
        (``left_to_right``, ``right_to_left``, or ``""``).

    """
    wave = simulation["wave"].values
    tangential = simulation["phase"].values == "tangential"
    order = simulation["cascade_round"].values
    x = simulation["x"].values
    length = float(np.ptp(x))
    seen = [k for k in np.flatnonzero(tangential & (wave != "none"))
            if np.ptp(x[order[k] >= 0]) >= min_extent * length]
    if not seen:
        return float("nan"), ""
    first = order[seen[0]]
    origin = float(x[(first >= 0) & (first <= np.quantile(first[first >= 0], 0.1))].mean())
    ways = []
    for k in np.flatnonzero(tangential & (wave == "gross")):
        slipped = order[k] >= 0
        start = x[slipped & (order[k] <= np.quantile(order[k][slipped], 0.1))].mean()
        end = x[slipped & (order[k] >= np.quantile(order[k][slipped], 0.9))].mean()
        ways.append("right_to_left" if end < start else "left_to_right")
    way = max(set(ways), key=ways.count) if ways else ""
    return origin, way


MEDIAN_ERROR = 0.929
"""The standard error of a sample's median, times the square root of its size, over its
interquartile range (1.2533 sigma / 1.349 sigma, for a normal sample)."""

QUARTILES_ERROR = 1.166
"""The same for its interquartile range (1.573 sigma / 1.349 sigma)."""

WAVE_SPEED = Feature("wave speed, median (video vs quasi-dynamic)", "mm/s", 0.0)
WAVE_SPEED_SPREAD = Feature("wave speed, interquartile range (video vs quasi-dynamic)",
                            "mm/s", 0.0)
FIRST_WAVE_START = Feature("first wave: where it began (video vs quasi-dynamic)", "mm",
                           ORIGIN.tolerance)
WHOLE_CONTACT = Feature("share of waves over the whole contact (video vs quasi-dynamic)",
                        "1", 0.0)
FOLLOWED = Feature("share of waves the camera could follow (video vs quasi-dynamic)", "1",
                   0.0)
WAVE_FEATURES = (WAVE_SPEED.name, WAVE_SPEED_SPREAD.name, FIRST_WAVE_START.name,
                 "first wave: the way it ran (video vs quasi-dynamic)", WHOLE_CONTACT.name,
                 FOLLOWED.name)
"""The rows of :func:`compare_waves`, in order."""


def _sampled_row(feature: Feature, measured: np.ndarray, simulated: np.ndarray,
                 statistic: str) -> dict[str, Any]:
    """A statistic of two samples of waves, within twice its standard error.

    ``statistic`` is ``median`` or ``quartiles`` (the interquartile range); each
    side's standard error is its :data:`MEDIAN_ERROR` or :data:`QUARTILES_ERROR` times
    its interquartile range over the root of its size, joined in quadrature.
    """
    factor = MEDIAN_ERROR if statistic == "median" else QUARTILES_ERROR
    values, errors = [], []
    for sample in (measured, simulated):
        sample = sample[np.isfinite(sample)]
        if sample.size < 2:
            values.append(float(np.median(sample)) if sample.size and statistic == "median"
                          else float("nan"))
            errors.append(float("nan"))
            continue
        quartiles = float(np.subtract(*np.percentile(sample, [75, 25])))
        values.append(float(np.median(sample)) if statistic == "median" else quartiles)
        errors.append(factor * quartiles / np.sqrt(sample.size))
    return _row(feature, values[0], values[1], 0.0,
                unknown="fewer than two waves with a speed" if statistic != "median"
                else "no wave with a speed",
                tolerance=2.0 * float(np.hypot(errors[0], errors[1])),
                untold="fewer than two waves on a side")


def compare_waves(measured: pd.DataFrame, simulated: pd.DataFrame) -> pd.DataFrame:
    """The video's waves against a simulation's, one row per feature.

    Both tables are in :data:`slipwave.io.tables.WAVE_COLUMNS` (the video's
    :func:`slipwave.video.track_waves`, a quasi-dynamic simulation's). The wave speed's median and
    interquartile range agree when they differ by at most twice their standard error
    from the two samples (:data:`MEDIAN_ERROR`, :data:`QUARTILES_ERROR`); the first
    wave's start within the video's origin tolerance (:data:`ORIGIN`), its way when the
    same; the share of waves that sweep the whole contact (``kind`` gross), and the share
    the camera could follow (not ``unresolved``), each within twice its binomial standard
    error from both samples. Compare waves measured alike: a simulation filmed
    (:func:`slipwave.simulate_waves.film_kymograph`), whose fronts faster than the frames
    show as the camera shows them.

    Parameters
    ----------
    measured
        The video's waves.
    simulated
        The simulated waves.

    Returns
    -------
    pandas.DataFrame
        :data:`COMPARISON_COLUMNS`, the rows :data:`WAVE_FEATURES`.

    Examples
    --------
    >>> video = pd.DataFrame({"speed": [200.0, 230.0, 210.0, 250.0], "x_start": 38.0,
    ...                       "direction": "right_to_left",
    ...                       "kind": ["partial", "gross", "partial", "gross"]})
    >>> simulated = video.assign(speed=[6000.0, 6500.0, 5800.0, 7000.0])
    >>> compare_waves(video, simulated).set_index("feature")["verdict"].tolist()
    ['differs', 'agrees', 'agrees', 'agrees', 'agrees', 'agrees']
    """
    resolved = [table[table["kind"] != "unresolved"] for table in (measured, simulated)]
    speeds = [table["speed"].to_numpy(dtype=float) for table in resolved]
    rows = [_sampled_row(WAVE_SPEED, speeds[0], speeds[1], "median"),
            _sampled_row(WAVE_SPEED_SPREAD, speeds[0], speeds[1], "quartiles")]
    firsts = [table.iloc[0] if len(table) else None for table in resolved]
    starts = [float(first["x_start"]) if first is not None else float("nan")
              for first in firsts]
    rows.append(_row(FIRST_WAVE_START, starts[0], starts[1], 0.0, unknown="no wave"))
    ways = [str(first["direction"]) if first is not None else "" for first in firsts]
    rows.append({"feature": WAVE_FEATURES[3], "unit": "", "measured": ways[0] or "none",
                 "simulated": ways[1] or "none", "scatter": float("nan"), "difference": "",
                 "tolerance": "same way",
                 "verdict": ("agrees" if ways[0] == ways[1] else "differs")
                 if ways[0] and ways[1] else "not compared",
                 "note": "" if ways[0] and ways[1] else "no wave"})
    rows.append(_share_row(WHOLE_CONTACT, [table["kind"] == "gross"
                                           for table in (measured, simulated)]))
    # a slip faster than the frames is one the tracker cannot follow: its speed is not a
    # front's, so the share it follows tells fast fronts from slow ones
    rows.append(_share_row(FOLLOWED, [table["kind"] != "unresolved"
                                      for table in (measured, simulated)]))
    return pd.DataFrame(rows, columns=list(COMPARISON_COLUMNS))


def _share_row(feature: Feature, counted: list[pd.Series]) -> dict[str, Any]:
    """The share of waves counted on each side, within twice its binomial standard error."""
    shares = [float(flags.mean()) if len(flags) else float("nan") for flags in counted]
    sizes = [len(flags) for flags in counted]
    tolerance = float("nan")
    if min(sizes):
        pooled = (shares[0] * sizes[0] + shares[1] * sizes[1]) / (sizes[0] + sizes[1])
        # a share seen in a handful of waves is uncertain by at least one wave in either
        pooled = min(max(pooled, 1.0 / sum(sizes)), 1.0 - 1.0 / sum(sizes))
        tolerance = 2.0 * float(np.sqrt(pooled * (1 - pooled)
                                        * (1.0 / sizes[0] + 1.0 / sizes[1])))
    return _row(feature, shares[0], shares[1], 0.0, unknown="no wave", tolerance=tolerance)


def compare_test(measured: pd.DataFrame, simulated_recording: xr.Dataset,
                 simulation: xr.Dataset | None = None, waves: pd.DataFrame | None = None,
                 *, min_drop: float | None = None, scatter: pd.DataFrame | None = None,
                 detection: DetectionSettings = DEFAULT_DETECTION,
                 simulated_waves: pd.DataFrame | None = None) -> pd.DataFrame:
    """Measured against simulated, one row per feature.

    A feature agrees when the difference lies within its tolerance: what the
    measurement allows (:data:`EVENT_FEATURES`), joined in quadrature with twice the
    simulation's own scatter, the standard deviation of the feature over the
    simulation and its neighbours (``scatter``). Under fs > fd the law settles in
    cycles that change by whole slips with coefficients closer than any measurement
    tells apart, so that what it cannot fix is not held against it.

    Parameters
    ----------
    measured
        The test's events (``slipwave detect`` with the simulation's
        ``gross_edge_ratio``).
    simulated_recording
        The simulated recording (:func:`slipwave.simulate.replay_test`), whose
        attrs carry ``gross_edge_ratio``.
    simulation
        The solver's steps, for where the first wave began and the way gross slips
        swept; ``None``: those rows are not compared.
    waves
        The video's waves (``slipwave waves``); ``None``: no video rows.
    min_drop
        The measurement's smallest drop (N), used for the simulated events too.
    scatter
        The features of neighbouring simulations
        (:func:`slipwave.simulate.sequence_scatter`), one row each; ``None``: no
        scatter (the measurement's tolerances alone).
    detection
        The detection's settings (the measurement's), for the simulated events.
    simulated_waves
        The waves of the test simulated quasi-dynamically (``slipwave simulate-waves``):
        with the video's, the rows of :func:`compare_waves`; ``None``: the wave speed is
        not compared (the quasi-static solver's slips have none).

    Returns
    -------
    pandas.DataFrame
        :data:`COMPARISON_COLUMNS`; ``attrs["simulated_events"]`` holds the simulated
        events.

    """
    if "gross_edge_ratio" not in simulated_recording.attrs:
        raise SlipwaveError(f"{simulated_recording.attrs.get('source', 'the simulation')}: "
                            "no gross_edge_ratio: not a recording of 'slipwave simulate --fit'")
    simulated = detect_events(simulated_recording, **detection.keywords(
        min_drop=min_drop, edge_convention="x_axis",
        gross_edge_ratio=float(simulated_recording.attrs["gross_edge_ratio"])))
    measured_values = event_features(measured)
    simulated_values = event_features(simulated)
    origin, way = first_wave(simulation) if simulation is not None else (np.nan, "")
    simulated_values[ORIGIN.name] = origin

    def scatter_of(name: str) -> float:
        if scatter is None or name not in scatter:
            return 0.0
        return spread([simulated_values[name], *scatter[name].to_numpy(dtype=float)])

    rows = [_row(feature, measured_values[feature.name], simulated_values[feature.name],
                 scatter_of(feature.name)) for feature in EVENT_FEATURES]
    if waves is not None and len(waves):
        if waves["kind"].iloc[0] == "unresolved":
            rows.append(_row(ORIGIN, float("nan"), origin, 0.0, unknown="the video's first "
                             "wave was too fast to tell where it began"))
        else:
            rows.append(_row(ORIGIN, float(waves["x_start"].iloc[0]), origin,
                             scatter_of(ORIGIN.name)))
        seen = waves.loc[waves["kind"] == "gross", "direction"]
        measured_way = seen.mode().iloc[0] if len(seen) else ""
        same = bool(measured_way) and bool(way) and measured_way == way
        rows.append({"feature": "way gross slips sweep (video vs zones)", "unit": "",
                     "measured": measured_way or "none seen", "simulated": way or "none",
                     "scatter": float("nan"), "difference": "", "tolerance": "same way",
                     "verdict": ("agrees" if same else "differs") if measured_way and way
                     else "not compared", "note": ""})
        if simulated_waves is not None:
            rows.extend({str(key): value for key, value in row.items()}
                        for row in compare_waves(waves, simulated_waves).to_dict("records"))
        else:
            rows.append({"feature": WAVE_SPEED.name, "unit": "mm/s",
                         "measured": _median(waves, "speed"), "simulated": float("nan"),
                         "scatter": float("nan"), "difference": float("nan"),
                         "tolerance": float("nan"), "verdict": "not compared",
                         "note": "not simulated quasi-dynamically: the quasi-static "
                                 "solver's slips have no speed"})
    else:
        for feature in (ORIGIN.name, "way gross slips sweep (video vs zones)",
                        *(WAVE_FEATURES if simulated_waves is not None
                          else (WAVE_SPEED.name,))):
            rows.append({"feature": feature, "unit": "", "measured": float("nan"),
                         "simulated": float("nan"), "scatter": float("nan"),
                         "difference": float("nan"), "tolerance": float("nan"),
                         "verdict": "not compared", "note": "no video"})
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
        ``map_friction`` (the case's), ``behaviour``, ``sequence``, ``inside_map``,
        ``in_mesh_band`` (whether the case lies in the band where the map still moves
        with the mesh; false when the map has no band).

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
                               and f.min() <= friction <= f.max()),
            "in_mesh_band": bool(case["mesh_band"]) if "mesh_band" in case else False}


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


def read_comparison(path: str | PathLike[str]) -> dict[str, Any]:
    """A comparison's JSON (``slipwave compare --json``), checked.

    Parameters
    ----------
    path
        The file.

    Returns
    -------
    dict
        ``test_id``, ``recording_sha256``, ``law``, ``parameters``, ``verdicts``,
        when placed ``map``, and when compared with a scatter ``scatter_left_out``
        (:func:`slipwave.simulate.left_out_neighbours`).

    Raises
    ------
    SlipwaveError
        Naming the file and the key that is wrong.

    """
    return read_json(path, "comparison")
