from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from dry_runs import SnakemakeRunner, environment

CANONICAL = """\
# test_id: t1
# sample_rate_hz: 100
# length_mm: 80
# height_mm: 40
# width_mm: 10
# speed_mm_s: 0.048
# normal_load_n: 85
time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]
0.00,0.5,-80.0,0.10,0.20,0.000
0.01,1.5,-80.5,0.11,0.21,0.001
0.02,2.5,-81.0,0.12,0.22,0.002
0.03,3.5,-81.5,0.13,0.23,0.003
"""


@pytest.fixture
def write(tmp_path: Path) -> Callable[..., Path]:
    """Write text (or bytes) to a file in tmp_path and return its path."""

    def _write(content: str | bytes, name: str = "test.csv", encoding: str = "utf-8") -> Path:
        path = tmp_path / name
        path.write_bytes(content if isinstance(content, bytes) else content.encode(encoding))
        return path

    return _write


@pytest.fixture(scope="module")
def snakemake_cli(tmp_path_factory: pytest.TempPathFactory) -> Iterator[SnakemakeRunner]:
    """Snakemake's command line, run by a helper that imports it once (:mod:`dry_runs`)."""
    runner = SnakemakeRunner(environment(), tmp_path_factory.mktemp("snakemake"))
    yield runner
    runner.close()


# The files that take longest go first: `make test`'s two workers take whole files in
# collection order (--no-loadscope-reorder), and the longest started last would end alone.
LONGEST_FIRST = ("test_workflow.py", "test_events_colas.py", "test_events_accuracy.py",
                 "test_video_waves.py")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Put the slowest files first (a stable sort: each file keeps its tests' order)."""
    rank = {name: k for k, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))
