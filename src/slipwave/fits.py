"""The fits stage: a campaign's fits in one table, one row per test.

Each test's chosen law with its fs and fd and their 95 % intervals, and every law's
parameters and log Bayes factor against the chosen law, from the tests' ``fit.json``
(:func:`slipwave.fit.fit_test`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import pandas as pd


def fits_table(fits: Sequence[Mapping[str, Any]]) -> pd.DataFrame:
    """The campaign's fits, one row per test.

    Parameters
    ----------
    fits
        ``fit.json`` contents (:func:`fit_test`).

    Returns
    -------
    pandas.DataFrame
        ``test_id``, ``height_ratio``, ``law`` (chosen), ``gross_slips``, each
        parameter of each law as ``<law>_<name>``, ``_low``, ``_high``, each law's
        ``<law>_log_bayes_factor``, whether the chosen law's posterior predictive
        agrees on every feature (``predictive_agrees``), and its ``fs``, ``fd`` with their
        intervals
        and, when the fit checked its mesh, their relative change at twice it
        (``fs_mesh_change``, ``fd_mesh_change``; empty otherwise).

    """
    rows = []
    for fit in fits:
        setup = fit["setup"]
        row: dict[str, Any] = {
            "test_id": fit["test_id"],
            "height_ratio": setup["height_mm"]["value"] / setup["length_mm"]["value"],
            "law": fit["chosen"], "gross_slips": fit["measured"]["gross_slips"],
            "predictive_agrees": all(check["agrees"]
                                     for check in fit.get("predictive", {}).values())}
        chosen = fit["laws"][fit["chosen"]]["parameters"]
        finer = fit.get("mesh_check") or {}
        for name in ("fs", "fd"):
            row[name] = chosen[name]["value"]
            row[f"{name}_low"], row[f"{name}_high"] = chosen[name]["low"], chosen[name]["high"]
            row[f"{name}_mesh_change"] = finer.get("change", {}).get(name)
        for law, entry in fit["laws"].items():
            key = law.replace("-", "_")
            row[f"{key}_log_bayes_factor"] = entry["log_bayes_factor"]
            for name, value in entry["parameters"].items():
                row[f"{key}_{name}"] = value["value"]
                row[f"{key}_{name}_low"] = value["low"]
                row[f"{key}_{name}_high"] = value["high"]
        rows.append(row)
    return pd.DataFrame(rows)
