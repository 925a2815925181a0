"""What a process's simulations share: condensed slabs, their bodies, frictionless approaches.

A :class:`SolverCache` is owned by whoever runs many simulations of the same slab (a
map row, a fit, the command line's process) and handed to :func:`~slipwave.solver.condense`
and :func:`~slipwave.solver.simulate`. It keeps, in memory and least recently used
first out:

- the condensed matrices of a slab's geometry and mesh, for E = 1
  (:func:`~slipwave.solver.slab.geometry_key`), and, through ``store``, on disk
  across processes (:class:`slipwave.cache.DiskCache`);
- a slab's body (:class:`~slipwave.solver.contact.Body`, its condensation for its
  Young's modulus and gaps), restarted by each simulation rather than made again;
- the steps of a frictionless normal approach, which do not depend on the friction
  law, so that a map row or a fit presses the flat once.

Entries are keyed by what they are computed from, never by an object's identity.
Without a cache, every call computes afresh.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any

from slipwave.solver.slab import CondensationStore, Condensed

CONDENSATIONS_KEPT = 32
"""Geometries kept in memory (a map's 12 H/L values fit)."""
APPROACHES_KEPT = 4
"""Frictionless normal approaches kept in memory."""
BODIES_KEPT = 4
"""Bodies kept in memory (each holds two (2n, 2n) working arrays beside its stiffness)."""


class SolverCache:
    """Condensed slabs, their bodies and normal approaches, shared by a process's runs.

    Parameters
    ----------
    store
        Where condensed matrices outlive the process; ``None``: memory only.

    Examples
    --------
    >>> from slipwave.solver import Slab, condense
    >>> cache = SolverCache()
    >>> soft = condense(Slab(elements=8), cache=cache)
    >>> stiff = condense(Slab(elements=8, youngs_modulus=14.0), cache=cache)
    >>> len(cache)  # one geometry, scaled by E
    1
    """

    def __init__(self, store: CondensationStore | None = None) -> None:
        self.store = store
        self._condensed: OrderedDict[str, Condensed] = OrderedDict()
        self._approaches: OrderedDict[Hashable, Any] = OrderedDict()
        self._bodies: OrderedDict[Hashable, Any] = OrderedDict()

    def __len__(self) -> int:
        return len(self._condensed)

    def condensed(self, key: str, assemble: Callable[[], Condensed]) -> Condensed:
        """The unit condensation of ``key``: from memory, the store, or ``assemble``.

        Parameters
        ----------
        key
            From :func:`~slipwave.solver.slab.geometry_key`.
        assemble
            Computes it on a miss (then handed to the store).

        Returns
        -------
        Condensed
            The matrices for E = 1.

        """
        unit = self._condensed.get(key)
        if unit is None and self.store is not None:
            unit = self.store.load(key)
        if unit is None:
            unit = assemble()
            if self.store is not None:
                self.store.save(key, unit)
        _keep(self._condensed, key, unit, CONDENSATIONS_KEPT)
        return unit

    def approach(self, key: Hashable) -> Any:
        """A kept frictionless approach, or ``None``.

        Parameters
        ----------
        key
            What the approach was computed from.

        Returns
        -------
        object or None
            What :meth:`keep_approach` was given.

        """
        found = self._approaches.get(key)
        if found is not None:
            self._approaches.move_to_end(key)
        return found

    def keep_approach(self, key: Hashable, approach: Any) -> None:
        """Keep a frictionless approach under ``key``.

        Parameters
        ----------
        key
            What it was computed from.
        approach
            The steps and state to reuse.

        """
        _keep(self._approaches, key, approach, APPROACHES_KEPT)

    def body(self, key: Hashable, make: Callable[[], Any]) -> Any:
        """A kept body, or the one ``make`` returns, kept under ``key``.

        Parameters
        ----------
        key
            What the body is computed from.
        make
            Computes it on a miss.

        Returns
        -------
        object
            What ``make`` returned, now or earlier: the caller restarts it.

        """
        found = self._bodies.get(key)
        if found is None:
            found = make()
        _keep(self._bodies, key, found, BODIES_KEPT)
        return found


def _keep(entries: OrderedDict[Any, Any], key: Hashable, value: Any, kept: int) -> None:
    """Put ``value`` last (the most recently used) and drop the oldest beyond ``kept``."""
    entries[key] = value
    entries.move_to_end(key)
    while len(entries) > kept:
        entries.popitem(last=False)
