"""Outputs written whole or not at all."""

from __future__ import annotations

import contextlib
import glob
import os
import secrets
from collections.abc import Iterable, Iterator
from os import PathLike
from pathlib import Path

_UMASK = os.umask(0)
os.umask(_UMASK)


def _part_name(target: Path) -> Path:
    """A ``.NAME.<pid>-<random>.part`` beside ``target``, naming the process writing it."""
    return target.parent / f".{target.name}.{os.getpid()}-{secrets.token_hex(6)}.part"


def _writer_alive(part: Path) -> bool:
    """Whether the process that named ``part`` still runs (a name without one: no)."""
    pid = part.name.rsplit(".", 2)[-2].split("-")[0]
    if not pid.isdigit():
        return False
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def remove_stale_parts(folders: Iterable[str | PathLike[str]]) -> list[Path]:
    """Remove the ``.part`` files that killed writers left under ``folders``.

    A process killed outright (SIGKILL, the out-of-memory killer) cannot remove the
    temporary file of :func:`atomic_output`; the workflow calls this when it starts
    and when a job fails. Files of writers still running are kept.

    Parameters
    ----------
    folders
        Searched recursively; missing ones are skipped.

    Returns
    -------
    list of Path
        The files removed.

    """
    removed = []
    for folder in folders:
        for part in Path(folder).rglob(".*.part"):
            if part.is_file() and not _writer_alive(part):
                part.unlink(missing_ok=True)
                removed.append(part)
    return removed


@contextlib.contextmanager
def atomic_output(path: str | PathLike[str]) -> Iterator[Path]:
    """Give a temporary path beside ``path`` and move it into place on success.

    The destination is written whole or not at all: a failure leaves any
    previous file untouched and no partial file behind. A process killed
    while writing (SIGKILL; the ``slipwave`` command turns SIGTERM into a
    clean exit) leaves its ``.NAME.<pid>-<random>.part`` file: the next write of
    the same output removes it, and so does :func:`remove_stale_parts`. Two
    processes writing the same output at once are not supported (a workflow never
    does that).

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
        if not _writer_alive(stale):
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

