"""Snakemake runs without a Python start each: one helper process, a fork per run.

A ``snakemake -n`` costs some 4 s, of which 3 are its own and the Snakefile's imports;
the settings and malformed-config tests make about sixty. The helper imports them once
and forks a child per run, from a process with one thread (forking one with more could
leave a lock held in the child); the child changes to the run's folder, writes its
standard output and error to files and calls Snakemake's own command line, so a run is
the command's, its exit status and output included.
"""

from __future__ import annotations

import json
import os
import selectors
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

SERVER = r"""
import json, os, sys, traceback
import snakemake.cli
# the Snakefile's imports
import slipwave.campaign, slipwave.io.atomic, slipwave.map, slipwave.slider_campaign
import slipwave.validation
print("ready", flush=True)
for line in sys.stdin:
    request = json.loads(line)
    pid = os.fork()
    if pid == 0:
        code = 1
        try:
            for stream, path in ((1, request["stdout"]), (2, request["stderr"])):
                os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC), stream)
            os.chdir(request["cwd"])
            snakemake.cli.main(request["args"])
            code = 0
        except SystemExit as exit:
            code = exit.code if isinstance(exit.code, int) else int(exit.code is not None)
        except BaseException:
            traceback.print_exc()
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    print(json.dumps(os.waitstatus_to_exitcode(status)), flush=True)
"""


class Run(NamedTuple):
    """A run's exit status and output, as :func:`subprocess.run` gives them."""

    returncode: int
    stdout: str
    stderr: str


class SnakemakeRunner:
    """Snakemake's command line, run in children of one helper process.

    Parameters
    ----------
    env
        The helper's environment (the runs' too).
    scratch
        A folder for the runs' output files.
    """

    def __init__(self, env: dict[str, str], scratch: Path) -> None:
        self.scratch = scratch
        self.runs = 0
        self.process = subprocess.Popen([sys.executable, "-c", SERVER], env=env, text=True,
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        self._answer(120.0)  # "ready"

    def _answer(self, timeout: float) -> str:
        assert self.process.stdout is not None
        with selectors.DefaultSelector() as selector:
            selector.register(self.process.stdout, selectors.EVENT_READ)
            if not selector.select(timeout):
                self.process.kill()
                raise TimeoutError(f"snakemake gave no answer in {timeout} s")
        line = self.process.stdout.readline()
        if not line:
            raise RuntimeError(f"the snakemake helper stopped ({self.process.wait()})")
        return line

    def __call__(self, cwd: Path, *args: str, timeout: float = 300.0) -> Run:
        """Run ``snakemake *args`` in ``cwd``.

        Parameters
        ----------
        cwd
            The run's folder.
        *args
            Snakemake's arguments.
        timeout
            Seconds to wait for it.

        Returns
        -------
        Run
            Its exit status, standard output and error.
        """
        assert self.process.stdin is not None
        self.runs += 1
        stdout, stderr = (self.scratch / f"run{self.runs}.{name}" for name in ("out", "err"))
        request = {"cwd": str(cwd), "args": list(args), "stdout": str(stdout),
                   "stderr": str(stderr)}
        self.process.stdin.write(json.dumps(request) + "\n")
        self.process.stdin.flush()
        code = json.loads(self._answer(timeout))
        return Run(code, stdout.read_text(), stderr.read_text())

    def close(self) -> None:
        """Stop the helper."""
        if self.process.stdin is not None:
            self.process.stdin.close()
        self.process.wait(30)


def environment() -> dict[str, str]:
    """The tests' environment with this Python's bin folder first on PATH."""
    folder = Path(sys.executable).parent
    return {**os.environ, "PATH": f"{folder}{os.pathsep}{os.environ.get('PATH', '')}"}
