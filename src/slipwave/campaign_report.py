"""The campaign_report stage: one page (HTML and PDF) over a campaign's tests.

One row per test (its slips, its fitted law, its verdicts, its place on the behaviour
map) and the figures over the tests: T/|N| and the fitted coefficients against H/L,
and the map with the tests.
"""

from __future__ import annotations

from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from slipwave import __version__
from slipwave.io import atomic_output
from slipwave.plot import plot_campaign, plot_map
from slipwave.report import page_template, png_base64, write_pdf


def campaign_summary(summary: pd.DataFrame, fits: pd.DataFrame | None,
                     comparisons: dict[str, dict[str, Any]],
                     behaviour_map: xr.Dataset | None = None) -> dict[str, Any]:
    """The campaign report's content: one row per test, the figures over the tests.

    Parameters
    ----------
    summary
        ``results/summary.csv`` (:func:`slipwave.events.summary_row` per test).
    fits
        ``results/fits.csv`` (:func:`slipwave.fits.fits_table`), or ``None``.
    comparisons
        Each test's ``comparison.json`` by test id (verdict counts, place on the map).
    behaviour_map
        ``map.nc``, or ``None``.

    Returns
    -------
    dict
        ``tests`` (rows), ``figures`` (base64 PNG) and ``missing``.

    """
    rows = []
    fitted = fits.set_index("test_id") if fits is not None and len(fits) else None
    for _, test in summary.iterrows():
        test_id = str(test["test_id"])
        row: dict[str, Any] = {"test_id": test_id, **{
            key: test.get(key) for key in ("gross_slip_waves", "partial_slip_waves",
                                           "static_ratio_mean", "static_ratio_ci_low",
                                           "static_ratio_ci_high", "dynamic_ratio_mean")}}
        if fitted is not None and test_id in fitted.index:
            fit = fitted.loc[test_id]
            row.update(height_ratio=fit["height_ratio"], law=fit["law"],
                       fs=fit["fs"], fs_low=fit["fs_low"], fs_high=fit["fs_high"],
                       fd=fit["fd"], fd_low=fit["fd_low"], fd_high=fit["fd_high"],
                       mesh_change=[fit.get(f"{name}_mesh_change", np.nan)
                                    for name in ("fs", "fd")])
        compared = comparisons.get(test_id, {})
        row["verdicts"] = compared.get("verdicts", {})
        row["behaviour"] = (compared.get("map") or {}).get("behaviour", "")
        rows.append(row)
    missing = []
    figures: dict[str, str | None] = {"fits": None, "map": None}
    if fitted is not None and fits is not None:
        figures["fits"] = png_base64(plot_campaign(summary, fits))
    else:
        missing.append("no fits: the tests were not fitted")
    if behaviour_map is not None and fitted is not None:
        tests = pd.DataFrame({"test_id": fitted.index, "height_ratio": fitted["height_ratio"],
                              "ratio": fitted["fs"], "ci_low": fitted["fs_low"],
                              "ci_high": fitted["fs_high"]})
        figures["map"] = png_base64(plot_map(behaviour_map, tests.reset_index(drop=True),
                                       label="tests (fitted fs, 95 % interval)"))
    else:
        missing.append("no behaviour map with the tests")
    return {"tests": rows, "figures": figures, "missing": missing}


def write_campaign_report(content: dict[str, Any], path: str | PathLike[str], *,
                          pdf: str | PathLike[str] | None = None,
                          title: str = "Campaign") -> Path:
    """Write the campaign report (HTML, and PDF), whole or not at all.

    Parameters
    ----------
    content
        From :func:`campaign_summary`.
    path
        The HTML file.
    pdf
        Also print it to this PDF; ``None``: no PDF.
    title
        The report's title.

    Returns
    -------
    Path
        The page written.

    """
    html = page_template("campaign.html.j2").render(
        title=title, version=__version__, **content)
    if pdf is not None:
        write_pdf(html, pdf)
    with atomic_output(path) as temporary:
        temporary.write_text(html, encoding="utf-8")
    return Path(path)
