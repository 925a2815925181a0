"""Outputs written whole or not at all."""

from __future__ import annotations

import contextlib
import glob
import os
import secrets
from collections.abc import Iterator
from os import PathLike
from pathlib import Path

_UMASK = os.umask(0)
os.umask(_UMASK)


def _part_name(target: Path) -> Path:
    """A random ``.NAME.<random>.part`` beside ``target``."""
    return target.parent / f".{target.name}.{secrets.token_hex(6)}.part"


@contextlib.contextmanager
def atomic_output(path: str | PathLike[str]) -> Iterator[Path]:
    """Give a temporary path beside ``path`` and move it into place on success.

    The destination is written whole or not at all: a failure leaves any
    previous file untouched and no partial file behind. A process killed
    while writing (SIGKILL; the ``slipwave`` command turns SIGTERM into a
    clean exit) leaves its ``.NAME.<random>.part`` file: the next write of the
    same output removes it. Two processes writing the same output at once are
    not supported (a workflow never does that).

    Parameters
    ----------
    path
        The destination.

    Yields
    ------
    Path
        The temporary file to write.

    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    for stale in target.parent.glob(f".{glob.escape(target.name)}.*.part"):
        stale.unlink(missing_ok=True)
    # The name is drawn before the file exists, so that an interrupt (SIGTERM arrives
    # as KeyboardInterrupt) just after its creation still finds it in ``finally``.
    temporary = _part_name(target)
    try:
        while True:
            try:
                os.close(os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
                break
            except FileExistsError:  # another write's file: draw again
                temporary = _part_name(target)
        yield temporary
        temporary.chmod(0o666 & ~_UMASK)  # created 0600; outputs follow the umask
        os.replace(temporary, target)
    finally:
        temporary.unlink(missing_ok=True)

