"""A posterior from Gaussian processes of a simulator's features, for a thin likelihood.

Where the simulator is nearly deterministic and its features nearly exact (a quasi-dynamic
run's cycle repeats to 10⁻⁴ in T/|N| from window to window; a slip-weakening slab's first
slip moves by tens of its standard errors when Dc changes by a third), the likelihood is
a thin ridge or needle through the parameters, each feature known to its floor.
A process of the log-likelihood (:class:`slipwave.fit.search.Surrogate`) must then find a
needle with a few dozen guesses. The features themselves vary smoothly over the prior, so
here each is emulated by its own Gaussian process (Wilkinson 2014, "Accelerating ABC
methods using Gaussian processes", AISTATS; the emulation of summaries of Jabot et al.
2014), and the likelihood is computed from the emulated features with the emulator's
own variance added to the features' (what it has not seen widens the posterior rather
than hiding it). The guesses after a Latin hypercube are drawn from that posterior
(emcee), tempered where the emulator's errors would otherwise cut a ridge short
(:func:`tempered`), each batch refitting the emulator where the posterior is: the ridge
is found by the emulator's likelihood, sharp as the data make it, not by the guesses.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.linalg import solve_triangular
from sklearn.gaussian_process import GaussianProcessRegressor

from slipwave.errors import SlipwaveError
from slipwave.fit.search import (
    ACQUISITION_BATCH,
    BEST_STARTS,
    gaussian_process,
    sample_posterior,
    scaled,
)


@dataclass(frozen=True)
class FeatureEmulator:
    """Gaussian processes of a simulator's features over a box, one per feature.

    Attributes
    ----------
    processes
        The fitted processes (inputs scaled to the box's unit cube).
    box
        The box, shape (parameters, 2).
    loglik_of
        The log-likelihood given the features' predicted means and variances, each of
        shape (n, features).
    stacked
        The processes stacked for their predictions (:func:`stack_processes`; formed
        with the emulator, once a batch).

    """

    processes: tuple[GaussianProcessRegressor, ...]
    box: np.ndarray
    loglik_of: Callable[[np.ndarray, np.ndarray], np.ndarray]
    stacked: StackedProcesses = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "stacked", stack_processes(self.processes))

    def predict(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The features' means and variances at points.

        Parameters
        ----------
        points
            Shape (n, parameters).

        Returns
        -------
        tuple of numpy.ndarray
            Each of shape (n, features).
        """
        return self.stacked.predict(scaled(np.atleast_2d(points), self.box))

    def loglik(self, points: np.ndarray) -> np.ndarray:
        """The log-likelihood of the emulated features at points.

        Parameters
        ----------
        points
            Shape (n, parameters).

        Returns
        -------
        numpy.ndarray
            One per point.
        """
        return self.loglik_of(*self.predict(points))


@dataclass(frozen=True)
class StackedProcesses:
    """Fitted processes' predictions at once, as array operations over all of them.

    Each process is a constant times an anisotropic RBF plus white noise
    (:func:`~slipwave.fit.search.gaussian_process`), fitted to one output with
    ``normalize_y``. One process at a time, a prediction's cost is mostly scikit-learn's
    checks and kernel objects' calls, whatever the points, and emcee's walkers ask
    thirteen processes about eight points at a time, tens of thousands of times a fit
    (the times are in the CHANGELOG). Stacked, the processes' runs padded to the most
    any learnt from (a padded run weighs nothing: its weight in ``alpha`` and its column
    of ``whitening`` are zero), one call predicts them all.

    Attributes
    ----------
    train
        Shape (processes, runs, parameters): each process's runs over its length scales.
    train_norms
        Shape (processes, runs): their squared norms.
    length_scales
        Shape (processes, parameters).
    alpha
        Shape (processes, runs): each process's weights of its runs' covariances.
    whitening
        Shape (processes, runs, runs): the inverse of each process's Cholesky factor.
    constant, noise
        Shape (processes,): the kernel's constant and white-noise level.
    output_scale, output_mean
        Shape (processes,): each output's normalisation.

    """

    train: np.ndarray
    train_norms: np.ndarray
    length_scales: np.ndarray
    alpha: np.ndarray
    whitening: np.ndarray
    constant: np.ndarray
    noise: np.ndarray
    output_scale: np.ndarray
    output_mean: np.ndarray

    def predict(self, unit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every process's mean and variance at points of the unit cube.

        Parameters
        ----------
        unit
            Shape (n, parameters).

        Returns
        -------
        tuple of numpy.ndarray
            Means and variances, each of shape (n, processes).
        """
        z = unit[None, :, :] / self.length_scales[:, None, :]
        distances = ((z**2).sum(axis=2)[:, :, None] + self.train_norms[:, None, :]
                     - 2.0 * z @ self.train.transpose(0, 2, 1))
        np.maximum(distances, 0.0, out=distances)
        covariances = self.constant[:, None, None] * np.exp(-0.5 * distances)
        means = (covariances @ self.alpha[:, :, None])[:, :, 0]
        v = self.whitening @ covariances.transpose(0, 2, 1)
        variances = (self.constant + self.noise)[:, None] - (v**2).sum(axis=1)
        np.maximum(variances, 0.0, out=variances)
        means = self.output_scale[:, None] * means + self.output_mean[:, None]
        return means.T, (variances * self.output_scale[:, None] ** 2).T


def stack_processes(processes: tuple[GaussianProcessRegressor, ...]) -> StackedProcesses:
    """Fitted processes as a :class:`StackedProcesses`.

    Parameters
    ----------
    processes
        Each fitted by :func:`~slipwave.fit.search.gaussian_process`.

    Returns
    -------
    StackedProcesses
        Their predictions as one.

    Examples
    --------
    >>> from slipwave.fit.search import gaussian_process
    >>> rng = np.random.default_rng(0)
    >>> inputs = rng.random((12, 2))
    >>> process = gaussian_process(inputs, np.sin(4.0 * inputs[:, 0]), seed=0)
    >>> mean, variance = stack_processes((process,)).predict(inputs[:3])
    >>> np.allclose(mean[:, 0], process.predict(inputs[:3]))
    True
    """
    count = max(process.X_train_.shape[0] for process in processes)
    dimensions = processes[0].X_train_.shape[1]
    size = len(processes)
    train = np.zeros((size, count, dimensions))
    alpha = np.zeros((size, count))
    whitening = np.zeros((size, count, count))
    length_scales = np.empty((size, dimensions))
    constant, noise = np.empty(size), np.empty(size)
    output_scale, output_mean = np.empty(size), np.empty(size)
    for k, process in enumerate(processes):
        scaled_rbf, white = process.kernel_.k1, process.kernel_.k2
        runs = process.X_train_.shape[0]
        length_scales[k] = scaled_rbf.k2.length_scale
        train[k, :runs] = process.X_train_ / length_scales[k]
        alpha[k, :runs] = np.ravel(process.alpha_)
        whitening[k, :runs, :runs] = solve_triangular(process.L_, np.eye(runs), lower=True,
                                                      check_finite=False)
        constant[k] = scaled_rbf.k1.constant_value
        noise[k] = white.noise_level
        output_scale[k] = np.ravel(process._y_train_std)[0]
        output_mean[k] = np.ravel(process._y_train_mean)[0]
    return StackedProcesses(train, (train**2).sum(axis=2), length_scales, alpha, whitening,
                            constant, noise, output_scale, output_mean)


MIN_VALUES = 3
"""Runs with a value of a feature that its process learns from, at least; with fewer, the
runs lacking it take the feature's ``absent`` value."""


def emulate(points: np.ndarray, features: np.ndarray, box: np.ndarray,
            loglik_of: Callable[[np.ndarray, np.ndarray], np.ndarray], seed: int,
            absent: np.ndarray | None = None, previous: FeatureEmulator | None = None
            ) -> FeatureEmulator:
    """Fit one Gaussian process per feature (:func:`~slipwave.fit.search.gaussian_process`).

    Parameters
    ----------
    points
        Shape (n, parameters).
    features
        Shape (n, features); each feature's process learns from its finite values.
    box
        The box the inputs are scaled by.
    loglik_of
        As :attr:`FeatureEmulator.loglik_of`.
    seed
        The optimiser's restarts' seed.
    absent
        One per feature: the value a run lacking the feature takes where fewer than
        :data:`MIN_VALUES` runs have it (NaN, the default: the feature is never lacked).
    previous
        The emulator fitted to fewer of these runs: each process's optimiser starts once,
        from its hyperparameters (a warm start), rather than from the defaults and
        random restarts.

    Returns
    -------
    FeatureEmulator
        The processes.

    Raises
    ------
    SlipwaveError
        If a feature without an ``absent`` value has fewer than :data:`MIN_VALUES` values.
    """
    lacking = np.full(features.shape[1], np.nan) if absent is None else absent
    processes = []
    for index, column in enumerate(features.T):
        if np.isfinite(column).sum() < MIN_VALUES:
            column = np.where(np.isfinite(column), column, lacking[index])
        known = np.isfinite(column)
        if known.sum() < MIN_VALUES:
            raise SlipwaveError(f"feature {index} has {known.sum()} values of "
                                f"{len(column)} runs: too few to emulate it")
        # a nearly deterministic simulator: its noise may be far below the likelihood's
        start = None if previous is None else previous.processes[index].kernel_
        processes.append(gaussian_process(scaled(points[known], box), column[known], seed,
                                          noise=(1e-3, (1e-8, 1e0)), start=start))
    return FeatureEmulator(tuple(processes), box, loglik_of)


def emulated_posterior(emulator: FeatureEmulator, points: np.ndarray,
                       inside: Callable[[np.ndarray], np.ndarray], *, samples: int,
                       seed: int) -> np.ndarray:
    """Samples of prior x exp(emulated log-likelihood) over the emulator's box (emcee).

    Parameters
    ----------
    emulator
        The emulator.
    points
        Guesses made: the walkers start around the best of them by the emulator.
    inside
        Whether points lie in the prior.
    samples
        Samples kept.
    seed
        The sampler's seed.

    Returns
    -------
    numpy.ndarray
        Shape (samples, parameters).
    """
    starts = points[np.argsort(emulator.loglik(points))[-BEST_STARTS:]]
    return sample_posterior(emulator, emulator.box, inside, starts, samples=samples,
                            seed=seed)


def tempered(emulator: FeatureEmulator, temperature: float) -> FeatureEmulator:
    """The emulator with its log-likelihood divided by a temperature.

    An emulator fitted to a few dozen guesses errs most where it has seen least, and its
    posterior, as sharp as the data, then excludes parts of a ridge the likelihood does
    not: on a slip-weakening test whose synthetic likelihood (12 members) stays within
    3.5 of its highest from fs 0.90 to 0.99 along the fs-Dc ridge, the emulators' fell
    by 10 to 15 at places along it, different for each seed; four seeds' medians of fs
    ran from 0.906 to 0.958, and two of their intervals, [0.883, 0.936] and [0.931,
    0.983], barely met. Guesses drawn from the tempered posterior (Neal 1996, "Sampling
    from multimodal distributions using tempered transitions") reach along the whole
    ridge; the posterior is then sampled untempered.

    Parameters
    ----------
    emulator
        The emulator.
    temperature
        At least 1; 1 returns the emulator itself.

    Returns
    -------
    FeatureEmulator
        Its processes, its log-likelihood divided by ``temperature``.

    Examples
    --------
    >>> from slipwave.fit.search import gaussian_process
    >>> inputs = np.linspace(0.0, 1.0, 8)[:, None]
    >>> process = gaussian_process(inputs, inputs[:, 0], seed=0)
    >>> emulator = FeatureEmulator((process,), np.array([[0.0, 1.0]]),
    ...                            lambda means, variances: -means[:, 0])
    >>> point = np.array([[0.5]])
    >>> round(float(tempered(emulator, 2.0).loglik(point)[0] / emulator.loglik(point)[0]), 6)
    0.5
    """
    if temperature == 1.0:
        return emulator
    loglik_of = emulator.loglik_of
    return replace(emulator,
                   loglik_of=lambda means, variances: loglik_of(means, variances) / temperature)


def emulator_search(simulate: Callable[[np.ndarray], np.ndarray], box: np.ndarray,
                    draw: Callable[[int, np.random.Generator | int], np.ndarray],
                    inside: Callable[[np.ndarray], np.ndarray],
                    loglik_of: Callable[[np.ndarray, np.ndarray], np.ndarray], *,
                    design: int, refinements: int, samples: int, seed: int,
                    absent: np.ndarray | None = None,
                    progress: Callable[[str], None] | None = None,
                    batch: int = ACQUISITION_BATCH, warm: bool = False,
                    temperature: float = 1.0
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, FeatureEmulator]:
    """A posterior from an emulator of the features, its guesses drawn from its posterior.

    A Latin hypercube of the prior (``design`` points per coordinate); then batches of
    ``batch`` guesses drawn from the emulator's posterior, the emulator refitted after
    each (``refinements`` per coordinate); then emcee on prior x exp(emulated
    log-likelihood).

    Parameters
    ----------
    simulate
        The features at guesses, shape (n, features) for (n, coordinates); a row of NaN
        where the simulation failed, a NaN where a run has no value of a feature (it is
        learnt from the others).
    box
        The prior's box, one row (low, high) per coordinate.
    draw
        ``draw(count, rng)``: ``count`` points of the prior.
    inside
        Whether points lie in the prior.
    loglik_of
        The log-likelihood given features' means and variances (:class:`FeatureEmulator`).
    design, refinements
        Guesses of the design and from the emulator's posterior, per coordinate.
    samples
        Posterior samples kept.
    seed
        The search's seed.
    absent
        As :func:`emulate`'s.
    progress
        Called with a line after each batch.
    batch
        Guesses drawn per refit of the emulator.
    warm
        Each refit starts its processes' optimisers from the last fit's
        hyperparameters (:func:`emulate`'s ``previous``), not afresh.
    temperature
        The batches are drawn from the emulated posterior with its log-likelihood
        divided by this (1: the posterior itself).

    Returns
    -------
    tuple
        The posterior samples, the guesses, their features and the last emulator.

    Raises
    ------
    SlipwaveError
        If fewer guesses of the design than coordinates plus two have features.

    Examples
    --------
    Two features of three parameters, x + y and y - z, measured as 1.0 and 0.2 to 0.01:
    a ridge, which the posterior follows without a guess on it.

    >>> from scipy.stats import qmc
    >>> box = np.array([[0.0, 1.0]] * 3)
    >>> def draw(count, rng):
    ...     return qmc.LatinHypercube(d=3, seed=rng).random(count)
    >>> def inside(x):
    ...     return np.all((x >= 0.0) & (x <= 1.0), axis=1)
    >>> def loglik_of(means, variances):
    ...     total = variances + 0.01**2
    ...     return -0.5 * (((means - [1.0, 0.2]) ** 2) / total + np.log(total)).sum(axis=1)
    >>> def simulate(x):
    ...     return np.column_stack([x[:, 0] + x[:, 1], x[:, 1] - x[:, 2]])
    >>> drawn, points, features, _ = emulator_search(
    ...     simulate, box, draw, inside, loglik_of, design=4, refinements=1, samples=1000,
    ...     seed=1)
    >>> sums = drawn[:, 0] + drawn[:, 1]
    >>> round(float(sums.mean()), 2), float(sums.std()) < 0.02, float(drawn[:, 0].std()) > 0.1
    (1.0, True, True)
    """
    say = progress or (lambda _: None)
    rng = np.random.default_rng(seed)
    dimensions = box.shape[0]
    points = draw(design * dimensions, seed)
    features = np.asarray(simulate(points), dtype=float)

    def fitted(round_: int, previous: FeatureEmulator | None) -> FeatureEmulator:
        finite = np.isfinite(features[:, 0])
        if finite.sum() < dimensions + 2:
            raise SlipwaveError(f"{finite.sum()} of {len(points)} guesses have features (the "
                                "simulations failed): too few to emulate them")
        return emulate(points[finite], features[finite], box, loglik_of, seed + round_,
                       absent, previous if warm else None)

    def made() -> np.ndarray:
        return points[np.isfinite(features[:, 0])]

    say(f"design: {len(points)} guesses")
    emulator: FeatureEmulator | None = None
    for round_ in range(0, refinements * dimensions, batch):
        emulator = fitted(round_, emulator)
        draws = emulated_posterior(tempered(emulator, temperature), made(), inside,
                                   samples=200, seed=int(rng.integers(2**31)))
        chosen = draws[rng.choice(draws.shape[0], batch, replace=False)]
        points = np.vstack([points, chosen])
        features = np.vstack([features, np.asarray(simulate(chosen), dtype=float)])
        say(f"refinements: {len(points)} guesses, the emulator's best log-likelihood "
            f"{float(np.max(emulator.loglik(points))):.1f}")
    emulator = fitted(refinements * dimensions, emulator)
    drawn = emulated_posterior(emulator, made(), inside, samples=samples, seed=seed)
    return drawn, points, features, emulator
