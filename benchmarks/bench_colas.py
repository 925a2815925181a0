"""Issue 36's acceptance on real records: fit six Colas records, predict the other three.

Rate-and-state friction (aging law) is fitted jointly on the six Colas et al. (2019)
records at 168 and 1002 N/m with the schema's settings (``slipwave.fit.slider``), on one
core as the issue asks the time for, with one state variable, then with two (the
two-state search starting from the one-state fit's best guesses, its second state idle),
then with one state and a cut-off speed (started alike, the cut-off at 1 m/s); the
three records at 2254 N/m are read only to be compared with each law's posterior
predictive, after the fits. Targets, for each law: each held-out record's regime
predicted right and its median drop and recurrence inside the predictive's 95 %
interval (issue 36). Writes the one-state law's predictions of the nine records as
docs/_static/colas_predictions.png.
Run: python benchmarks/bench_colas.py (needs ../shared/data/colas2019)
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from slipwave.defaults import SLIDER_DEFAULTS
from slipwave.fit.slider import (
    SliderFitSettings,
    SliderPosterior,
    SliderRecord,
    fit_records,
    nested_start,
    predict_record,
    slider_record,
)
from slipwave.io.slider_record import read_slider_record
from slipwave.slider_campaign import read_slider_campaign
from slipwave.slider_report import plot_predictions
from targets import check, finish

ROOT = Path(__file__).parents[1]
DATA = ROOT.parent / "shared" / "data" / "colas2019"
FIGURE = ROOT / "docs" / "_static" / "colas_predictions.png"


def _record(row_id: str, row: pd.Series) -> SliderRecord:
    path = ROOT / str(row["mat"])
    return slider_record(row_id, read_slider_record(path),
                         stiffness=float(row["stiffness_n_m"]),
                         drive_speed=float(row["drive_speed_um_s"]) * 1e-6,
                         mass=float(row["mass_g"]) * 1e-3,
                         normal_load=float(row["normal_load_n"]),
                         window=float(row["window_s"]))


def main() -> None:
    if hasattr(os, "sched_setaffinity"):  # here, not at import: bench_colas_laws reads _record
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})  # one core, as the issue says
    if not DATA.is_dir():
        print(f"colas: {DATA} is not there; nothing measured")
        sys.exit(0)
    table = read_slider_campaign(ROOT / "config" / "colas.tsv")
    fitted = [_record(i, row) for i, row in table[table["role"] == "fit"].iterrows()]
    one_state = _fit_and_predict(table, fitted, 1, None)
    _fit_and_predict(table, fitted, 2, nested_start(one_state))
    _fit_and_predict(table, fitted, 1, nested_start(one_state, 1, cutoff=True), cutoff=True)
    finish()


def _line(predicted: dict[str, Any]) -> str:
    """A record's predicted regime and features against the measured ones, on one line."""
    regime = predicted["regime"]
    parts = [f"{predicted['record']}: regime {regime['predicted']} for {regime['measured']}"]
    for name in ("drop", "recurrence", "stuck_share"):
        entry = predicted[name]
        parts.append(f"{name} {entry['measured']:.3g} in [{entry['low']:.3g}, "
                     f"{entry['high']:.3g}]: {'yes' if entry['inside'] else 'NO'}")
    return "; ".join(parts)


def _predictions(table: pd.DataFrame, fitted: list[SliderRecord], posterior: SliderPosterior,
                 tag: str) -> list[dict[str, Any]]:
    """Every record's posterior predictive: the fitted ones, then the held-out ones (read
    only here, after the fit), each printed as it comes."""
    predictions = []
    for record in fitted:  # in-sample: does the law reproduce what it was fitted to?
        predicted = predict_record(record, posterior, SLIDER_DEFAULTS["draws"],
                                   SLIDER_DEFAULTS["members"], SLIDER_DEFAULTS["seed"])
        predictions.append({**predicted, "role": "fit"})
        print(f"{tag}: fitted {_line(predicted)}", flush=True)
    for record_id, row in table[table["role"] == "predict"].iterrows():
        predicted = predict_record(_record(str(record_id), row), posterior,
                                   SLIDER_DEFAULTS["draws"], SLIDER_DEFAULTS["members"],
                                   SLIDER_DEFAULTS["seed"])
        predictions.append({**predicted, "role": "predict"})
        print(f"{tag}: held out {_line(predicted)}", flush=True)
    return predictions


def _fit_and_predict(table: pd.DataFrame, fitted: list[SliderRecord], states: int,
                     start: np.ndarray | None, cutoff: bool = False) -> SliderPosterior:
    tag = f"colas ({states} state{'s' if states > 1 else ''}{', cut-off' if cutoff else ''})"
    settings = SliderFitSettings(processes=1, states=states, cutoff=cutoff)
    began = time.perf_counter()
    posterior = fit_records(fitted, settings, start=start,
                            progress=lambda line: print(f"{tag}: {line}", flush=True))
    seconds = time.perf_counter() - began
    print(f"{tag}: six records fitted in {seconds:.0f} s on one core "
          f"({len(posterior.points)} guesses)")
    for name, (middle, low, high) in posterior.interval().items():
        print(f"{tag}: {name} {middle:.4g} [{low:.4g}, {high:.4g}]")
    predictions = _predictions(table, fitted, posterior, tag)
    if states == 1 and not cutoff:  # the methods page's figure
        plot_predictions(predictions).savefig(FIGURE, dpi=100)
    held_out = [p for p in predictions if p["role"] == "predict"]
    counts = {"regimes right": sum(p["regime"]["predicted"] == p["regime"]["measured"]
                                   for p in held_out),
              "drops inside": sum(p["drop"]["inside"] for p in held_out),
              "recurrences inside": sum(p["recurrence"]["inside"] for p in held_out)}
    for name, value in counts.items():
        print(f"{tag}: {name} {value} of {len(held_out)} "
              f"({check(f'{tag}: {name}', value, len(held_out), at_least=True)})")
    return posterior


if __name__ == "__main__":
    main()
