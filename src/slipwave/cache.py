"""The on-disk store of the solver's condensed matrices, shared across processes.

Condensing a slab costs far more than one of its load steps; the simulations of the
same geometry in other processes (a map's rows, a campaign's tests, repeated runs)
reuse it from a folder the caller names: the workflow's ``cache_dir`` under its
results, or the command line's ``--cache-dir``. Nothing is written anywhere else.
"""

from __future__ import annotations

import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from slipwave.io.atomic import atomic_output
from slipwave.solver.slab import Condensed


@dataclass(frozen=True)
class DiskCache:
    """Condensed matrices as ``condensed-<key>.npz`` files in ``folder``.

    Each file keeps its key beside the matrices: a damaged file, or one of another
    geometry under the key's name, is rebuilt; a folder that cannot be written only
    costs time.
    Hand it to :class:`slipwave.solver.SolverCache` as its ``store``.

    Attributes
    ----------
    folder
        Where the files are (created on the first save).
    """

    folder: Path

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
            The stored matrices, or ``None`` when missing, unreadable, stored under
            another key or not of one shape.

        """
        path = self._path(key)
        if not path.exists():
            return None
        try:
            with np.load(path) as stored:
                if str(stored["key"]) != key:
                    return None  # another geometry's file under this name
                condensed = Condensed(stored["stiffness"], stored["sensors"])
        except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError):
            return None  # a damaged cache file is rebuilt
        size = condensed.stiffness.shape[0]
        shapes = [condensed.stiffness.shape == (size, size), condensed.sensors.shape == (2, size)]
        return condensed if all(shapes) else None

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
                np.savez(handle, key=np.array(key), stiffness=condensed.stiffness,
                         sensors=condensed.sensors)
        except OSError:
            pass  # a read-only cache only costs time
