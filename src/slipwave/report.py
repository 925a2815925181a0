"""HTML pages of tests, from the workflow's results."""

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
from slipwave.io import CHANNELS, atomic_output
from slipwave.plot import figure_png, plot_recording


def _environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.PackageLoader("slipwave", "templates"),
        autoescape=jinja2.select_autoescape(["html", "j2"]),
        undefined=jinja2.StrictUndefined,
    )


def channel_summary(recording: xr.Dataset) -> list[dict[str, Any]]:
    """One row per channel: units, minimum, maximum, missing samples."""
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
    """Counts, friction ratios, warnings and the table of events, for the page."""
    from slipwave.events import EVENT_COLUMNS, wave_counts

    table = events[list(EVENT_COLUMNS)].to_dataframe()
    ratios = {
        name: {key: float(events[f"{name}_{key}"]) for key in ("mean", "std", "ci_low",
                                                                "ci_high")}
        for name in ("static", "dynamic")
    }
    return {
        "counts": wave_counts(table),
        "ratios": ratios,
        "warnings": [w for w in str(events.attrs.get("warnings", "")).splitlines() if w],
        "columns": list(EVENT_COLUMNS),
        "rows": table.to_dict("records"),
    }


def video_summary(
    kymo: xr.Dataset,
    waves: pd.DataFrame,
    clock: dict[str, Any],
    frames: str | PathLike[str] | None = None,
    events: xr.Dataset | None = None,
) -> dict[str, Any]:
    """The page's video section: kymograph with fronts, frames around the first gross slip.

    ``clock`` is the fit ``slipwave waves`` writes (``offset_s``, ``rate``...).
    """
    from slipwave.plot import plot_frames, plot_kymograph
    from slipwave.video import open_frames

    def camera(card_time: float) -> float:
        return (card_time - float(clock["offset_s"])) / float(clock["rate"])

    figures = [figure_png(plot_kymograph(kymo, waves))]
    gross = None
    if events is not None:
        kinds = events["kind"].values.astype(str)
        if (kinds == "gross_slip").any():
            gross = float(events["t_start"].values[np.argmax(kinds == "gross_slip")])
    strip = None
    if gross is not None:
        start = camera(gross)
        figures.append(figure_png(plot_kymograph(kymo, waves, window=(start - 1.0, start + 1.5))))
        if frames is not None:
            wanted = start + np.arange(-1, 7) * 0.08
            images: list[np.ndarray] = []
            times: list[float] = []
            for frame in open_frames(frames):
                if len(images) < wanted.size and frame.time >= wanted[len(images)] - 1e-6:
                    images.append(frame.image)
                    times.append(frame.time)
                if len(images) == wanted.size:
                    break
            if images:
                strip = base64.b64encode(figure_png(plot_frames(images, times))).decode("ascii")
    resolved = waves[waves["kind"] != "unresolved"]
    return {
        "figures": [base64.b64encode(png).decode("ascii") for png in figures],
        "frames": strip,
        "waves": len(resolved),
        "unresolved": len(waves) - len(resolved),
        "directions": resolved["direction"].value_counts().to_dict(),
        "speed": float(resolved["speed"].median()) if len(resolved) else float("nan"),
        "clock": clock,
        "first_gross": gross,
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
        warnings=[w for w in str(attrs.get("warnings", "")).splitlines() if w],
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
    """Write :func:`render_test_page` to ``path``, whole or not at all."""
    with atomic_output(path) as temporary:
        temporary.write_text(render_test_page(recording, events, video), encoding="utf-8")
    return Path(path)
