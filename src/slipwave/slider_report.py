"""The spring-slider campaign's page: the fitted law, and record by record its predictions.

The page sets the fitted a, b, Dc and mu0 with their 95 % intervals, and for every
record the measured regime, median drop and recurrence against the posterior
predictive's (the records the fit did not see marked as held out), with a figure of
the intervals.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from os import PathLike
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from slipwave import __version__
from slipwave.io import atomic_output
from slipwave.report import page_template, png_base64

FEATURE_TITLES = {"drop": "median drop of F/N", "recurrence": "median recurrence (s)",
                  "stuck_share": "stuck share"}
"""The predicted features, as the page names them."""


def plot_predictions(predictions: Sequence[dict[str, Any]]) -> Figure:
    """Each record's measured feature against its predictive's 95 % interval.

    Parameters
    ----------
    predictions
        ``slipwave slider-predict``'s results.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per feature; held-out records in orange.
    """
    fig, axes = plt.subplots(1, len(FEATURE_TITLES), figsize=(12, 0.45 * len(predictions) + 1.5),
                             sharey=True, layout="constrained")
    names = [p["record"] for p in predictions]
    for ax, (feature, title) in zip(axes, FEATURE_TITLES.items(), strict=True):
        for row, prediction in enumerate(predictions):
            entry = prediction[feature]
            colour = "tab:orange" if prediction["role"] == "predict" else "tab:blue"
            ax.plot([entry["low"], entry["high"]], [row, row], color=colour, lw=3, alpha=0.5)
            ax.plot(entry["predicted"], row, "|", color=colour, ms=12)
            ax.plot(entry["measured"], row, "kx" if entry["inside"] else "rx", ms=8)
        ax.set_title(title)
        if feature == "recurrence":
            ax.set_xscale("log")
    axes[0].set_yticks(range(len(names)), names)
    axes[0].invert_yaxis()
    fig.suptitle("bars: posterior predictive 95 % (orange: held out); x: measured "
                 "(red: outside)")
    return fig


def write_slider_report(fit_path: str | PathLike[str],
                        prediction_paths: Sequence[str | PathLike[str]],
                        output: str | PathLike[str]) -> Path:
    """Write the campaign's HTML page.

    Parameters
    ----------
    fit_path
        ``slipwave slider-fit``'s JSON.
    prediction_paths
        ``slipwave slider-predict``'s JSONs, one per record.
    output
        The page to write.

    Returns
    -------
    Path
        The page.
    """
    fit = json.loads(Path(fit_path).read_text(encoding="utf-8"))
    predictions = [json.loads(Path(path).read_text(encoding="utf-8"))
                   for path in prediction_paths]
    held_out = [p for p in predictions if p["role"] == "predict"]
    html = page_template("sliders.html.j2").render(
        title="spring-slider campaign", version=__version__, fit=fit,
        predictions=predictions, features=FEATURE_TITLES,
        regimes_right=sum(p["regime"]["predicted"] == p["regime"]["measured"] for p in held_out),
        held_out=len(held_out), figure=png_base64(plot_predictions(predictions)))
    with atomic_output(output) as temporary:
        temporary.write_text(html, encoding="utf-8")
    return Path(output)
