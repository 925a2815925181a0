"""The summary stage: what the events say about a test (phases, T/|N|, wave counts)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr
from scipy import stats

from slipwave.errors import warning_lines

PHASES = ("normal_loading", "stick", "partial_slip", "gross_slip", "unclassified_slip")
"""Phase labels of :func:`segment_phases` (``unclassified_slip``: a T drop whose kind is
not known, without DG and DD)."""

KINDS = ("partial_slip", "gross_slip")


def load_ratio(recording: xr.Dataset, *, min_fraction: float = 0.05) -> xr.DataArray:
    """T/|N|, the apparent friction ratio, along the recording.

    Parameters
    ----------
    recording
        A Dataset from :func:`slipwave.io.read_acquisition`.
    min_fraction
        Where |N| is below this fraction of its maximum (the start of normal
        loading) the ratio is meaningless and set to NaN.

    Returns
    -------
    xarray.DataArray
        ``T_over_N`` along ``time``, dimensionless.

    Examples
    --------
    The first sample, at |N| = 1 N < 5 % of 85 N, is masked:

    >>> import xarray as xr
    >>> ds = xr.Dataset({"T": ("time", [0.0, 40.0, 85.0]), "N": ("time", [-1.0, -80.0, -85.0])})
    >>> load_ratio(ds).values.round(2).tolist()
    [nan, 0.5, 1.0]

    """
    compressive = abs(recording["N"])
    floor = min_fraction * float(compressive.max(skipna=True))
    ratio = (recording["T"] / compressive).where(compressive > floor)
    ratio.attrs = {"units": "1", "long_name": "T/|N|, tangential over compressive normal load"}
    return ratio.rename("T_over_N")


def normal_loading_end(recording: xr.Dataset, *, plateau_fraction: float = 0.98) -> int:
    """Index of the first sample where |N| reaches its plateau.

    The plateau is the median |N| over the second half of the recording; the
    normal loading ends where |N| first reaches ``plateau_fraction`` of it.

    Parameters
    ----------
    recording
        With ``N``.
    plateau_fraction
        Fraction of the plateau that ends the normal loading.

    Returns
    -------
    int
        The sample index (the recording's length if never reached).

    Examples
    --------
    >>> ds = xr.Dataset({"N": ("time", -np.minimum(np.arange(20.0), 10.0))})
    >>> normal_loading_end(ds)
    10
    """
    if "N" not in recording or not np.isfinite(recording["N"].values).any():
        return 0  # a force-only record: its normal loading is not known
    normal = np.abs(recording["N"].values.astype(float))
    plateau = float(np.nanmedian(normal[normal.size // 2:]))
    reached = np.flatnonzero(normal >= plateau_fraction * plateau)
    return int(reached[0]) if reached.size else normal.size


def segment_phases(recording: xr.Dataset, events: pd.DataFrame) -> xr.DataArray:
    """The phase of every sample: normal loading, stick, partial or gross slip.

    Samples before |N| reaches its plateau (:func:`normal_loading_end`) are
    ``normal_loading``; samples from an event's onset to its end take the
    event's kind (gross wins where events overlap; an unclassified event, a T
    drop without DG and DD, is ``unclassified_slip``, never partial or gross);
    the rest is ``stick``. Without N the normal loading is not known (none).
    Phases are CF flags: one byte per sample, the codes of :data:`PHASES` (a
    label per sample would take seven times the memory of the signal);
    :func:`phase_labels` gives the labels.

    Parameters
    ----------
    recording
        With ``N`` (and ``time``).
    events
        From :func:`~slipwave.events.detect_events`.

    Returns
    -------
    xarray.DataArray
        ``phase`` along ``time``, int8 codes with CF ``flag_values`` and
        ``flag_meanings`` (:data:`PHASES`).

    Examples
    --------
    >>> ds = xr.Dataset({"N": ("time", np.r_[-np.arange(5.0), np.full(10, -5.0)])},
    ...                 coords={"time": np.arange(15.0)})
    >>> events = pd.DataFrame({"kind": ["gross_slip"], "i_start": [9], "i_end": [11]})
    >>> phase = phase_labels(segment_phases(ds, events)).tolist()
    >>> phase[4:6], phase[9:13]
    (['normal_loading', 'stick'], ['stick', 'gross_slip', 'gross_slip', 'stick'])
    """
    size = recording.sizes["time"]
    code = np.full(size, PHASES.index("stick"), dtype=np.int8)
    code[: normal_loading_end(recording)] = PHASES.index("normal_loading")
    for kind in ("unclassified", "partial_slip", "gross_slip"):
        chosen = events[events["kind"] == kind]
        value = PHASES.index("unclassified_slip" if kind == "unclassified" else kind)
        for start, end in zip(chosen["i_start"], chosen["i_end"], strict=True):
            code[int(start) + 1 : int(end) + 1] = value
    phase = xr.DataArray(code, dims="time", name="phase",
                         coords={"time": recording["time"]} if "time" in recording.coords
                         else None)
    phase.attrs = {"long_name": "phase of the test",
                   "flag_values": np.arange(len(PHASES), dtype=np.int8),
                   "flag_meanings": " ".join(PHASES)}
    return phase


def _spread(values: np.ndarray, confidence: float) -> dict[str, float]:
    """Mean, standard deviation and a Student-t confidence interval of the mean."""
    count = values.size
    mean = float(values.mean()) if count else np.nan
    std = float(values.std(ddof=1)) if count > 1 else np.nan
    if count > 1:
        half = float(stats.t.ppf(0.5 + confidence / 2, count - 1)) * std / np.sqrt(count)
    else:
        half = np.nan
    return {"mean": mean, "std": std, "ci_low": mean - half, "ci_high": mean + half}


def friction_ratio(events: pd.DataFrame, *, confidence: float = 0.95) -> xr.Dataset:
    """T/|N| at each gross slip, before the drop (static) and after it (dynamic).

    Parameters
    ----------
    events
        From :func:`~slipwave.events.detect_events`.
    confidence
        Level of the confidence interval of the means (Student t).

    Returns
    -------
    xarray.Dataset
        ``static`` and ``dynamic`` along ``slip`` (with ``time``, the onsets),
        and scalars ``static_mean``, ``static_std``, ``static_ci_low``,
        ``static_ci_high`` and the same for ``dynamic``. No gross slip: empty
        ``slip`` and NaN scalars.

    Examples
    --------
    >>> events = pd.DataFrame({"kind": ["gross_slip"] * 3 + ["partial_slip"],
    ...                        "t_start": [1.0, 2.0, 3.0, 4.0],
    ...                        "ratio_before": [0.9, 1.0, 1.1, 0.5],
    ...                        "ratio_after": [0.6, 0.6, 0.6, 0.45]})
    >>> ratio = friction_ratio(events)
    >>> float(ratio["static_mean"]), round(float(ratio["static_ci_high"]), 3)
    (1.0, 1.248)
    """
    gross = events[events["kind"] == "gross_slip"]
    data: dict[str, tuple] = {}
    for name, column, meaning in (("static", "ratio_before", "before the drop (peak)"),
                                  ("dynamic", "ratio_after", "after the drop")):
        values = gross[column].to_numpy(dtype=float)
        values = values[np.isfinite(values)] if values.size else values
        data[name] = ("slip", gross[column].to_numpy(dtype=float),
                      {"units": "1", "long_name": f"T/|N| at gross slips, {meaning}"})
        for key, value in _spread(values, confidence).items():
            data[f"{name}_{key}"] = ((), value, {
                "units": "1",
                "long_name": f"{key.replace('_', ' ')} of the {name} T/|N|"
                + (f" ({confidence:.0%} confidence, Student t)" if "ci" in key else ""),
            })
    return xr.Dataset(
        data,
        coords={"time": ("slip", gross["t_start"].to_numpy(dtype=float),
                         {"units": "s", "long_name": "onset of the gross slip"})},
        attrs={"confidence": confidence, "gross_slips": len(gross)},
    )


def wave_counts(events: pd.DataFrame | xr.Dataset) -> dict[str, int]:
    """Number of partial and gross slips (and unclassified drops, if any).

    Parameters
    ----------
    events
        With a ``kind`` column or variable.

    Returns
    -------
    dict
        Kind -> count; ``unclassified`` only when there are some.

    Examples
    --------
    >>> wave_counts(pd.DataFrame({"kind": ["gross_slip", "partial_slip", "gross_slip"]}))
    {'partial_slip': 1, 'gross_slip': 2}
    """
    counts = {kind: int((events["kind"] == kind).sum()) for kind in KINDS}
    unclassified = int((events["kind"] == "unclassified").sum())
    if unclassified:
        counts["unclassified"] = unclassified
    return counts


def phase_labels(phase: xr.DataArray) -> np.ndarray:
    """The label of each sample's phase (the codes of :func:`segment_phases` decoded).

    Parameters
    ----------
    phase
        From :func:`segment_phases` (or ``events.nc``).

    Returns
    -------
    numpy.ndarray
        One of :data:`PHASES` per sample.

    """
    return np.asarray(PHASES)[np.asarray(phase.values, dtype=np.intp)]


def phase_durations(phase: xr.DataArray) -> dict[str, float]:
    """Time (s) spent in each phase: samples times the sampling interval.

    Parameters
    ----------
    phase
        From :func:`segment_phases`.

    Returns
    -------
    dict
        Phase -> seconds.

    """
    time = phase["time"].values.astype(float)
    interval = float(np.median(np.diff(time))) if time.size > 1 else 0.0
    counts = np.bincount(np.asarray(phase.values, dtype=np.intp), minlength=len(PHASES))
    return {name: float(counts[k]) * interval for k, name in enumerate(PHASES)}


def summary_row(test_id: str, dataset: xr.Dataset) -> dict[str, object]:
    """One campaign-summary row from :func:`events_dataset`'s Dataset.

    Friction ratios at gross slips (mean, std, confidence interval), wave
    counts (T drops of unknown kind apart, as ``unclassified_waves``), time
    spent in each phase, warnings.

    Parameters
    ----------
    test_id
        The test.
    dataset
        ``events.nc``.

    Returns
    -------
    dict
        Column -> value of the summary's row.

    """
    row: dict[str, object] = {"test_id": test_id}
    counts = {"unclassified": 0, **wave_counts(dataset)}  # the same columns for every test
    row.update({f"{k}_waves": counts[k] for k in (*KINDS, "unclassified")})
    for name in ("static", "dynamic"):
        for key in ("mean", "std", "ci_low", "ci_high"):
            row[f"{name}_ratio_{key}"] = float(dataset[f"{name}_{key}"])
    row.update({f"{k}_s": v for k, v in phase_durations(dataset["phase"]).items()})
    row["warnings"] = " | ".join(warning_lines(dataset.attrs))
    return row
