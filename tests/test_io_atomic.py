"""Outputs written whole or not at all: interrupted writes and stale parts."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from slipwave.io import atomic_output

BIN = Path(sys.executable).parent


def test_sigterm_during_a_write_leaves_nothing(tmp_path):
    big = tmp_path / "big.csv"
    rows = "".join(f"{k / 1000:.3f},{k % 97},-80,0.1,0.2,{k / 1e5:.5f}\n" for k in range(400_000))
    big.write_text("time [s],T [N],N [N],DG [mm],DD [mm],DT [mm]\n" + rows)
    out = tmp_path / "out"
    out.mkdir()
    process = subprocess.Popen([str(BIN / "slipwave"), "ingest", str(big), "-o",
                                str(out / "rec.nc")], stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not list(out.glob(".rec.nc.*.part")) and time.monotonic() < deadline:
        time.sleep(0.01)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    if process.returncode == 0:
        pytest.skip("the write finished before the signal arrived")
    assert process.returncode == 130, err
    assert "interrupted; nothing half-written was kept" in err
    assert list(out.iterdir()) == []


def test_an_interrupt_just_after_the_part_is_created_leaves_nothing(tmp_path,
                                                                         monkeypatch):
    """SIGTERM (as KeyboardInterrupt) between the part file's creation and its use.

    CI once caught test 8's signal there: the command said nothing half-written was
    kept, and the part file stayed.
    """
    import os

    real_close = os.close

    def interrupted_close(fd: int) -> None:
        real_close(fd)
        monkeypatch.setattr(os, "close", real_close)
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "close", interrupted_close)
    with pytest.raises(KeyboardInterrupt), atomic_output(tmp_path / "rec.nc") as temporary:
        temporary.write_bytes(b"never")
    assert list(tmp_path.iterdir()) == []


def test_a_stale_part_of_the_same_output_is_removed(tmp_path):
    stale = tmp_path / ".rec.nc.k1ll3d00.part"  # what SIGKILL leaves
    other = tmp_path / ".other.nc.k1ll3d00.part"
    stale.write_bytes(b"x" * 100)
    other.write_bytes(b"x")
    with atomic_output(tmp_path / "rec.nc") as temporary:
        temporary.write_bytes(b"whole")
    assert not stale.exists() and other.exists()
    assert (tmp_path / "rec.nc").read_bytes() == b"whole"


_STALLED_UNWIND = """
import argparse, sys, threading, time
from pathlib import Path
from slipwave import cli
from slipwave.io import atomic_output

cli.UNWIND_SECONDS = 1.0
lock = threading.Lock()


def write(args):
    with atomic_output(Path(sys.argv[1]) / "rec.nc") as part:
        part.write_bytes(b"half")
        try:  # (said inside: a signal that came before the try would skip the finally)
            print("writing", flush=True)
            time.sleep(60)
        finally:  # a clean-up that never ends: a lock the interrupted code still holds
            lock.acquire()
            lock.acquire()


class Parser:
    def parse_args(self, argv):
        return argparse.Namespace(run=write)


cli.build_parser = Parser
sys.exit(cli.main([]))
"""


def test_a_stalled_unwinding_after_sigterm_still_ends_and_leaves_nothing(tmp_path):
    """The watchdog ends a command whose clean-up hangs, its part file removed."""
    process = subprocess.Popen([sys.executable, "-c", _STALLED_UNWIND, str(tmp_path)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdout.readline() == "writing\n"
    assert len(list(tmp_path.glob(".rec.nc.*.part"))) == 1
    started = time.monotonic()
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=30)
    assert process.returncode == 130, err
    assert "nothing half-written was kept (the clean-up had not ended 1 s" in err
    assert time.monotonic() - started < 10
    assert list(tmp_path.iterdir()) == []
