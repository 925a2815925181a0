"""Outputs written whole or not at all."""

from __future__ import annotations

import contextlib
import glob
import os
import secrets
import socket
from collections.abc import Iterable, Iterator
from os import PathLike
from pathlib import Path

_UMASK = os.umask(0)
os.umask(_UMASK)

_PENDING: set[Path] = set()  # the part files of this process's writes under way


def _host() -> str:
    """The machine's name, as a ``.part`` file's name holds it (no dot, no dash)."""
    return socket.gethostname().replace(".", "_").replace("-", "_") or "host"


def _part_name(target: Path) -> Path:
    """A ``.NAME.<host>-<pid>-<random>.part`` beside ``target``: who writes it."""
    return target.parent / (f".{target.name}.{_host()}-{os.getpid()}-"
                            f"{secrets.token_hex(6)}.part")


def _writer_alive(part: Path) -> bool:
    """Whether the process that named ``part`` may still run.

    One on another machine (a cluster's node) may: it is not known here. A name
    without a writer is a dead one's.
    """
    writer = part.name.rsplit(".", 2)[-2].rsplit("-", 2)
    if len(writer) != 3 or not writer[1].isdigit():
        return False
    if writer[0] != _host():
        return True
    try:
        os.kill(int(writer[1]), 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def remove_stale_parts(folders: Iterable[str | PathLike[str]], *,
                       nothing_runs: bool = False) -> list[Path]:
    """Remove the ``.part`` files that killed writers left under ``folders``.

    A process killed outright (SIGKILL, the out-of-memory killer) cannot remove the
    temporary file of :func:`atomic_output`; the workflow calls this when it starts
    (when nothing of it runs) and when a job fails. Otherwise the files of writers
    that may still run are kept: this machine's running processes, and any on
    another machine.

    Parameters
    ----------
    folders
        Searched recursively; missing ones are skipped.
    nothing_runs
        Whether the caller knows that no writer runs (every ``.part`` is then stale).

    Returns
    -------
    list of Path
        The files removed.

    """
    removed = []
    for folder in folders:
        for part in Path(folder).rglob(".*.part"):
            if part.is_file() and (nothing_runs or not _writer_alive(part)):
                part.unlink(missing_ok=True)
                removed.append(part)
    return removed


@contextlib.contextmanager
def atomic_output(path: str | PathLike[str]) -> Iterator[Path]:
    """Give a temporary path beside ``path`` and move it into place on success.

    The destination is written whole or not at all: a failure leaves any
    previous file untouched and no partial file behind. A process killed
    while writing (SIGKILL; the ``slipwave`` command turns SIGTERM into a
    clean exit) leaves its ``.NAME.<host>-<pid>-<random>.part`` file: the next write of
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
    _PENDING.add(temporary)
    try:
        while True:
            try:
                os.close(os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
                break
            except FileExistsError:  # another write's file: draw again
                _PENDING.discard(temporary)
                temporary = _part_name(target)
                _PENDING.add(temporary)
        yield temporary
        temporary.chmod(0o666 & ~_UMASK)  # created 0600; outputs follow the umask
        os.replace(temporary, target)
    finally:
        temporary.unlink(missing_ok=True)
        _PENDING.discard(temporary)


def remove_pending_parts() -> list[Path]:
    """Remove the part files of this process's writes under way, as it gives up.

    For a process that must end at once without unwinding (the ``slipwave`` command
    when unwinding after SIGTERM does not end in time): its :func:`atomic_output`
    blocks will not run their own clean-up.

    Returns
    -------
    list of Path
        The files removed.

    """
    removed = []
    for part in list(_PENDING):
        part.unlink(missing_ok=True)
        removed.append(part)
    return removed

