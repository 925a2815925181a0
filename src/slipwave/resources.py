"""What the machine can give a run: checked before a large job starts, not after it fails."""

from __future__ import annotations

import os
from pathlib import Path

from slipwave.errors import SlipwaveError

MEMORY_LIMIT_VARIABLE = "SLIPWAVE_MEMORY_LIMIT_GB"
"""Environment variable that caps the memory a run may plan to use, GB."""


def available_memory() -> int:
    """Memory the machine can give now: ``MemAvailable``, else the physical memory.

    Returns
    -------
    int
        Bytes.

    """
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))


def require_memory(needed: int, what: str, *, limit_gb: float | None = None) -> None:
    """Refuse a run that would need more memory than the limit or the machine has.

    Parameters
    ----------
    needed
        The run's estimated peak, bytes.
    what
        The run, for the message (e.g. ``"condensing a slab of 2000 elements"``).
    limit_gb
        A cap, GB; ``None``: ``$SLIPWAVE_MEMORY_LIMIT_GB`` if set, else the memory
        available now.

    Raises
    ------
    SlipwaveError
        Saying what needs how much, the limit, and what to change.

    Examples
    --------
    >>> require_memory(10**6, "a small run", limit_gb=1.0)
    >>> require_memory(2 * 10**9, "a big run", limit_gb=1.0)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipwave.errors.SlipwaveError: a big run needs about 2.0 GB, more than the limit of 1 GB ...
    """
    if limit_gb is None and os.environ.get(MEMORY_LIMIT_VARIABLE):
        try:
            limit_gb = float(os.environ[MEMORY_LIMIT_VARIABLE])
        except ValueError as err:
            raise SlipwaveError(f"${MEMORY_LIMIT_VARIABLE} is "
                                f"{os.environ[MEMORY_LIMIT_VARIABLE]!r}, not a number") from err
    if limit_gb is not None:
        limit, source = limit_gb * 1e9, f"the limit of {limit_gb:g} GB"
    else:
        limit = available_memory()
        source = f"the {limit / 1e9:.1f} GB this machine has available"
    if needed > limit:
        raise SlipwaveError(
            f"{what} needs about {needed / 1e9:.1f} GB, more than {source} (fewer elements "
            f"or a smaller slab; or set ${MEMORY_LIMIT_VARIABLE} / --memory-limit)")
