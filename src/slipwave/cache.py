"""The on-disk store of the solver's condensed matrices, shared across processes.

Condensing a slab takes 0.2-1.8 s at 160 elements; every simulation of the same
geometry (a map row, a campaign's tests, repeated runs) reuses it from here.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from slipwave.io.atomic import atomic_output
from slipwave.solver.slab import Condensed


def default_cache_folder() -> Path:
    """``$SLIPWAVE_CACHE_DIR``, else ``$XDG_CACHE_HOME/slipwave`` (``~/.cache/slipwave``).

    Returns
    -------
    Path
        The folder (not created).

    """
    explicit = os.environ.get("SLIPWAVE_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "slipwave"


@dataclass(frozen=True)
class DiskCache:
    """Condensed matrices as ``condensed-<key>.npz`` files in ``folder``.

    A damaged file is rebuilt; a folder that cannot be written only costs time.
    Hand it to :func:`slipwave.solver.condense` as ``store``.
    """

    folder: Path = field(default_factory=default_cache_folder)

    def _path(self, key: str) -> Path:
        return Path(self.folder) / f"condensed-{key}.npz"

    def load(self, key: str) -> Condensed | None:
        """The matrices stored under ``key``, or ``None``.

        Parameters
        ----------
        key
            From :func:`slipwave.solver.slab.geometry_key`.

        Returns
        -------
        Condensed or None
            The stored matrices, or ``None`` when missing or unreadable.

        """
        path = self._path(key)
        if not path.exists():
            return None
        try:
            with np.load(path) as stored:
                return Condensed(stored["stiffness"], stored["sensors"], stored.get("compliance"))
        except (OSError, ValueError, KeyError):
            return None  # a damaged cache file is rebuilt

    def save(self, key: str, condensed: Condensed) -> None:
        """Store ``condensed`` under ``key``, whole or not at all.

        Parameters
        ----------
        key
            From :func:`slipwave.solver.slab.geometry_key`.
        condensed
            The matrices for E = 1.

        """
        try:
            with atomic_output(self._path(key)) as temporary, open(temporary, "wb") as handle:
                if condensed.compliance is None:
                    np.savez(handle, stiffness=condensed.stiffness, sensors=condensed.sensors)
                else:
                    np.savez(handle, stiffness=condensed.stiffness, sensors=condensed.sensors,
                             compliance=condensed.compliance)
        except OSError:
            pass  # a read-only cache only costs time
