"""A law's posterior on a test, from emulators of its ensemble's features.

The synthetic likelihood of a quasi-static law is a thin ridge through its parameters:
a slip-weakening law's first slip moves by many standard errors when Dc changes by a
third (calibration test 4104-7: log-likelihood 24.7 at the truth, -4.9 at 1.4 times
its Dc, -158 at 0.7 times), so a Gaussian process of the log-likelihood itself needs a
guess near the needle to see it, and a few dozen guesses over the prior's box rarely
make one. The ensemble's features vary smoothly over the parameters; each is emulated
by its own process (:mod:`slipwave.fit.emulator`, Wilkinson 2014), and the likelihood
is computed from the emulated features (:meth:`SyntheticLikelihood.emulated
<slipwave.fit.likelihood.SyntheticLikelihood.emulated>`), sharp as the data make it.
The mesh's error of the features is then measured along the posterior and carried, as
:func:`search_law` says.
"""

from __future__ import annotations

import time as clock
from collections.abc import Callable, Mapping

import numpy as np
from scipy.stats import qmc

from slipwave.errors import SlipwaveError
from slipwave.fit.emulator import emulated_posterior, emulator_search
from slipwave.fit.laws import from_coordinates, prior_bounds, prior_mask, to_coordinates
from slipwave.fit.likelihood import ModelError, SyntheticLikelihood
from slipwave.fit.search import Posterior, SearchSettings, error_points, log_evidence


def _inside(law: str, box: np.ndarray, dc_per_excess: float
            ) -> Callable[[np.ndarray], np.ndarray]:
    """Which points (rows) lie in the box and the prior's support."""
    def inside(x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(x)
        return (np.all((x >= box[:, 0]) & (x <= box[:, 1]), axis=1)
                & prior_mask(law, x, dc_per_excess=dc_per_excess))
    return inside


def _fill(law: str, box: np.ndarray, count: int, rng: np.random.Generator,
          inside: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """``count`` points of a Latin hypercube of the box that lie within the prior."""
    found: list[np.ndarray] = []
    for _ in range(50):
        points = qmc.scale(qmc.LatinHypercube(d=box.shape[0], seed=rng).random(count),
                           box[:, 0], box[:, 1])
        found.extend(points[inside(points)])
        if len(found) >= count:
            break
    if not found:
        raise SlipwaveError(f"the {law} law's search box {box.tolist()} holds no point of its "
                            "prior")
    return np.array(found[:count])


BATCH = 4
"""Guesses drawn from the emulated posterior per refit of the emulators. Each refit
(thirteen processes) and the sampler's run after it cost as much as a guess's
ensemble; four draws of one posterior are as good a spread as two of two."""


def _guess_features(members: np.ndarray) -> np.ndarray:
    """A guess's features as the emulator learns them: its members' mean.

    NaN throughout where fewer than two members were followed (a failed guess).
    """
    followed = members[np.all(np.isfinite(members), axis=1)]
    if followed.shape[0] < 2:
        return np.full(members.shape[1], np.nan)
    return followed.mean(axis=0)


def search_law(law: str, simulate: Callable[[Mapping[str, float]], np.ndarray],
               likelihood: SyntheticLikelihood, box: np.ndarray, settings: SearchSettings,
               *, dc_per_excess: float = 0.0,
               model_error: Callable[[Mapping[str, float]], ModelError] | None = None
               ) -> Posterior:
    """A law's posterior on a test, by emulators of its ensemble's features.

    A Latin hypercube of the box (``settings.design`` guesses per parameter), then
    guesses drawn from the emulated posterior in batches of :data:`BATCH`, the emulators
    refitted after each from their last hyperparameters (``settings.refinements`` per
    parameter, rounded up to whole batches; :func:`~slipwave.fit.emulator.
    emulator_search`), the scatter of one member pooled over every guess's ensemble.
    With ``model_error``, the features' error from the mesh is then measured at
    :func:`~slipwave.fit.search.error_points` of that posterior (the best guess and the
    two ends of its longest axis), its root mean square over the points added to the
    measurement's error, and the posterior is sampled again. Its size only, not its
    sign: a shift measured at three points and carried along the posterior's longest
    axis moved two slip-weakening calibration tests' posteriors off their truths
    (4104-7 and -12: fs 0.539 [0.506, 0.566] for 0.611, 0.530 [0.508, 0.553] for 0.585;
    the size alone, [0.506, 0.650] and [0.513, 0.606]), for the mesh's change of a
    feature as steep as the first slip's varies across the needle more than three
    points tell. The evidence is the emulated likelihood's mean over the prior
    (:func:`~slipwave.fit.search.log_evidence`).

    Parameters
    ----------
    law
        One of :data:`~slipwave.fit.laws.LAWS`.
    simulate
        The ensemble's feature vectors at the law's parameters (by name), shape
        (members, features).
    likelihood
        The test's synthetic likelihood.
    box
        Where to search, shape (parameters, 2), in the prior's coordinates
        (:func:`~slipwave.fit.laws.to_coordinates`); clipped to the prior's bounds.
    settings
        How far to search.
    dc_per_excess
        The shortest Dc the fit's mesh resolves per unit of fs - fd, mm
        (:func:`~slipwave.fit.laws.in_prior`).
    model_error
        The features' error from the mesh at a guess (by name), or None.

    Returns
    -------
    Posterior
        Its samples and evidence, the guesses and their ensembles' own synthetic
        log-likelihoods (the mesh's error carried).

    Raises
    ------
    SlipwaveError
        If too few guesses of the design have an ensemble the solver followed.

    Examples
    --------
    Three features (fs, fd, fs - fd) read to 0.01 by four members: the posterior
    centres on the truth.

    >>> from slipwave.fit.likelihood import SyntheticLikelihood
    >>> rng = np.random.default_rng(1)
    >>> def simulate(p):
    ...     mean = np.array([p["fs"], p["fd"], p["fs"] - p["fd"]])
    ...     return mean + rng.normal(0.0, 0.01, (4, 3))
    >>> likelihood = SyntheticLikelihood(np.array([0.9, 0.6, 0.3]), np.full(3, 1e-3))
    >>> settings = SearchSettings(design=6, refinements=2, draw_temperature=3.0,
    ...                           samples=1000, seed=0)
    >>> posterior = search_law("coulomb", simulate, likelihood,
    ...                        np.array([[0.6, 1.2], [0.45, 0.75]]), settings)
    >>> summary = posterior.summary()
    >>> bool(summary["fs"]["low"] < 0.9 < summary["fs"]["high"])
    True
    """
    began = clock.perf_counter()
    bounds = prior_bounds(law)
    box = np.column_stack([np.maximum(box[:, 0], bounds[:, 0]),
                           np.minimum(box[:, 1], bounds[:, 1])])
    inside = _inside(law, box, dc_per_excess)
    runs: list[np.ndarray] = []
    carried: dict[str, np.ndarray | None] = {"error": None}

    def features(points: np.ndarray) -> np.ndarray:
        made = [simulate(from_coordinates(law, x)) for x in points]
        runs.extend(made)
        return np.array([_guess_features(members) for members in made])

    def draw(count: int, seed: np.random.Generator | int) -> np.ndarray:
        return _fill(law, box, count, np.random.default_rng(seed), inside)

    scored: dict[tuple[int, int], Callable[[np.ndarray, np.ndarray], np.ndarray]] = {}

    def loglik_of(means: np.ndarray, variances: np.ndarray) -> np.ndarray:
        # the scatter pooled over the ensembles made so far, the mesh's error once
        # measured: formed once for each, not at each of the sampler's thousands of calls
        key = (len(runs), id(carried["error"]))
        if key not in scored:
            scored[key] = likelihood.emulated(runs, carried["error"])
        return scored[key](means, variances)

    samples, points, features_made, emulator = emulator_search(
        features, box, draw, inside, loglik_of, design=settings.design,
        refinements=settings.refinements, samples=settings.samples, seed=settings.seed,
        batch=BATCH, warm=True, temperature=settings.draw_temperature)
    rng = np.random.default_rng(settings.seed)
    if model_error is not None:
        made = points[np.isfinite(features_made[:, 0])]
        best = made[int(np.argmax(emulator.loglik(made)))]
        measured = [model_error(from_coordinates(law, x))
                    for x in error_points(best, samples, box)]
        carried["error"] = np.sqrt(np.mean([m.error**2 for m in measured], axis=0))
        samples = emulated_posterior(emulator, made, inside, samples=settings.samples,
                                     seed=int(rng.integers(2**31)))
    evidence = log_evidence(emulator, box, law, inside, samples, int(rng.integers(2**31)))
    natural = np.array([list(from_coordinates(law, row).values()) for row in samples])
    values = likelihood(runs, np.ones(len(runs), dtype=bool), carried["error"])
    return Posterior(law, natural, evidence, points, values, box,
                     clock.perf_counter() - began, carried["error"])


MESH_CHECK_REACH = 1.0
"""The mesh check's box reaches this many times the posterior's 99 % range beyond each
end of it (:func:`posterior_box`): room for the finer mesh's posterior to move."""


def posterior_box(posterior: Posterior) -> np.ndarray:
    """Where the mesh check searches: the posterior's 99 % range, widened each way.

    Parameters
    ----------
    posterior
        A law's posterior.

    Returns
    -------
    numpy.ndarray
        Shape (parameters, 2), the search's coordinates, within the prior's bounds.

    Examples
    --------
    >>> from slipwave.fit.search import Posterior
    >>> samples = np.column_stack([np.linspace(0.8, 0.9, 1001), np.full(1001, 0.6)])
    >>> box = posterior_box(Posterior("coulomb", samples, 0.0, np.zeros((0, 2)),
    ...                               np.zeros(0), np.zeros((2, 2))))
    >>> box.round(4).tolist()
    [[0.7015, 0.9985], [0.6, 0.6]]
    """
    coordinates = np.array([to_coordinates(posterior.law,
                                           dict(zip(posterior.names, row, strict=True)))
                            for row in posterior.samples])
    low, high = np.quantile(coordinates, [0.005, 0.995], axis=0)
    reach = MESH_CHECK_REACH * (high - low)
    bounds = prior_bounds(posterior.law)
    return np.column_stack([np.maximum(low - reach, bounds[:, 0]),
                            np.minimum(high + reach, bounds[:, 1])])
