"""The report stage: HTML pages of tests, from the workflow's results."""

from __future__ import annotations

import base64
from os import PathLike
from pathlib import Path
from typing import Any

import jinja2
import numpy as np
import pandas as pd
import xarray as xr

from slipwave import __version__
from slipwave.errors import warning_lines
from slipwave.events import EVENT_COLUMNS, events_table, wave_counts
from slipwave.io import CHANNELS, atomic_output
from slipwave.plot import figure_png, plot_frames, plot_kymograph, plot_recording
from slipwave.video import ClockFit, open_frames


def _environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.PackageLoader("slipwave", "templates"),
        autoescape=jinja2.select_autoescape(["html", "j2"]),
        undefined=jinja2.StrictUndefined,
    )


def channel_summary(recording: xr.Dataset) -> list[dict[str, Any]]:
    """One row per channel: units, minimum, maximum, missing samples.

    Parameters
    ----------
    recording
        From :func:`slipwave.io.read_acquisition`.

    Returns
    -------
    list of dict
        ``name``, ``long_name``, ``units``, ``min``, ``max``, ``missing``.

    """
    rows = []
    for name in CHANNELS:
        if name not in recording.data_vars:
            continue
        values = recording[name].values
        finite = values[np.isfinite(values)]
        rows.append(
            {
                "name": name,
                "long_name": recording[name].attrs.get("long_name", ""),
                "units": recording[name].attrs.get("units", ""),
                "min": float(finite.min()) if finite.size else float("nan"),
                "max": float(finite.max()) if finite.size else float("nan"),
                "missing": int(values.size - finite.size),
            }
        )
    return rows


def event_summary(events: xr.Dataset) -> dict[str, Any]:
    """Counts, friction ratios, warnings and the table of events, for the page.

    Parameters
    ----------
    events
        ``events.nc``, from :func:`slipwave.events.events_dataset`.

    Returns
    -------
    dict
        ``counts``, ``ratios`` (static and dynamic: mean, std, interval),
        ``warnings``, ``columns`` and ``rows`` of the events table, and how the
        edge sensors read (``edge_convention``, ``edge_evidence``).

    """
    table = events_table(events)
    ratios = {
        name: {key: float(events[f"{name}_{key}"]) for key in ("mean", "std", "ci_low",
                                                                "ci_high")}
        for name in ("static", "dynamic")
    }
    return {
        "counts": wave_counts(table),
        "ratios": ratios,
        "warnings": warning_lines(events.attrs),
        "columns": list(EVENT_COLUMNS),
        "rows": table.to_dict("records"),
        "edge_convention": {"x_axis": "both along +x", "outward": "each its edge's outward "
                            "displacement"}.get(str(events.attrs.get("edge_convention", "")), ""),
        "edge_evidence": str(events.attrs.get("edge_convention_evidence", "")),
    }


def _frames_at(frames: str | PathLike[str], wanted: np.ndarray) -> tuple[list[np.ndarray],
                                                                           list[float]]:
    """The first frame at or after each wanted camera time (stops reading after the last)."""
    images: list[np.ndarray] = []
    times: list[float] = []
    for frame in open_frames(frames):
        if len(images) < wanted.size and frame.time >= wanted[len(images)] - 1e-6:
            images.append(frame.image)
            times.append(frame.time)
        if len(images) == wanted.size:
            break
    return images, times


def video_summary(
    kymo: xr.Dataset,
    waves: pd.DataFrame,
    clock: ClockFit,
    frames: str | PathLike[str] | None = None,
    events: xr.Dataset | None = None,
    fused: pd.DataFrame | None = None,
) -> dict[str, Any]:
    """The page's video section: kymograph with fronts, frames around the first gross slip.

    Parameters
    ----------
    kymo
        From :func:`slipwave.video.kymograph`.
    waves
        From :func:`slipwave.video.track_waves`.
    clock
        From :func:`slipwave.video.align_clocks` (``clock.json``).
    frames
        The video or image folder, for frames around the first gross slip.
    events
        ``events.nc``: where the first gross slip is.
    fused
        From :func:`slipwave.video.fuse` (``events_video.csv``): how the load
        events and the waves pair, and whether their kinds agree.

    Returns
    -------
    dict
        Figures (base64 PNG), frames, wave counts and directions, median
        front speed, the clock, the first gross slip's time and the pairing.

    """
    figures = [figure_png(plot_kymograph(kymo, waves))]
    gross = None
    if events is not None:
        kinds = events["kind"].values.astype(str)
        if (kinds == "gross_slip").any():
            gross = float(events["t_start"].values[np.argmax(kinds == "gross_slip")])
    strip = None
    if gross is not None:
        start = float(clock.camera_time(gross))
        figures.append(figure_png(plot_kymograph(kymo, waves, window=(start - 1.0, start + 1.5))))
        if frames is not None:
            images, times = _frames_at(frames, start + np.arange(-1, 7) * 0.08)
            if images:
                strip = base64.b64encode(figure_png(plot_frames(images, times))).decode("ascii")
    resolved = waves[waves["kind"] != "unresolved"]
    pairing = None
    if fused is not None:
        source = fused["source"].value_counts()
        agrees = fused["kind_agrees"].dropna().astype(bool)
        pairing = {"both": int(source.get("both", 0)), "load": int(source.get("load", 0)),
                   "video": int(source.get("video", 0)), "judged": int(agrees.size),
                   "agree": int(agrees.sum())}
    return {
        "figures": [base64.b64encode(png).decode("ascii") for png in figures],
        "frames": strip,
        "waves": len(resolved),
        "unresolved": len(waves) - len(resolved),
        "directions": resolved["direction"].value_counts().to_dict(),
        "speed": float(resolved["speed"].median()) if len(resolved) else float("nan"),
        "clock": clock,
        "first_gross": gross,
        "pairing": pairing,
    }


def render_test_page(recording: xr.Dataset, events: xr.Dataset | None = None,
                     video: dict[str, Any] | None = None) -> str:
    """The HTML page of one test: metadata, warnings, channels and their plot.

    With ``events`` (:func:`slipwave.events.events_dataset`) the plot shades
    the phases and marks the slips, and the page lists the events, the wave
    counts and T/|N| at gross slips; with ``video`` (:func:`video_summary`)
    it shows the kymograph with the tracked fronts and frames around the
    first gross slip. The page is self-contained (the figure is
    embedded), so it can be mailed or archived on its own.

    Parameters
    ----------
    recording
        From :func:`slipwave.io.read_acquisition` (``recording.nc``).
    events
        ``events.nc``, or ``None``.
    video
        From :func:`video_summary`, or ``None``.

    Returns
    -------
    str
        The page's HTML.

    """
    png = figure_png(plot_recording(recording, events))
    attrs = recording.attrs
    time = recording["time"].values
    metadata = {
        k: v for k, v in attrs.items()
        if k not in {"warnings", "Conventions", "source_sha256", "source", "source_format"}
    }
    return _environment().get_template("test_page.html.j2").render(
        test_id=attrs.get("test_id", attrs.get("source", "test")),
        source=attrs.get("source", ""),
        sha256=attrs.get("source_sha256", ""),
        source_format=attrs.get("source_format", ""),
        warnings=warning_lines(attrs),
        metadata=metadata,
        channels=channel_summary(recording),
        samples=int(time.size),
        duration=float(time[-1] - time[0]) if time.size else 0.0,
        figure=base64.b64encode(png).decode("ascii"),
        events=None if events is None else event_summary(events),
        video=video,
        version=__version__,
    )


def write_test_page(
    recording: xr.Dataset, path: str | PathLike[str], events: xr.Dataset | None = None,
    video: dict[str, Any] | None = None,
) -> Path:
    """Write :func:`render_test_page` to ``path``, whole or not at all.

    Parameters
    ----------
    recording, events, video
        As in :func:`render_test_page`.
    path
        The HTML file to write.

    Returns
    -------
    Path
        The page written.

    """
    with atomic_output(path) as temporary:
        temporary.write_text(render_test_page(recording, events, video), encoding="utf-8")
    return Path(path)
