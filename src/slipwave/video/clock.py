"""The camera's clock against the acquisition card's: offset and rate, and conversions."""

from __future__ import annotations

import json
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr
from scipy import stats

from slipwave.defaults import PAIRING_TOLERANCE_S
from slipwave.errors import SlipwaveError
from slipwave.video.waves import change


@dataclass(frozen=True)
class ClockFit:
    """Acquisition time = ``offset + rate * camera time``; how it was found and how well."""

    offset: float
    rate: float
    residual: float
    method: str
    pairs: int

    def acquisition_time(self, camera_time: np.ndarray | float) -> np.ndarray:
        """The acquisition-card time of camera times.

        Parameters
        ----------
        camera_time
            Times on the camera's clock, s.

        Returns
        -------
        numpy.ndarray
            The same instants on the card's clock, s.

        """
        return self.offset + self.rate * np.asarray(camera_time, dtype=float)

    def camera_time(self, acquisition_time: np.ndarray | float) -> np.ndarray:
        """The camera time of acquisition-card times (the inverse of :meth:`acquisition_time`).

        Parameters
        ----------
        acquisition_time
            Times on the card's clock, s.

        Returns
        -------
        numpy.ndarray
            The same instants on the camera's clock, s.

        Examples
        --------
        >>> clock = ClockFit(offset=0.37, rate=1.0005, residual=0.01, method="sync LED", pairs=3)
        >>> float(clock.camera_time(clock.acquisition_time(12.5)))
        12.5
        """
        return (np.asarray(acquisition_time, dtype=float) - self.offset) / self.rate

    def to_json(self) -> str:
        """The fit as the JSON text of ``clock.json`` (``offset_s``, ``rate``, ...).

        Returns
        -------
        str
            Indented JSON, ending with a newline.

        """
        return json.dumps({"offset_s": self.offset, "rate": self.rate,
                           "residual_s": self.residual, "method": self.method,
                           "pairs": self.pairs}, indent=2) + "\n"

    @classmethod
    def from_json(cls, text: str) -> ClockFit:
        """Read a fit written by :meth:`to_json`.

        Parameters
        ----------
        text
            The JSON text.

        Returns
        -------
        ClockFit
            The fit.

        Raises
        ------
        SlipwaveError
            If the text is not such a fit.

        """
        try:
            fields = json.loads(text)
            return cls(float(fields["offset_s"]), float(fields["rate"]),
                       float(fields["residual_s"]), str(fields["method"]), int(fields["pairs"]))
        except (ValueError, KeyError, TypeError) as err:
            raise SlipwaveError(f"not a camera clock fit: {err}") from err


def on_card_clock(waves: pd.DataFrame, clock: ClockFit) -> pd.DataFrame:
    """The waves with their start and end on the card's clock (``t_start_card``, ``t_end_card``).

    Parameters
    ----------
    waves
        From :func:`~slipwave.video.waves.track_waves`.
    clock
        From :func:`align_clocks`.

    Returns
    -------
    pandas.DataFrame
        A copy of ``waves`` with the two columns added.

    """
    return waves.assign(t_start_card=clock.acquisition_time(waves["t_start"].to_numpy()),
                        t_end_card=clock.acquisition_time(waves["t_end"].to_numpy()))


def sync_offset(kymo: xr.Dataset, sync_time: float) -> float | None:
    """Clock offset from the sync LED lit at acquisition time ``sync_time``, if it shows.

    The first lit frame comes at most one frame after the LED lit up: the
    offset is taken half a frame before it. ``None`` when no frame is lit.

    Parameters
    ----------
    kymo
        With the ``sync`` corner's level.
    sync_time
        Card time the LED lit up, s.

    Returns
    -------
    float or None
        card time - camera time, s.

    """
    level = kymo["sync"].values.astype(float)
    lit = level > 0.5 * (level.max() + np.median(level))
    if level.max() - np.median(level) < 0.2 or not lit.any():
        return None
    time = kymo["time"].values.astype(float)
    period = float(np.median(np.diff(time)))
    return float(sync_time - time[np.argmax(lit)] + 0.5 * period)


def correlation_offset(kymo: xr.Dataset, recording: xr.Dataset, *,
                       max_offset: float = 60.0) -> float:
    """Clock offset that best lines up the video's activity with the fall rate of T.

    Cross-correlates the band's total change per frame with ``max(-dT/dt, 0)``
    sampled on the frames, over offsets up to ``max_offset`` (s) either way.

    Parameters
    ----------
    kymo
        From :func:`~slipwave.video.kymograph`.
    recording
        With ``T``.
    max_offset
        Largest offset tried, s.

    Returns
    -------
    float
        card time - camera time, s, to a frame.

    """
    time = kymo["time"].values.astype(float)
    period = float(np.median(np.diff(time)))
    activity = change(kymo).values.sum(axis=1)
    activity = activity - activity.mean()
    card = recording["time"].values.astype(float)
    falling = np.maximum(-np.gradient(recording["T"].values.astype(float), card), 0.0)
    lags = np.arange(-max_offset, max_offset + period, period)
    grid = time[0] + np.arange(time.size) * period
    best, score = 0.0, -np.inf
    for lag in lags:
        sampled = np.interp(grid + lag, card, falling, left=0.0, right=0.0)
        value = float(activity @ (sampled - sampled.mean()))
        if value > score:
            best, score = float(lag), value
    return best


def align_clocks(
    waves: pd.DataFrame,
    kymo: xr.Dataset,
    recording: xr.Dataset,
    events: pd.DataFrame,
    *,
    sync_time: float | None = None,
    tolerance: float = PAIRING_TOLERANCE_S,
) -> ClockFit:
    """Offset and rate between the camera's and the acquisition card's clocks.

    A first offset comes from the sync LED (``sync_time``, by default the
    recording's ``sync_time_s`` attribute) or, without one, from
    :func:`correlation_offset`. Then every wave whose start falls within
    ``tolerance`` (s) of a load event's onset is paired with it and a straight
    line (acquisition = offset + rate x camera) is fitted to the pairs
    (Theil-Sen: a wrong pair does not tilt it); the residual is the robust
    standard deviation (1.4826 MAD) of its misfit (wave starts are known to a
    frame).

    Parameters
    ----------
    waves
        From :func:`~slipwave.video.track_waves` (camera time).
    kymo
        Their kymograph.
    recording
        The test's recording.
    events
        From :func:`~slipwave.events.detect_events` (card time).
    sync_time
        Card time the sync LED lit up, s.
    tolerance
        Largest wave-event gap that pairs them, s.

    Returns
    -------
    ClockFit
        The fit, how it was found and its residual.

    """
    if sync_time is None and "sync_time_s" in recording.attrs:
        sync_time = float(recording.attrs["sync_time_s"])
    first = sync_offset(kymo, sync_time) if sync_time is not None else None
    method = "sync LED"
    if first is None:
        first, method = correlation_offset(kymo, recording), "cross-correlation"
    camera = waves["t_start"].to_numpy(dtype=float)
    onsets = events["t_start"].to_numpy(dtype=float) if len(events) else np.array([])
    fit = ClockFit(first, 1.0, np.nan, method, 0)
    for _ in range(2):  # pair, fit, pair again with the better clock
        if camera.size == 0 or onsets.size == 0:
            return fit
        mapped = fit.acquisition_time(camera)
        nearest = np.abs(mapped[:, None] - onsets[None, :]).argmin(axis=1)
        close = np.abs(mapped - onsets[nearest]) <= tolerance
        if close.sum() < 3:
            return fit
        paired = onsets[nearest[close]]
        rate = float(stats.theilslopes(paired, camera[close])[0])
        offset = float(np.median(paired - rate * camera[close]))
        misfit = onsets[nearest[close]] - (offset + rate * camera[close])
        spread = 1.4826 * float(np.median(np.abs(misfit - np.median(misfit))))
        fit = ClockFit(float(offset), float(rate), spread,
                       f"{method}, then {int(close.sum())} wave/event pairs",
                       int(close.sum()))
    return fit


def read_clock(path: str | PathLike[str]) -> ClockFit:
    """A camera clock's fit, from its JSON (``slipwave waves --clock``).

    Parameters
    ----------
    path
        The file.

    Returns
    -------
    ClockFit
        The fit.

    Raises
    ------
    SlipwaveError
        Naming the file, when it cannot be read or is not such a fit.

    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise SlipwaveError(f"{path}: cannot be read as a clock fit: {err}") from err
    try:
        return ClockFit.from_json(text)
    except SlipwaveError as err:
        raise SlipwaveError(f"{path}: {err}") from err
