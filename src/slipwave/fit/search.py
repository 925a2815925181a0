"""The search's shared parts: a law's posterior and evidence, samplers, surrogates.

Each synthetic log-likelihood costs an ensemble of simulations
(:mod:`slipwave.fit.ensemble`), so an MCMC cannot call it the thousands of times it
needs; it samples a model of it instead. A quasi-static law's model is an emulator of
its features (:mod:`slipwave.fit.law_search`); the spring-slider's
(:mod:`slipwave.fit.slider`) a Gaussian process of the log-likelihood itself, its guesses
added where its upper confidence bound is highest (:func:`upper_bound_search`, BOLFI's
scheme: Gutmann and Corander 2016, JMLR 17:125). Either is sampled by emcee's
affine-invariant ensemble sampler (Foreman-Mackey et al. 2013, :func:`sample_posterior`);
a law's evidence is that posterior's normalising constant, estimated by importance
sampling (:func:`log_evidence`), and the laws are compared by it (Bayes factors: each
law's prior volume is what penalises its extra parameters). The model's own error from
the mesh is measured along the posterior (:func:`error_points`) and carried. ELFI's
BOLFI itself is not used: its Gaussian processes come from GPy, which does not install
with numpy 2.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Protocol

import emcee
import numpy as np
from scipy.special import logsumexp
from scipy.stats import multivariate_normal
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, Kernel, WhiteKernel

from slipwave.errors import SlipwaveError
from slipwave.fit.laws import LAWS, prior_bounds, prior_mask


@dataclass(frozen=True)
class SearchSettings:
    """How far the search goes (the fit section of the configuration).

    Attributes
    ----------
    design
        Guesses of the Latin hypercube, per parameter
        (:func:`~slipwave.fit.law_search.search_law`).
    refinements
        Guesses drawn from the emulated posterior after it, per parameter.
    draw_temperature
        Their draws' posterior tempered by it
        (:func:`~slipwave.fit.emulator.tempered`).
    samples
        Posterior samples kept.
    seed
        The search's random seed.

    """

    design: int
    refinements: int
    draw_temperature: float
    samples: int
    seed: int


@dataclass
class Posterior:
    """A law's posterior on a test.

    Attributes
    ----------
    law
        Its name (:data:`~slipwave.fit.laws.LAWS`).
    samples
        Posterior samples, shape (samples, parameters), in the parameters' own units.
    log_evidence
        The log of the law's marginal likelihood (up to the same constant for every
        law of a test).
    points, logliks
        Where the synthetic log-likelihood was evaluated (the search's coordinates) and
        its values.
    box
        The search box, shape (parameters, 2), in the search's coordinates.
    seconds
        Time the search took.
    model_error
        The features' error from the mesh the likelihood carried
        (:func:`~slipwave.fit.ensemble.mesh_error`), or None.

    """

    law: str
    samples: np.ndarray
    log_evidence: float
    points: np.ndarray
    logliks: np.ndarray
    box: np.ndarray
    seconds: float = 0.0
    model_error: np.ndarray | None = None

    @property
    def names(self) -> tuple[str, ...]:
        """The law's parameters.

        Returns
        -------
        tuple of str
            In :data:`~slipwave.fit.laws.LAWS`' order.

        """
        return LAWS[self.law]

    def summary(self) -> dict[str, dict[str, float]]:
        """Each parameter's posterior median and central 95 % interval.

        Returns
        -------
        dict
            Name -> ``value``, ``low``, ``high``.

        """
        low, median, high = np.quantile(self.samples, [0.025, 0.5, 0.975], axis=0)
        return {name: {"value": float(m), "low": float(a), "high": float(b)}
                for name, a, m, b in zip(self.names, low, median, high, strict=True)}


@dataclass
class Surrogate:
    """A Gaussian process of the log-likelihood's distance from its best, in log.

    BOLFI's transform (Gutmann and Corander 2016 model a log discrepancy): with m the
    best log-likelihood evaluated, the process models log(m + 1 - loglik), which is 0 at
    the best guess and grows by a few units where the log-likelihood falls by
    thousands, a surface a stationary process can follow; the log-likelihood is read
    back as m + 1 - exp(prediction).

    Attributes
    ----------
    process
        The fitted process (inputs scaled to the box, :func:`scaled`).
    top
        m.
    box
        The box the inputs were scaled by.

    """

    process: GaussianProcessRegressor
    top: float
    box: np.ndarray

    def loglik(self, points: np.ndarray) -> np.ndarray:
        """The surrogate's log-likelihood at points (the search's coordinates).

        Parameters
        ----------
        points
            Shape (n, parameters).

        Returns
        -------
        numpy.ndarray
            One per point.

        """
        return self.top + 1.0 - np.exp(self.process.predict(scaled(points, self.box)))

    def _predicted(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The process's mean and standard deviation of the log distance at points."""
        return self.process.predict(scaled(points, self.box), return_std=True)

    def upper(self, points: np.ndarray, exploration: float) -> np.ndarray:
        """The log-likelihood's upper confidence bound (the distance's lower one).

        Parameters
        ----------
        points
            Shape (n, parameters).
        exploration
            Standard deviations of the process below its mean.

        Returns
        -------
        numpy.ndarray
            One per point.

        """
        mean, sd = self._predicted(points)
        return self.top + 1.0 - np.exp(mean - exploration * sd)


def surrogate(points: np.ndarray, logliks: np.ndarray, box: np.ndarray, seed: int
              ) -> Surrogate:
    """A Gaussian process fitted to the log-likelihoods (:class:`Surrogate`).

    Parameters
    ----------
    points
        Shape (n, parameters), the search's coordinates.
    logliks
        The finite log-likelihoods at ``points``.
    box
        The search box.
    seed
        The optimiser's restarts' seed.

    Returns
    -------
    Surrogate
        Fitted on points scaled to [0, 1] (:func:`scaled`).

    """
    top = float(logliks.max())
    return Surrogate(gaussian_process(scaled(points, box), np.log(top + 1.0 - logliks),
                                      seed), top, box)


def gaussian_process(inputs: np.ndarray, outputs: np.ndarray, seed: int, *,
                     noise: tuple[float, tuple[float, float]] = (1e-2, (1e-6, 1e1)),
                     start: Kernel | None = None) -> GaussianProcessRegressor:
    """A Gaussian process fitted to outputs: a constant times an anisotropic RBF, plus noise.

    Parameters
    ----------
    inputs
        Shape (n, parameters), in the unit cube (:func:`scaled`).
    outputs
        Shape (n,), finite.
    seed
        The optimiser's restarts' seed.
    noise
        The white noise's first value and its bounds, in the outputs' normalised variance.
    start
        A kernel of this form fitted before (to fewer of the same outputs): its
        hyperparameters are the optimiser's one start, instead of the defaults and
        :data:`RESTARTS` random ones.

    Returns
    -------
    sklearn.gaussian_process.GaussianProcessRegressor
        Fitted (its outputs normalised).
    """
    kernel = start if start is not None else (
        ConstantKernel(1.0, (1e-3, 1e3)) * RBF(np.full(inputs.shape[1], 0.3), (1e-2, 1e1))
        + WhiteKernel(*noise))
    process = GaussianProcessRegressor(kernel, normalize_y=True,
                                       n_restarts_optimizer=0 if start is not None else RESTARTS,
                                       random_state=seed)
    with warnings.catch_warnings():  # a length scale at its bound is an answer, not a fault
        warnings.simplefilter("ignore", ConvergenceWarning)
        process.fit(inputs, outputs)
    return process


RESTARTS = 2
"""Random starts of a process's optimiser besides its default hyperparameters."""


MIN_STEPS = 300
"""Steps of each emcee walker at least; the first half is discarded (burn-in)."""


def scaled(points: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Points in the box's unit cube.

    Parameters
    ----------
    points
        Shape (n, parameters).
    box
        Shape (parameters, 2).

    Returns
    -------
    numpy.ndarray
        (points - low) / (high - low).

    """
    return (points - box[:, 0]) / (box[:, 1] - box[:, 0])


START_TRIES = 64
"""Jittered copies of the best guesses drawn per walker to start emcee from, and uniform
draws of the box after them (a best guess may lie just outside the box or the prior)."""


def _walkers_start(starts: np.ndarray, box: np.ndarray,
                   inside: Callable[[np.ndarray], np.ndarray], walkers: int,
                   rng: np.random.Generator) -> np.ndarray:
    """Walkers' first positions: around the best guesses (clipped to the box), in the prior.

    Where too few of the jittered guesses lie in the box and the prior (a best guess on
    the prior's edge, or one of the guesses near the box kept from outside it), the rest
    are drawn uniformly over the box.
    """
    width = 0.01 * (box[:, 1] - box[:, 0])
    centres = np.clip(starts, box[:, 0], box[:, 1])
    tries = (centres[np.arange(START_TRIES * walkers) % len(centres)]
             + rng.normal(0.0, width, (START_TRIES * walkers, box.shape[0])))
    found = tries[inside(tries)]
    if found.shape[0] < walkers:
        uniform = rng.uniform(box[:, 0], box[:, 1], (START_TRIES * walkers, box.shape[0]))
        found = np.vstack([found, uniform[inside(uniform)]])
    if found.shape[0] < walkers:
        raise SlipwaveError(f"the search box {box.tolist()} holds too little of the prior to "
                            "start the posterior's sampler")
    return found[:walkers]


class LogLikelihood(Protocol):
    """What :func:`sample_posterior` samples: a log-likelihood at points."""

    def loglik(self, points: np.ndarray) -> np.ndarray:
        """The log-likelihood at points.

        Parameters
        ----------
        points
            Shape (n, parameters).

        Returns
        -------
        numpy.ndarray
            One per point.
        """


def sample_posterior(process: LogLikelihood, box: np.ndarray,
                     inside: Callable[[np.ndarray], np.ndarray], starts: np.ndarray, *,
                     samples: int, seed: int) -> np.ndarray:
    """Samples of prior x exp(surrogate mean) over the box (emcee).

    Parameters
    ----------
    process
        The surrogate (:func:`surrogate`) or any model of the log-likelihood.
    box
        The search box.
    inside
        Whether a point lies in the box and the prior.
    starts
        The best points evaluated: the walkers start around them.
    samples
        Samples kept.
    seed
        The sampler's seed.

    Returns
    -------
    numpy.ndarray
        Shape (samples, parameters), the search's coordinates.

    """
    p = box.shape[0]
    walkers = max(4 * p, 16)

    def log_probability(x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(x)
        keep = inside(x)
        out = np.full(x.shape[0], -np.inf)
        if keep.any():
            out[keep] = process.loglik(x[keep])
        return out

    rng = np.random.default_rng(seed)
    sampler = emcee.EnsembleSampler(walkers, p, log_probability, vectorize=True)
    sampler.random_state = np.random.RandomState(int(rng.integers(2**31))).get_state()
    steps = max(MIN_STEPS, 4 * samples // walkers)
    sampler.run_mcmc(_walkers_start(starts, box, inside, walkers, rng), steps, progress=False)
    chain = sampler.get_chain(discard=steps // 2, flat=True)
    return chain[rng.choice(chain.shape[0], size=min(samples, chain.shape[0]), replace=False)]



def central_intervals(values: Mapping[str, np.ndarray], probability: float = 0.95
                      ) -> dict[str, tuple[float, float, float]]:
    """Each quantity's posterior median and central interval.

    Parameters
    ----------
    values
        Posterior samples of each quantity, by name.
    probability
        The interval's probability.

    Returns
    -------
    dict
        Name -> (median, low, high).

    Examples
    --------
    >>> [round(value, 6) for value in central_intervals({"x": np.arange(101.0)}, 0.9)["x"]]
    [50.0, 5.0, 95.0]
    """
    tail = 50.0 * (1.0 - probability)
    out = {}
    for name, v in values.items():
        middle, low, high = np.percentile(v, [50.0, tail, 100.0 - tail])
        out[name] = (float(middle), float(low), float(high))
    return out


ACQUISITION_BATCH = 2
"""Guesses added per refit of the surrogate in :func:`upper_bound_search` (the highest
upper bounds): the same whatever the number of processes, so that a fit does not depend
on the cores it ran on."""

CANDIDATES = 4000
"""Prior draws among which :func:`upper_bound_search` picks each batch's guesses."""

BEST_STARTS = 4
"""The best guesses the posterior's walkers start around (:func:`upper_bound_search`)."""


def upper_bound_search(evaluate: Callable[[np.ndarray], np.ndarray], box: np.ndarray,
                       draw: Callable[[int, np.random.Generator | int], np.ndarray],
                       inside: Callable[[np.ndarray], np.ndarray], *, design: int,
                       acquisitions: int, exploration: float, samples: int, seed: int,
                       start: np.ndarray | None = None,
                       progress: Callable[[str], None] | None = None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A posterior from a surrogate of a likelihood, its guesses chosen by upper bound.

    A Latin hypercube of the prior (``design`` points per coordinate), then batches of
    :data:`ACQUISITION_BATCH` guesses where the surrogate's upper confidence bound is
    highest among :data:`CANDIDATES` prior draws (``acquisitions`` per coordinate), then
    emcee on prior x exp(surrogate mean) (:func:`sample_posterior`): BOLFI's scheme
    without its zooming stages, for a likelihood cheap enough to search the prior whole.

    Parameters
    ----------
    evaluate
        The log-likelihoods at guesses, shape (n,) for (n, coordinates); -inf or NaN
        where the simulation failed.
    box
        The prior's box, one row (low, high) per coordinate.
    draw
        ``draw(count, rng)``: ``count`` points of the prior (a Latin hypercube of the box
        restricted to the prior), ``rng`` a seed or a generator.
    inside
        Whether points lie in the prior.
    design, acquisitions
        Guesses of the design and of the acquisitions, per coordinate.
    exploration
        The upper bound's multiple of the surrogate's standard deviation.
    samples
        Posterior samples kept.
    seed
        The search's seed.
    start
        Guesses evaluated with the design (those outside the prior are left out).
    progress
        Called with a line after each round of guesses.

    Returns
    -------
    tuple of numpy.ndarray
        The posterior samples, the guesses and their log-likelihoods.

    Raises
    ------
    SlipwaveError
        If fewer than two guesses have a finite likelihood.

    Examples
    --------
    A Gaussian likelihood of mean 0.3 and standard deviation 0.05 over [0, 1]:

    >>> from scipy.stats import qmc
    >>> box = np.array([[0.0, 1.0]])
    >>> def draw(count, rng):
    ...     return qmc.LatinHypercube(d=1, seed=rng).random(count)
    >>> def inside(x):
    ...     return np.all((x >= 0.0) & (x <= 1.0), axis=1)
    >>> samples, points, _ = upper_bound_search(
    ...     lambda x: -0.5 * ((x[:, 0] - 0.3) / 0.05) ** 2, box, draw, inside, design=8,
    ...     acquisitions=6, exploration=2.0, samples=2000, seed=1)
    >>> round(float(samples.mean()), 2), round(float(samples.std()), 2)
    (0.3, 0.05)
    """
    say = progress or (lambda _: None)
    rng = np.random.default_rng(seed)
    dimensions = box.shape[0]
    points = draw(design * dimensions, seed)
    if start is not None:
        start = np.atleast_2d(np.asarray(start, dtype=float))
        points = np.vstack([start[inside(start)], points])
    logliks = np.asarray(evaluate(points), dtype=float)
    say(f"design: {len(points)} guesses, best log-likelihood {np.nanmax(logliks):.1f}")

    def fitted(refit: int) -> Surrogate:
        finite = np.isfinite(logliks)
        if finite.sum() < 2:
            raise SlipwaveError(f"{finite.sum()} of {len(points)} guesses have a likelihood "
                                "(the simulations failed): nothing to search")
        return surrogate(points[finite], logliks[finite], box, seed + refit)

    for round_ in range(0, acquisitions * dimensions, ACQUISITION_BATCH):
        candidates = draw(CANDIDATES, rng)
        upper = fitted(round_).upper(candidates, exploration)
        chosen = candidates[np.argsort(upper)[-ACQUISITION_BATCH:]]
        points = np.vstack([points, chosen])
        logliks = np.append(logliks, np.asarray(evaluate(chosen), dtype=float))
        say(f"acquisitions: {len(points)} guesses, best log-likelihood "
            f"{np.nanmax(logliks):.1f}")

    def best() -> np.ndarray:
        finite = np.isfinite(logliks)
        return points[finite][np.argsort(logliks[finite])[-BEST_STARTS:]]

    drawn = sample_posterior(fitted(0), box, inside, best(), samples=samples, seed=seed)
    return drawn, points, logliks


def log_evidence(process: LogLikelihood, box: np.ndarray, law: str,
                 inside: Callable[[np.ndarray], np.ndarray], samples: np.ndarray, seed: int, *,
                 draws: int = 4000) -> float:
    """The log of the law's evidence: the prior's mean of exp(surrogate mean).

    By importance sampling from a normal fitted to the posterior samples, its
    covariance doubled (a proposal wider than the posterior); the prior is uniform over
    its support, whose volume is measured by drawing its bounds' box.

    Parameters
    ----------
    process, box, inside
        As in :func:`sample_posterior`.
    law
        The law (its prior's bounds).
    samples
        Posterior samples (the search's coordinates).
    seed
        The draws' seed.
    draws
        Importance draws.

    Returns
    -------
    float
        log Z.

    """
    rng = np.random.default_rng(seed)
    bounds = prior_bounds(law)
    uniform = rng.uniform(bounds[:, 0], bounds[:, 1], (draws, bounds.shape[0]))
    support = float(np.mean(prior_mask(law, uniform)))
    log_volume = float(np.sum(np.log(bounds[:, 1] - bounds[:, 0]))) + np.log(max(support,
                                                                                1e-12))
    covariance = 2.0 * np.atleast_2d(np.cov(samples.T)) + 1e-12 * np.eye(samples.shape[1])
    proposal = multivariate_normal(samples.mean(axis=0), covariance, seed=rng)
    x = np.atleast_2d(proposal.rvs(draws))
    keep = inside(x)
    if not keep.any():
        return float("-inf")
    log_weights = np.full(draws, -np.inf)
    log_weights[keep] = process.loglik(x[keep]) - proposal.logpdf(x[keep])
    return float(logsumexp(log_weights) - np.log(draws) - log_volume)


ERROR_QUANTILES = (0.05, 0.95)
"""Where along the posterior's longest axis the model's error is measured besides the
best guess: these quantiles of the posterior's draws."""


def _longest_axis(spread: np.ndarray, box: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The draws' centre and first principal axis in the box's unit cube.

    The axis has no sign of its own (an SVD's): its largest component is made positive.
    """
    unit = scaled(spread, box)
    centre = unit.mean(axis=0)
    axis = np.linalg.svd(unit - centre, full_matrices=False)[2][0]
    return centre, axis if axis[np.argmax(np.abs(axis))] > 0 else -axis


def error_points(best: np.ndarray, spread: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Where to measure the model's own error: the best guess and the posterior's reach.

    The error from the mesh changes along the posterior: on a slip-weakening law's
    fs-Dc ridge, measured at its best guess alone it missed a 4 % change of the
    recurrence at the truth (calibration test 3602-12), and the posterior excluded the
    truth. Measured also at the posterior's draws nearest the
    :data:`ERROR_QUANTILES` of its longest axis (the first principal component, in the
    box's unit cube), the error's root mean square over the points is the discrepancy
    expected where the truth may lie, for three ensembles on the finer mesh.

    Parameters
    ----------
    best
        The best guess, the search's coordinates.
    spread
        Draws from the posterior, shape (draws, parameters).
    box
        The search box.

    Returns
    -------
    numpy.ndarray
        The best guess, then the two draws (each point once).

    Examples
    --------
    Draws along a diagonal: the points lie at its two ends.

    >>> spread = np.column_stack([np.linspace(0.0, 1.0, 101), np.linspace(2.0, 1.0, 101)])
    >>> box = np.array([[0.0, 1.0], [1.0, 2.0]])
    >>> error_points(np.array([0.5, 1.5]), spread, box).round(6).tolist()
    [[0.5, 1.5], [0.05, 1.95], [0.95, 1.05]]
    """
    centre, axis = _longest_axis(spread, box)
    along = (scaled(spread, box) - centre) @ axis
    chosen = [best]
    for level in np.quantile(along, ERROR_QUANTILES):
        point = spread[int(np.argmin(np.abs(along - level)))]
        if not any(np.array_equal(point, kept) for kept in chosen):
            chosen.append(point)
    return np.array(chosen)
