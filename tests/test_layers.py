"""The package's layers at run time: the analysis of a test loads neither the virtual
bench nor a video or PDF library (the import contracts check the same statically)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest


@pytest.mark.parametrize("module", ["slipwave.setup", "slipwave.fit", "slipwave.simulate",
                                    "slipwave.compare", "slipwave.solver", "slipwave.events"])
def test_the_analysis_of_a_test_loads_no_bench_and_no_video_library(module):
    probe = (f"import json, sys, {module}; print(json.dumps(sorted(m for m in sys.modules "
             "if m.split('.')[0] in ('av', 'weasyprint') or m.startswith('slipwave.bench'))))")
    loaded = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                            check=True)
    assert json.loads(loaded.stdout) == []


def test_the_workflow_plans_and_joins_the_map_without_the_solver():
    # the Snakefile and `slipwave map assemble` import slipwave.map: numba and the
    # solver would add 0.4 s to every snakemake start and to the map's join
    probe = ("import json, sys, slipwave.map; print(json.dumps(sorted(m for m in sys.modules "
             "if m.split('.')[0] == 'numba' or m.startswith('slipwave.solver'))))")
    loaded = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                            check=True)
    assert json.loads(loaded.stdout) == []
