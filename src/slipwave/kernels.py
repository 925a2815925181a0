"""What numba's disk cache did for a module's compiled kernels."""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numba


def cache_report(module: ModuleType) -> dict[str, dict[str, Any]]:
    """Each compiled kernel of ``module`` called so far: where it is cached, and how often.

    Parameters
    ----------
    module
        A module whose functions numba compiles (``@njit(cache=True)``).

    Returns
    -------
    dict
        Per kernel name, its ``cache_path``, ``loaded`` (cache hits) and ``compiled``
        (misses); kernels never called are left out.

    Examples
    --------
    >>> import numpy as np
    >>> from slipwave.events import load_drops, steps
    >>> t = np.arange(2000) / 100.0
    >>> _ = load_drops(t, 2.0 * (t % 5.0))
    >>> kernel = cache_report(steps)["_lowest_before_rise"]
    >>> kernel["loaded"] + kernel["compiled"] >= 1
    True
    """
    kernels = {}
    for name in dir(module):
        kernel = getattr(module, name)
        if isinstance(kernel, numba.core.registry.CPUDispatcher) and kernel.signatures:
            stats = kernel.stats
            kernels[name] = {"cache_path": str(stats.cache_path),
                             "loaded": sum(stats.cache_hits.values()),
                             "compiled": sum(stats.cache_misses.values())}
    return kernels
