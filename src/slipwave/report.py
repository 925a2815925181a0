"""HTML pages of tests, from the workflow's results."""

from __future__ import annotations

import base64
from os import PathLike
from pathlib import Path
from typing import Any

import jinja2
import numpy as np
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


def render_test_page(recording: xr.Dataset, events: xr.Dataset | None = None) -> str:
    """The HTML page of one test: metadata, warnings, channels and their plot.

    With ``events`` (:func:`slipwave.events.events_dataset`) the plot shades
    the phases and marks the slips, and the page lists the events, the wave
    counts and T/|N| at gross slips. The page is self-contained (the figure is
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
        version=__version__,
    )


def write_test_page(
    recording: xr.Dataset, path: str | PathLike[str], events: xr.Dataset | None = None
) -> Path:
    """Write :func:`render_test_page` to ``path``, whole or not at all."""
    with atomic_output(path) as temporary:
        temporary.write_text(render_test_page(recording, events), encoding="utf-8")
    return Path(path)
