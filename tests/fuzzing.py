"""Hypothesis strategies for malformed acquisition files and campaign tables.

Shared by the fuzz tests (a few hundred cases each run) and ``benchmarks/bench_fuzz.py``
(tens of thousands).
"""

from __future__ import annotations

import copy

from hypothesis import strategies as st

from conftest import CANONICAL

CSV_VARIANTS = [
    CANONICAL,
    CANONICAL.replace(",", ";").replace(".", ","),
    CANONICAL.replace(",", "\t").replace("\n", "\r\n"),
    "Temps;Ft;Fn\ns;N;N\n0;0,5;-80\n0,01;1,5;-80,5\n",
    "# sample_rate_hz: 100\nT [N],N [N]\n1,2\n3,4\n",
]

CSV_ALPHABET = list("0123456789.,;\t\n\r-+eE#: []()TNDGtimsµk")

TABLE_VARIANTS = [
    "test_id\tcsv\tframes\tcolumns\tedge_reference\na\tx.csv\t\t\t\nb\ty.csv\tv.mkv\t\tflat\n",
    "# campaign\ntest_id\tcsv\n\nrun01\t/data/r1.csv\n# gone\nrun02\t/data/r2.csv\n",
    "test_id\tcsv\tcolumns\tfps\nhl050\traw.csv\tlabview_en\t25\n",
    "test_id\tcsv\tyoungs_modulus_mpa\tpoisson_ratio\tedge_reference\theight_mm\n"
    "run1\tr.csv\t7\t0.48\tframe\t40\nmap2\tx.csv\t1e3\t0.3\tflat\t\nRun1b\ty.csv\t\t\t\t1.5e1\n",
]

TABLE_ALPHABET = [*"abcAB01._-/ \t\n\r#\"'\\:;,éµ", "\x00", "\ufeff"]


def mutate(base: bytes, draw: st.DrawFn, alphabet: bytes) -> bytes:
    """Delete, insert, replace, truncate or duplicate a few pieces of ``base``."""
    content = bytearray(base)
    for _ in range(draw(st.integers(1, 6))):
        action = draw(st.sampled_from(["delete", "insert", "replace", "truncate", "duplicate"]))
        if not content:
            break
        at = draw(st.integers(0, len(content) - 1))
        if action == "delete":
            del content[at : at + draw(st.integers(1, 8))]
        elif action == "insert":
            content[at:at] = draw(st.binary(min_size=1, max_size=6))
        elif action == "replace":
            content[at] = draw(st.sampled_from(alphabet))
        elif action == "truncate":
            del content[at:]
        else:
            end = content.find(b"\n", at)
            start = content.rfind(b"\n", 0, at)
            content[end:end] = content[start:end]
    return bytes(content)


@st.composite
def mutated_csv(draw: st.DrawFn) -> bytes:
    """A valid acquisition CSV with a few random edits."""
    base = draw(st.sampled_from(CSV_VARIANTS)).encode("utf-8")
    return mutate(base, draw, b"0.,;\t\n\r-xe# []()")


@st.composite
def mutated_table(draw: st.DrawFn) -> bytes:
    """A valid campaign table with a few random edits."""
    base = draw(st.sampled_from(TABLE_VARIANTS)).encode("utf-8")
    return mutate(base, draw, b"\t\n\r#\" a1./e-5")


csv_like_text = st.text(alphabet=st.sampled_from(CSV_ALPHABET), max_size=300)
table_like_text = st.text(alphabet=st.sampled_from(TABLE_ALPHABET), max_size=200)


SETUP = {"test_id": "small", "edge_reference": "frame",
         **{key: {"value": value, "source": "campaign table"} for key, value in {
             "length_mm": 80.0, "height_mm": 40.0, "width_mm": 10.0,
             "youngs_modulus_mpa": 7.0, "poisson_ratio": 0.48, "normal_load_n": 85.0,
             "speed_mm_s": 0.1, "machine_stiffness_n_mm": 40.0, "duration_s": 60.0,
             "loading_time_s": 5.0}.items()}}
"""A short test's setup (60 s, a small slab): cheap to simulate."""


def valid_fit(**changes: object) -> dict:
    """A ``fit.json`` as ``slipwave fit`` writes it (Coulomb chosen), with ``changes``."""
    law = {"law": "coulomb",
           "parameters": {"fs": {"value": 0.8, "low": 0.75, "high": 0.85, "units": "1"},
                          "fd": {"value": 0.6, "low": 0.55, "high": 0.65, "units": "1"}},
           "log_evidence": -12.5, "log_bayes_factor": 0.0, "rejected": False,
           "guesses": 20, "simulations": 80, "mesh_error": {"first_ratio": 0.004}}
    fit = {"test_id": "small", "recording_sha256": "0" * 64, "setup": SETUP, "elements": 16,
           "detection": {"threshold": 8.0, "max_spike": 2, "max_duration": None,
                         "min_fall_rate": 1.2, "edge_convention": "auto"},
           "load_calibration": 0.02,
           "measured": {"slips": 3, "gross_slips": 2, "min_drop_n": 0.3},
           "edge_threshold": 0.9, "features": {"first_ratio": 0.55},
           "laws": {"coulomb": law}, "chosen": "coulomb",
           "parameters": {"fs": 0.8, "fd": 0.6}, "parameters_note": None,
           "settings": {"members": 4},
           "predictive": {"first_ratio": {"measured": 0.55, "simulated": 0.56, "spread": 0.01,
                                          "z": -1.0, "agrees": True}}}
    fit.update(changes)
    return copy.deepcopy(fit)


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-10, 10**6) | st.floats(allow_nan=False)
    | st.text(max_size=8),
    lambda children: st.lists(children, max_size=3)
    | st.dictionaries(st.text(max_size=6), children, max_size=3),
    max_leaves=6)


@st.composite
def mutated_fit(draw: st.DrawFn) -> object:
    """A valid fit.json's content with a few keys deleted, replaced or added, anywhere."""
    fit: object = valid_fit()
    for _ in range(draw(st.integers(1, 4))):
        # walk down to a random mapping or list, then change one of its entries
        node, path = fit, []
        while isinstance(node, (dict, list)) and node and draw(st.booleans()):
            keys = list(node) if isinstance(node, dict) else list(range(len(node)))
            key = draw(st.sampled_from(keys))
            path.append(key)
            node = node[key]
        parent: object = fit
        for key in path[:-1]:
            parent = parent[key]  # type: ignore[index]
        action = draw(st.sampled_from(["delete", "replace", "add"]))
        if not path:
            fit = draw(JSON_VALUES) if action == "replace" else fit
            continue
        last = path[-1]
        if action == "delete" and isinstance(parent, dict):
            del parent[last]
        elif action == "add" and isinstance(parent, dict):
            parent[draw(st.text(max_size=6))] = draw(JSON_VALUES)
        else:
            parent[last] = draw(JSON_VALUES)  # type: ignore[index]
    return fit


def use_fit(fit: dict) -> None:
    """Use a fit as the stages do: its law, setup, slab, load path, detection and table."""
    from slipwave.events import DetectionSettings
    from slipwave.fit import chosen_law
    from slipwave.fits import fits_table
    from slipwave.setup import TestSetup

    chosen_law(fit)
    setup = TestSetup.from_dict(fit["setup"])
    setup.slab(int(fit["elements"]))
    setup.load_path()
    DetectionSettings.from_dict(fit["detection"])
    assert len(fits_table([fit])) == 1
