"""Hypothesis strategies for malformed acquisition files and campaign tables.

Shared by the fuzz tests (a few hundred cases each run) and ``benchmarks/bench_fuzz.py``
(tens of thousands).
"""

from __future__ import annotations

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
    return mutate(base, draw, b"\t\n\r#\" a1./")


csv_like_text = st.text(alphabet=st.sampled_from(CSV_ALPHABET), max_size=300)
table_like_text = st.text(alphabet=st.sampled_from(TABLE_ALPHABET), max_size=200)
