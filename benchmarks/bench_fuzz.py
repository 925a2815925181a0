"""Fuzzing of the acquisition-CSV reader, the campaign table and fit.json, at scale.

Every generated file must either be read or raise SlipwaveError: any other
exception escaping is a defect (hypothesis then prints the smallest such file).
Target (issue 12): at least 10 000 cases in a run, none escaping.
Run: make bench  (or python benchmarks/bench_fuzz.py [--examples N])
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
import warnings
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))

from fuzzing import (
    csv_like_text,
    mutated_csv,
    mutated_fit,
    mutated_table,
    table_like_text,
    use_fit,
)
from slipwave.campaign import check_campaign, read_campaign
from slipwave.errors import SlipwaveError
from slipwave.fit import read_fit
from slipwave.io import read_acquisition
from targets import check, finish

TARGET_CASES = 10_000
SCHEMA = json.loads((Path(__file__).parents[1] / "src/slipwave/schemas/tests.schema.json")
                    .read_text())
CONFIG = {"detection": {"gross_edge_ratio": 0.9}, "column_maps": {"labview_en": {"a": "T"}}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--examples", type=int, default=1900,
                        help="cases per strategy (six strategies)")
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="slipwave-fuzz-"))
    counts = {"read": 0, "refused": 0}
    escaped: list[str] = []

    def read_csv(content: bytes) -> None:
        path = folder / "fuzz.csv"
        path.write_bytes(content)
        try:
            read_acquisition(path)
            counts["read"] += 1
        except SlipwaveError:
            counts["refused"] += 1

    def read_table(content: bytes) -> None:
        path = folder / "fuzz.tsv"
        path.write_bytes(content)
        try:
            check_campaign(CONFIG, read_campaign(path), SCHEMA)
            counts["read"] += 1
        except SlipwaveError:
            counts["refused"] += 1

    def read_fit_json(content: object) -> None:
        path = folder / "fit.json"
        path.write_text(json.dumps(content))
        try:
            fit = read_fit(path)
        except SlipwaveError:
            counts["refused"] += 1
            return
        use_fit(fit)  # what the reader accepts, the stages can use
        counts["read"] += 1

    fuzz = settings(max_examples=args.examples, deadline=None, database=None,
                    suppress_health_check=list(HealthCheck))
    runs = {
        "CSV, random bytes": (read_csv, st.binary(max_size=400)),
        "CSV, CSV-like text": (read_csv, csv_like_text.map(str.encode)),
        "CSV, mutated valid files": (read_csv, mutated_csv()),
        "campaign table, table-like text": (read_table, table_like_text.map(str.encode)),
        "campaign table, mutated valid tables": (read_table, mutated_table()),
        "fit.json, mutated valid fits": (read_fit_json, mutated_fit()),
    }
    # a warning leaving the reader is an unhandled case too (pandas warns where it truncates)
    warnings.simplefilter("error")
    start = time.perf_counter()
    for name, (function, strategy) in runs.items():
        before = sum(counts.values())
        try:
            fuzz(given(strategy)(function))()
        except Exception as err:  # hypothesis re-raises the smallest failing case
            escaped.append(f"{name}: {type(err).__name__}: {err}")
        print(f"fuzz: {name}: {sum(counts.values()) - before} cases")
    took = time.perf_counter() - start
    total = sum(counts.values())
    print(f"fuzz: {total} cases in {took:.0f} s ({counts['read']} read, {counts['refused']} "
          f"refused with SlipwaveError), {len(escaped)} strategies with an escape")
    for line in escaped:
        print(f"fuzz: ESCAPED {line}")
    check("fuzz cases", total, TARGET_CASES, at_least=True)
    check("fuzz escapes", len(escaped), 0, at_least=False)
    finish()


if __name__ == "__main__":
    main()
