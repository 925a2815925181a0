"""The report stage: the HTML and PDF page of a test, from the workflow's results."""

from __future__ import annotations

import base64
from collections.abc import Mapping
from os import PathLike
from pathlib import Path
from typing import Any

import jinja2
import numpy as np
import pandas as pd
import xarray as xr
from matplotlib.figure import Figure

from slipwave import __version__
from slipwave.compare import SCATTER_STEP
from slipwave.errors import SlipwaveError, warning_lines
from slipwave.events import EVENT_COLUMNS, events_table, wave_counts
from slipwave.fit.features import FEATURES
from slipwave.fit.procedure import band_z
from slipwave.io import CHANNELS, atomic_output
from slipwave.plot import (
    figure_png,
    figures_png,
    plot_frames,
    plot_gross_ratios,
    plot_gross_zooms,
    plot_kymograph,
    plot_map,
    plot_pairing,
    plot_recording,
    plot_simulated_fronts,
    plot_space_time,
)
from slipwave.simulate_waves import law_text, rate_state_law
from slipwave.video import ClockFit, open_frames

SETTING_MEANINGS = {
    "length_mm": ("contact length L", "mm"), "height_mm": ("slab height H", "mm"),
    "width_mm": ("slab width w", "mm"), "youngs_modulus_mpa": ("Young's modulus E", "MPa"),
    "poisson_ratio": ("Poisson's ratio", "-"), "normal_load_n": ("normal load N", "N"),
    "speed_mm_s": ("drive speed V", "mm/s"),
    "machine_stiffness_n_mm": ("machine stiffness k", "N/mm"),
    "duration_s": ("duration", "s"), "loading_time_s": ("normal loading time", "s"),
}
"""What each setting of a test's configuration is, and its unit."""


def page_template(name: str) -> jinja2.Template:
    """A page template shipped with slipwave, its values HTML-escaped.

    Parameters
    ----------
    name
        The file in ``slipwave/templates`` (e.g. ``"test_page.html.j2"``).

    Returns
    -------
    jinja2.Template
        The template; an undefined value is an error, not an empty string.

    """
    return jinja2.Environment(
        loader=jinja2.PackageLoader("slipwave", "templates"),
        autoescape=jinja2.select_autoescape(["html", "j2"]),
        undefined=jinja2.StrictUndefined,
    ).get_template(name)


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


# the fitted parameters as the page lists them: key, name, units, format
_FITTED = (("a", "a", "", "%.4f"), ("b", "b", "", "%.4f"), ("b_minus_a", "b - a", "", "%.4f"),
           ("dc_um", "D<sub>c</sub>", "µm", "%.3g"), ("mu0", "μ<sub>0</sub>", "", "%.3f"))


def _fitted_law(waves_fit: Mapping[str, Any], law: str) -> dict[str, Any]:
    """The fitted law's rows for the page, checked to be the law the run ran under."""
    fitted = law_text(rate_state_law(waves_fit["law"]))
    if fitted != law:
        raise SlipwaveError(f"the quasi-dynamic run ran under the {law}, not the fitted "
                            f"{fitted}: run the test again under its fit")
    parameters = waves_fit["parameters"]
    return {"rows": [{"name": name, "units": units,
                      **{end: fmt % parameters[key][end] for end in ("value", "low", "high")}}
                     for key, name, units, fmt in _FITTED],
            "guesses": int(waves_fit["guesses"]), "windows": int(waves_fit["test"]["windows"]),
            "window": float(waves_fit["test"]["window_s"]),
            "elements": int(waves_fit["settings"]["elements"])}


def video_summary(
    kymo: xr.Dataset,
    waves: pd.DataFrame,
    clock: ClockFit,
    frames: str | PathLike[str] | None = None,
    events: xr.Dataset | None = None,
    fused: pd.DataFrame | None = None,
    quasi_dynamic: xr.Dataset | None = None,
    simulated_waves: pd.DataFrame | None = None,
    simulated_fronts: pd.DataFrame | None = None,
    simulated_film: xr.Dataset | None = None,
    waves_fit: Mapping[str, Any] | None = None,
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
    quasi_dynamic, simulated_waves, simulated_fronts, simulated_film
        The test run quasi-dynamically, its film's waves, its slip-rate fronts and its
        film's kymograph (``slipwave simulate-waves``), shown beside the video's;
        ``None``: not shown.
    waves_fit
        The law fitted on the test's cycle and waves (``slipwave fit-waves``), which the
        quasi-dynamic run ran under; ``None``: the run's law is the configuration's.

    Returns
    -------
    dict
        Figures (matplotlib, drawn by :func:`render_test_page`), frames, wave
        counts and directions, median front speed, the clock, the first gross
        slip's time and the pairing; with a quasi-dynamic run, ``simulated`` (its law,
        elements, its film's waves and their median speed, its slip-rate fronts and
        theirs, the two figures, and ``fit``: the fitted law's intervals or ``None``).

    Raises
    ------
    SlipwaveError
        If the run did not run under the fitted law given.

    """
    figures = [plot_kymograph(kymo, waves)]
    gross = None
    if events is not None:
        kinds = events["kind"].values.astype(str)
        if (kinds == "gross_slip").any():
            gross = float(events["t_start"].values[np.argmax(kinds == "gross_slip")])
    strip = None
    if gross is not None:
        start = float(clock.camera_time(gross))
        figures.append(plot_kymograph(kymo, waves, window=(start - 1.0, start + 1.5)))
        if frames is not None:
            images, times = _frames_at(frames, start + np.arange(-1, 7) * 0.08)
            if images:
                strip = plot_frames(images, times)
    resolved = waves[waves["kind"] != "unresolved"]
    pairing = None
    if fused is not None:
        source = fused["source"].value_counts()
        agrees = fused["kind_agrees"].dropna().astype(bool)
        pairing = {"both": int(source.get("both", 0)), "load": int(source.get("load", 0)),
                   "video": int(source.get("video", 0)), "judged": int(agrees.size),
                   "agree": int(agrees.sum())}
    simulated = None
    if (quasi_dynamic is not None and simulated_waves is not None
            and simulated_fronts is not None and simulated_film is not None):
        filmed = simulated_waves[simulated_waves["kind"] != "unresolved"]
        speeds = filmed["speed"].dropna()
        fronts = simulated_fronts["speed"].dropna()
        law = str(quasi_dynamic.attrs.get("law_text", quasi_dynamic.attrs.get("law", "")))
        simulated = {"law": law, "fit": None if waves_fit is None else _fitted_law(waves_fit, law),
                     "waves": len(filmed),
                     "unresolved": len(simulated_waves) - len(filmed),
                     "fronts": len(simulated_fronts),
                     "elements": quasi_dynamic.sizes["x"] - 1,
                     "frame_rate": float(simulated_film.attrs.get("frame_rate", float("nan"))),
                     "speed": float(speeds.median()) if len(speeds) else float("nan"),
                     "front_speed": float(fronts.median()) if len(fronts) else float("nan"),
                     "film": plot_kymograph(simulated_film, simulated_waves),
                     "figure": plot_simulated_fronts(quasi_dynamic, simulated_fronts)}
    return {
        "simulated": simulated,
        "figures": figures,
        "frames": strip,
        "waves": len(resolved),
        "unresolved": len(waves) - len(resolved),
        "directions": resolved["direction"].value_counts().to_dict(),
        "speed": float(resolved["speed"].median()) if len(resolved) else float("nan"),
        "clock": clock,
        "first_gross": gross,
        "pairing": pairing,
    }


def _number(value: Any) -> Any:
    """A table cell as a float when it reads as one (a CSV column of mixed kinds)."""
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return value
    return value


def png_base64(fig: Figure) -> str:
    """A figure as a PNG in base64, to embed in a page.

    Parameters
    ----------
    fig
        The figure.

    Returns
    -------
    str
        The PNG file's content, base64-encoded.

    """
    return base64.b64encode(figure_png(fig)).decode("ascii")


def mesh_check_rows(fit: dict[str, Any]) -> dict[str, Any] | None:
    """What the page says of the fit's mesh: the chosen law refitted at twice it.

    Parameters
    ----------
    fit
        ``fit.json`` (:func:`slipwave.fit.fit_test`).

    Returns
    -------
    dict or None
        ``law``, ``elements`` (the finer mesh), ``fit_elements``, ``parameters`` (rows:
        ``name``, ``value``, ``low``, ``high``, ``units`` at the finer mesh and
        ``change``, relative), ``zone_mm`` and ``zone_elements`` (the process zone, and
        how many elements of each mesh it spans; ``None`` for a law without a length);
        ``None`` when the fit has no mesh check.

    Examples
    --------
    >>> fit = {"elements": 80, "setup": {"length_mm": {"value": 80.0}}, "mesh_check": {
    ...     "law": "coulomb", "elements": 160, "process_zone_mm": None,
    ...     "change": {"fs": 0.0093},
    ...     "parameters": {"fs": {"value": 0.91, "low": 0.89, "high": 0.93, "units": "1"}}}}
    >>> rows = mesh_check_rows(fit)
    >>> rows["parameters"][0]["change"], rows["zone_elements"]
    (0.0093, None)
    """
    finer = fit.get("mesh_check")
    if not finer:
        return None
    zone = finer["process_zone_mm"]
    length = float(fit["setup"]["length_mm"]["value"])
    return {"law": finer["law"], "elements": finer["elements"], "fit_elements": fit["elements"],
            "parameters": [{"name": name, **value, "change": finer["change"][name]}
                           for name, value in finer["parameters"].items()],
            "zone_mm": zone,
            "zone_elements": None if zone is None else
            [zone * fit["elements"] / length, zone * finer["elements"] / length]}


def predictive_rows(fit: dict[str, Any]) -> dict[str, Any]:
    """What the page says of the chosen law's posterior predictive, feature by feature.

    Parameters
    ----------
    fit
        ``fit.json`` (:func:`slipwave.fit.fit_test`).

    Returns
    -------
    dict
        ``predictive`` (rows: ``name``, ``meaning``, ``measured``, ``simulated``,
        ``spread``, ``z``, ``agrees``, ``mesh_error``: the chosen law's error from the
        mesh in that feature, in the spread, or None), ``predictive_differs`` (the
        features' meanings where it differs), ``predictive_z`` (the band's half-width
        in standard deviations), ``predictive_members`` and ``members``.

    Examples
    --------
    >>> fit = {"predictive": {"first_ratio": {"measured": 0.6, "simulated": 0.61,
    ...        "spread": 0.01, "z": -1.0, "agrees": True}}}
    >>> rows = predictive_rows(fit)
    >>> rows["predictive"][0]["meaning"], rows["predictive_differs"]
    ('T/|N| before the first slip of any kind', [])
    """
    checks = fit.get("predictive") or {}
    mesh = (fit.get("laws", {}).get(fit.get("chosen"), {}).get("mesh_error") or {})
    rows = [{"name": name, "meaning": FEATURES.get(name, name), **check,
             "mesh_error": mesh.get(name)}
            for name, check in checks.items()]
    settings = fit.get("settings", {})
    return {"predictive": rows,
            "predictive_differs": [row["meaning"] for row in rows if not row["agrees"]],
            "predictive_z": band_z(len(rows)),
            "predictive_members": settings.get("predictive_members"),
            "members": settings.get("members")}


def pairing_summary(
    recording: xr.Dataset,
    events: xr.Dataset | None,
    fit: dict[str, Any] | None = None,
    comparison: pd.DataFrame | None = None,
    simulated: xr.Dataset | None = None,
    simulated_events: pd.DataFrame | None = None,
    contact: xr.Dataset | None = None,
    placement: dict[str, Any] | None = None,
    behaviour_map: xr.Dataset | None = None,
    kymo: xr.Dataset | None = None,
    clock: ClockFit | None = None,
    scatter_left_out: list[dict[str, float]] | None = None,
) -> dict[str, Any]:
    """The page's sections on the test's simulation: what is there, and what is missing.

    Parameters
    ----------
    recording, events
        The measurement (``events`` may be ``None``).
    fit
        ``fit.json`` (:func:`slipwave.fit.fit_test`), or ``None``.
    comparison
        ``comparison.csv`` (:func:`slipwave.compare.compare_test`), or ``None``.
    simulated
        The simulated recording, or ``None``.
    simulated_events
        Its events, or ``None``.
    contact
        The simulated contact history (zones, kymograph, frames), or ``None``.
    placement
        The test's place on the behaviour map (``comparison.json``'s ``map``), or ``None``.
    behaviour_map
        ``map.nc``, to draw the test on it, or ``None``.
    kymo, clock
        The video's kymograph and clock, for the space-time figure, or ``None``.
    scatter_left_out
        The neighbouring laws the comparison's scatter lacks, the solver not following
        them (``comparison.json``), or ``None``.

    Returns
    -------
    dict
        ``setup`` (rows with sources), ``laws`` (rows), ``chosen`` and
        ``chosen_because`` (the law and why), ``mesh_check`` (the chosen law at twice
        the mesh: :func:`mesh_check_rows`), ``comparison``
        (rows) and ``verdicts``, figures (matplotlib, drawn by
        :func:`render_test_page`: ``signals``, ``zooms``,
        ``ratios``, ``space_time``, ``frames``, ``map``), ``placement``, ``missing``
        (what could not be shown, in words) and ``scatter_step`` (how far apart the
        coefficients of the comparison's neighbouring simulations are: the fit's load
        calibration), ``scatter_left_out`` (the neighbours it lacks, a list),
        ``simulated`` and ``simulated_note`` (the law the simulation takes, and why it
        is not the posterior medians, or None).

    """
    missing: list[str] = []
    summary: dict[str, Any] = {
        "setup": [], "laws": [], "chosen": None, "chosen_because": None, "mesh_check": None,
        "comparison": [],
        "verdicts": {},
        "figures": dict.fromkeys(("signals", "zooms", "ratios", "space_time", "frames",
                                  "map")),
        "placement": placement, "missing": missing, "edge_reference": None,
        "edge_threshold": None, "fit_edge_threshold": None, "elements": None,
        "frame_labels": [], "scatter_step": SCATTER_STEP,
        "scatter_left_out": list(scatter_left_out or []), "simulated": None,
        "simulated_note": None}
    if simulated is not None and "gross_edge_ratio" in simulated.attrs:
        # what detection told the test's events by, read off the simulation's slips
        summary["edge_threshold"] = float(simulated.attrs["gross_edge_ratio"])
    if fit is None:
        missing.append("no fit: the test was not fitted (fit.enabled is false, or its files "
                       "lack what the simulation needs), so no configuration, friction law "
                       "or simulation is shown")
    else:
        setup = fit["setup"]
        summary["edge_reference"] = setup.get("edge_reference")
        summary["fit_edge_threshold"] = fit.get("edge_threshold")
        for key, (meaning, unit) in SETTING_MEANINGS.items():
            if key in setup:
                summary["setup"].append({"key": key, "meaning": meaning, "unit": unit,
                                         "value": setup[key]["value"],
                                         "source": setup[key]["source"]})
        summary["chosen"] = fit["chosen"]
        summary["chosen_because"] = fit.get("chosen_because")
        summary["elements"] = fit.get("elements")
        summary["scatter_step"] = fit.get("load_calibration", SCATTER_STEP)
        for law, entry in fit["laws"].items():
            summary["laws"].append({
                "law": law, "chosen": law == fit["chosen"], "rejected": entry["rejected"],
                "parameters": [{"name": name, **value}
                               for name, value in entry["parameters"].items()],
                "log_bayes_factor": entry["log_bayes_factor"], "guesses": entry["guesses"],
                "simulations": entry["simulations"]})
        summary["mesh_check"] = mesh_check_rows(fit)
        summary["simulated"] = fit["parameters"]
        summary["simulated_note"] = fit.get("parameters_note")
        summary.update(predictive_rows(fit))
    if comparison is None:
        missing.append("no comparison: the test was not compared with a simulation")
    else:
        summary["comparison"] = [{key: _number(value) for key, value in row.items()}
                                 for row in comparison.to_dict("records")]
        summary["verdicts"] = comparison["verdict"].value_counts().to_dict()
    figures = summary["figures"]
    if simulated is None:
        missing.append("no simulation: measured signals only")
    else:
        figures["signals"] = plot_pairing(recording, simulated, events, simulated_events)
        if events is not None:
            zooms = plot_gross_zooms(recording, simulated, events, simulated_events)
            if zooms is None:
                missing.append("no measured gross slip to zoom on")
            else:
                figures["zooms"] = zooms
            figures["ratios"] = plot_gross_ratios(events_table(events), simulated_events)
    if contact is None and kymo is None:
        missing.append("no video and no simulated contact: no space-time diagram")
    else:
        timing = (clock.offset, clock.rate) if clock is not None else (0.0, 1.0)
        figures["space_time"] = plot_space_time(contact, kymo, timing)
        if kymo is None:
            missing.append("no video: the simulated zones and kymograph are shown alone")
        if contact is None:
            missing.append("no simulated contact history: the video's kymograph alone")
    if contact is not None and "frame" in contact:
        figures["frames"] = plot_frames(
            list(contact["frame"].values), [float(t) for t in contact["frame_time"].values],
            [str(label) for label in contact["frame_label"].values])
        summary["frame_labels"] = [str(label) for label in contact["frame_label"].values]
    if behaviour_map is not None and placement is not None and fit is not None:
        fs = fit["laws"][fit["chosen"]]["parameters"]["fs"]
        tests = pd.DataFrame([{"test_id": fit["test_id"], "height_ratio":
                               placement["height_ratio"], "ratio": fs["value"],
                               "ci_low": fs["low"], "ci_high": fs["high"]}])
        figures["map"] = plot_map(behaviour_map, tests,
                                  label="this test (fitted fs, 95 % interval)")
    elif fit is not None:
        missing.append("no behaviour map: the test is not placed on it")
    return summary


def _drawn(video: dict[str, Any] | None, pairing: dict[str, Any] | None,
           main: Figure | None, workers: int
           ) -> tuple[str | None, dict[str, Any] | None, dict[str, Any] | None]:
    """The page's figures as base64 PNG, drawn together (the summaries left as they were)."""
    holder: dict[str, Any] = {"main": main}
    slots: list[tuple[dict[str, Any] | list[Any], Any]] = [(holder, "main")]
    if video is not None:
        video = {**video, "figures": list(video["figures"])}
        slots += [(video["figures"], i) for i in range(len(video["figures"]))]
        slots.append((video, "frames"))
        if video.get("simulated") is not None:
            video["simulated"] = dict(video["simulated"])
            slots += [(video["simulated"], "film"), (video["simulated"], "figure")]
    if pairing is not None:
        pairing = {**pairing, "figures": dict(pairing["figures"])}
        slots += [(pairing["figures"], key) for key in pairing["figures"]]
    slots = [(h, k) for h, k in slots if isinstance(h[k], Figure)]
    # largest first, so that the last figure a worker takes is a small one
    slots.sort(key=lambda slot: -float(np.prod(slot[0][slot[1]].get_size_inches())))
    pngs = figures_png([h[k] for h, k in slots], workers=workers)
    for (h, k), png in zip(slots, pngs, strict=True):
        h[k] = base64.b64encode(png).decode("ascii")
    return holder["main"], video, pairing


def render_test_page(recording: xr.Dataset, events: xr.Dataset | None = None,
                     video: dict[str, Any] | None = None,
                     pairing: dict[str, Any] | None = None, *, workers: int = 1) -> str:
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
    pairing
        From :func:`pairing_summary`, or ``None`` (the measurement alone).
    workers
        Processes to draw the figures on (:func:`slipwave.plot.figures_png`).

    Returns
    -------
    str
        The page's HTML.

    """
    # the measurement alone is drawn only where no figure pairs it with its simulation
    paired = pairing is not None and pairing["figures"].get("signals") is not None
    main = None if paired else plot_recording(recording, events)
    figure, video, pairing = _drawn(video, pairing, main, workers)
    attrs = recording.attrs
    time = recording["time"].values
    metadata = {
        k: v for k, v in attrs.items()
        if k not in {"warnings", "Conventions", "source_sha256", "source", "source_format"}
    }
    return page_template("test_page.html.j2").render(
        test_id=attrs.get("test_id", attrs.get("source", "test")),
        source=attrs.get("source", ""),
        sha256=attrs.get("source_sha256", ""),
        source_format=attrs.get("source_format", ""),
        warnings=warning_lines(attrs),
        metadata=metadata,
        channels=channel_summary(recording),
        samples=int(time.size),
        duration=float(time[-1] - time[0]) if time.size else 0.0,
        figure=figure,
        events=None if events is None else event_summary(events),
        video=video,
        pairing=pairing,
        version=__version__,
    )


def write_pdf(html: str, path: str | PathLike[str]) -> Path:
    """Print an HTML page (its print style sheet: A4) to PDF, whole or not at all.

    Parameters
    ----------
    html
        The page.
    path
        The PDF to write.

    Returns
    -------
    Path
        The PDF written.

    """
    import logging

    import weasyprint

    # WeasyPrint reports every CSS rule it ignores (screen-only ones) as a warning
    logging.getLogger("weasyprint").setLevel(logging.ERROR)
    # no base URL: links between reports stay relative (the folder can move, and the
    # PDF is the same wherever it was built); figures are embedded
    with atomic_output(path) as temporary:
        weasyprint.HTML(string=html).write_pdf(temporary)
    return Path(path)


def write_test_page(
    recording: xr.Dataset, path: str | PathLike[str], events: xr.Dataset | None = None,
    video: dict[str, Any] | None = None, pairing: dict[str, Any] | None = None, *,
    pdf: str | PathLike[str] | None = None, workers: int = 1,
) -> Path:
    """Write :func:`render_test_page` to ``path`` (and ``pdf``), whole or not at all.

    Parameters
    ----------
    recording, events, video, pairing
        As in :func:`render_test_page`.
    path
        The HTML file to write.
    pdf
        Also print it to this PDF; ``None``: no PDF.
    workers
        Processes to draw the figures on.

    Returns
    -------
    Path
        The page written.

    """
    html = render_test_page(recording, events, video, pairing, workers=workers)
    if pdf is not None:
        write_pdf(html, pdf)
    with atomic_output(path) as temporary:
        temporary.write_text(html, encoding="utf-8")
    return Path(path)
