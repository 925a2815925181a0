"""The friction laws a test is fitted with: parameters, priors and the solver's law.

Each law's parameters have a prior, uniform over a region stated with its physical
reason (:data:`PRIORS`), in the coordinates the search and the sampler move in
(:func:`to_coordinates`): the coefficients themselves, and Dc by its decimal log (a
length whose order of magnitude is what is unknown). fs exceeds fd in every law (a
test without it does not stick-slip); a run-in's static coefficient goes from fs to
fs_final over its first gross slips, rising (the contact ages or wears in) or falling
(it is worn smooth or its surface film is wiped off), whichever the data say.

Examples
--------
>>> law_of("slip-weakening", {"fs": 1.0, "fd": 0.6, "dc": 0.2})
SlipWeakening(fs=1.0, fd=0.6, fs_final=None, runin_slips=0, fs_peak=None, dc=0.2)
>>> in_prior("coulomb", {"fs": 0.9, "fd": 0.6}), in_prior("coulomb", {"fs": 0.6, "fd": 0.9})
(True, False)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from slipwave.errors import SlipwaveError
from slipwave.solver import Coulomb, SlipWeakening

LAWS: dict[str, tuple[str, ...]] = {
    "coulomb": ("fs", "fd"),
    "run-in": ("fs", "fd", "fs_final", "runin_slips"),
    "slip-weakening": ("fs", "fd", "dc"),
}
"""The friction laws a test is fitted with, and their parameters."""

UNITS = {"fs": "1", "fd": "1", "fs_final": "1", "runin_slips": "gross slips", "dc": "mm"}
"""Each parameter's unit."""


@dataclass(frozen=True)
class Prior:
    """A parameter's prior: uniform between two bounds, in its search coordinate.

    Attributes
    ----------
    low, high
        The bounds, in the parameter's own unit (Dc: mm).
    log
        Uniform in the decimal log (a scale whose order is unknown).
    reason
        Why these bounds.

    """

    low: float
    high: float
    log: bool
    reason: str


PRIORS: dict[str, Prior] = {
    "fd": Prior(0.3, 1.0, False,
                "the dynamic coefficient of a soft polyurethane sliding dry on a smooth "
                "rigid flat: several tenths, up to 1 (above, this bench's slab rolls its "
                "edge over and the quasi-static solver stops converging)"),
    "fs": Prior(0.35, 1.5, False,
                "fd plus the static excess (STATIC_EXCESS): stick-slip needs fs above fd"),
    "fs_final": Prior(0.35, 1.8, False,
                      "fd plus a static excess up to RUNIN_EXCESS, above or below fs: the "
                      "contact may strengthen (ageing, wear-in) or weaken (a film wiped off)"),
    "runin_slips": Prior(1.0, 10.0, False,
                         "the run-in lasts 1 to 10 gross slips: longer, a 280 s test shows "
                         "too few slips after it to tell fs_final"),
    "dc": Prior(0.005, 0.3, True,
                "from a few microns (the asperity contacts' size) to 0.3 mm (its process "
                "zone then spans half the 80 mm contact at fs - fd 0.3: longer, the whole "
                "contact weakens at once, no front), and no shorter than the fit's mesh "
                "resolves (ZONE_ELEMENTS)"),
}
"""Each parameter's prior (uniform), with its physical reason."""

STATIC_EXCESS = (0.05, 0.5)
"""fs - fd: at least 0.05 (below, a gross slip's drop, some (fs - fd) N, is a few newtons
and the cycle's partial slips hide in the card's noise), at most 0.5 (more, a slab's
first gross slip releases most of T)."""
RUNIN_EXCESS = (0.05, 0.8)
"""fs_final - fd: as :data:`STATIC_EXCESS`, a run-in reaching further once the first gross
slips have worn the contact in (the default campaign's hl050 ends 0.7 above fd)."""

ZONE_ELEMENTS = 3.0
"""Elements a slip-weakening law's process zone spans at least, so that the law's
features do not depend on the mesh (Day et al. 2005 ask 3 or more of a rupture
simulation's cohesive zone; the mesh study, docs "Mesh convergence", found Dc 0.02 mm
converged from 2.9 elements across its zone, not at 1.4). A shorter Dc cannot be told
from it on the fit's mesh: the prior stops there."""


def law_of(name: str, params: Mapping[str, float]) -> Coulomb:
    """The solver's friction law of a fitted law's name and parameters.

    Parameters
    ----------
    name
        One of :data:`LAWS`.
    params
        Its parameters.

    Returns
    -------
    Coulomb
        :class:`~slipwave.solver.Coulomb` (with run-in) or
        :class:`~slipwave.solver.SlipWeakening`.

    Raises
    ------
    SlipwaveError
        For a law not in :data:`LAWS`.

    """
    if name == "coulomb":
        return Coulomb(fs=params["fs"], fd=params["fd"])
    if name == "run-in":
        return Coulomb(fs=params["fs"], fd=params["fd"], fs_final=params["fs_final"],
                       runin_slips=params["runin_slips"])
    if name == "slip-weakening":
        return SlipWeakening(fs=params["fs"], fd=params["fd"], dc=params["dc"])
    raise SlipwaveError(f"unknown friction law {name!r}; known: {', '.join(LAWS)}")


def in_prior(law: str, params: Mapping[str, float], *, dc_per_excess: float = 0.0) -> bool:
    """Whether a law's parameters lie where its prior is not zero.

    Parameters
    ----------
    law
        One of :data:`LAWS`.
    params
        Its parameters by name.
    dc_per_excess
        The shortest Dc the fit's mesh resolves per unit of fs - fd, mm
        (:data:`ZONE_ELEMENTS`).

    Returns
    -------
    bool
        Each within its bounds, fs - fd and fs_final - fd within their excesses, Dc at
        least ``dc_per_excess`` (fs - fd).

    """
    point = to_coordinates(law, params)[None, :]
    return bool(prior_mask(law, point, dc_per_excess=dc_per_excess)[0])


def prior_mask(law: str, coordinates: np.ndarray, *, dc_per_excess: float = 0.0
               ) -> np.ndarray:
    """Which points, in the prior's coordinates, lie where the prior is not zero.

    Parameters
    ----------
    law
        One of :data:`LAWS`.
    coordinates
        Shape (points, parameters) (:func:`to_coordinates`).
    dc_per_excess
        As in :func:`in_prior`.

    Returns
    -------
    numpy.ndarray
        One bool per point.

    """
    names = LAWS[law]
    bounds = prior_bounds(law)
    x = np.atleast_2d(coordinates)
    inside = np.all((x >= bounds[:, 0]) & (x <= bounds[:, 1]), axis=1)
    value = {name: (10.0 ** x[:, k] if PRIORS[name].log else x[:, k])
             for k, name in enumerate(names)}
    excess = value["fs"] - value["fd"]
    inside &= (excess >= STATIC_EXCESS[0]) & (excess <= STATIC_EXCESS[1])
    if law == "run-in":
        final = value["fs_final"] - value["fd"]
        inside &= (final >= RUNIN_EXCESS[0]) & (final <= RUNIN_EXCESS[1])
    if law == "slip-weakening":
        inside &= value["dc"] >= dc_per_excess * excess
    return inside


def to_coordinates(law: str, params: Mapping[str, float]) -> np.ndarray:
    """A law's parameters in the coordinates its prior is uniform in.

    Parameters
    ----------
    law
        One of :data:`LAWS`.
    params
        Its parameters by name.

    Returns
    -------
    numpy.ndarray
        One coordinate per parameter, in :data:`LAWS`' order (Dc: log10 of mm).

    """
    return np.array([np.log10(params[name]) if PRIORS[name].log else float(params[name])
                     for name in LAWS[law]])


def from_coordinates(law: str, coordinates: np.ndarray) -> dict[str, float]:
    """A law's parameters from its prior's coordinates (:func:`to_coordinates`).

    Parameters
    ----------
    law
        One of :data:`LAWS`.
    coordinates
        One per parameter, in :data:`LAWS`' order.

    Returns
    -------
    dict
        The parameters by name.

    Examples
    --------
    >>> from_coordinates("slip-weakening", np.array([0.9, 0.6, -1.0]))
    {'fs': 0.9, 'fd': 0.6, 'dc': 0.1}
    """
    return {name: float(10.0 ** value if PRIORS[name].log else value)
            for name, value in zip(LAWS[law], coordinates, strict=True)}


def prior_bounds(law: str) -> np.ndarray:
    """The bounds of each coordinate's prior.

    Parameters
    ----------
    law
        One of :data:`LAWS`.

    Returns
    -------
    numpy.ndarray
        Shape (parameters, 2): low and high, in :func:`to_coordinates`' coordinates.

    """
    return np.array([[np.log10(PRIORS[name].low), np.log10(PRIORS[name].high)]
                     if PRIORS[name].log else [PRIORS[name].low, PRIORS[name].high]
                     for name in LAWS[law]])


def draw_prior(law: str, rng: np.random.Generator, *, dc_per_excess: float = 0.0,
               tries: int = 10_000) -> dict[str, float]:
    """One law drawn from its prior (by rejection from the bounds' box).

    Parameters
    ----------
    law
        One of :data:`LAWS`.
    rng
        The random stream.
    dc_per_excess
        As in :func:`in_prior`.
    tries
        Draws at most.

    Returns
    -------
    dict
        The parameters by name.

    Raises
    ------
    SlipwaveError
        If no draw of ``tries`` falls in the prior.

    Examples
    --------
    >>> params = draw_prior("run-in", np.random.default_rng(1))
    >>> in_prior("run-in", params)
    True
    """
    bounds = prior_bounds(law)
    for _ in range(tries):
        params = from_coordinates(law, rng.uniform(bounds[:, 0], bounds[:, 1]))
        if in_prior(law, params, dc_per_excess=dc_per_excess):
            return params
    raise SlipwaveError(f"no {law} law drawn in {tries} tries falls in its prior")
