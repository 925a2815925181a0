"""Runs refused before they start when the machine cannot hold them."""

from __future__ import annotations

import pytest

from slipwave.bench.generate import BenchTest, simulate_test
from slipwave.cli import main
from slipwave.errors import SlipwaveError


def test_simulate_and_bench_refuse_what_the_machine_cannot_hold(tmp_path, capsys):
    assert main(["simulate", "--fs", "1", "--elements", "1280", "--memory-limit", "1", "-o",
                 str(tmp_path / "s.nc")]) == 1
    assert "1280 elements and H = 40 mm needs about" in capsys.readouterr().err
    assert main(["simulate", "--fs", "1", "--height", "1e6", "-o", str(tmp_path / "s.nc")]) == 1
    assert "H = 1e+06 mm needs about" in capsys.readouterr().err
    with pytest.raises(SlipwaveError, match=r"'big' \(2000 elements.*more than the limit of 1"):
        simulate_test(BenchTest("big", elements=2000), memory_limit_gb=1.0)
    assert not (tmp_path / "s.nc").exists()
