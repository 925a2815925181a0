"""The Gaussian synthetic likelihood of a test's features under a law (Wood 2010).

An ensemble's K feature vectors (:mod:`slipwave.fit.ensemble`) give the features' mean
and covariance under the law; the measured vector is scored by the normal density with
that mean and covariance, plus the measurement's own errors (Wood 2010, Nature
466:1102; Bayesian synthetic likelihood, Price et al. 2018, J. Comput. Graph. Stat.
27:1). With K of a few, a sample covariance of some ten features is singular or
nearly: its correlations are shrunk towards none by Ledoit and Wolf's estimator
(scikit-learn's), the features' own variances kept (An et al. 2019 shrink too,
by the graphical lasso, for the same reason). The mean's own scatter over K members
adds Sigma / K.

Examples
--------
>>> rng = np.random.default_rng(0)
>>> members = rng.normal(0.0, 1.0, (8, 3))
>>> near = synthetic_loglik(np.zeros(3), members, np.full(3, 0.1))
>>> far = synthetic_loglik(np.full(3, 5.0), members, np.full(3, 0.1))
>>> bool(near > far)
True
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import NamedTuple

import numpy as np
from scipy.stats import multivariate_normal
from sklearn.covariance import ledoit_wolf


class ModelError(NamedTuple):
    """The model's own error of each feature at a guess (the mesh's: twice the mesh less it).

    Attributes
    ----------
    shift
        What the model's features lack on average: added to every member's, so that
        they stand for the finer model's.
    error
        How far the model may still be off, a standard error added to the
        measurement's in quadrature.

    """

    shift: np.ndarray
    error: np.ndarray


def shrunk_covariance(members: np.ndarray) -> np.ndarray:
    """The members' covariance, its correlations shrunk by Ledoit-Wolf.

    The features are standardised by their own standard deviations first, so that the
    estimator's target (a multiple of the identity) is the diagonal of the variances: a
    feature's variance is kept, only the correlations are shrunk. A feature that does
    not vary over the members has variance 0 (the measurement's error then carries it).

    Parameters
    ----------
    members
        Shape (K, features), K >= 2, finite.

    Returns
    -------
    numpy.ndarray
        Shape (features, features).

    Examples
    --------
    >>> members = np.array([[0.0, 1.0, 5.0], [1.0, 2.0, 5.0], [2.0, 4.0, 5.0]])
    >>> np.diag(shrunk_covariance(members)).round(3).tolist()
    [1.0, 2.333, 0.0]
    """
    return _shrunk(members - members.mean(axis=0), members.std(axis=0, ddof=1))


def _shrunk(deviations: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """The covariance of deviations of these standard deviations, correlations shrunk."""
    varies = sd > 0
    covariance = np.zeros((deviations.shape[1], deviations.shape[1]))
    if varies.sum() >= 2:
        correlation, _ = ledoit_wolf(deviations[:, varies] / sd[varies], assume_centered=True)
        # ledoit_wolf divides by the rows: back to a unit diagonal, the variances kept
        correlation = correlation / np.sqrt(np.outer(np.diag(correlation),
                                                     np.diag(correlation)))
        covariance[np.ix_(varies, varies)] = correlation * np.outer(sd[varies], sd[varies])
    elif varies.any():
        covariance[varies, varies] = sd[varies] ** 2
    return covariance


def synthetic_loglik(observed: np.ndarray, members: np.ndarray,
                     measurement_error: np.ndarray) -> float:
    """The log density of the observed features under an ensemble's normal approximation.

    log N(observed; mean, Sigma (1 + 1/K) + diag(measurement_error^2)), mean and Sigma
    over the K members (:func:`shrunk_covariance`).

    Parameters
    ----------
    observed
        The measured feature vector.
    members
        Shape (K, features): the ensemble's vectors; rows with NaN (a member the solver
        could not follow) are left out.
    measurement_error
        The measured features' standard errors (the floor of every variance).

    Returns
    -------
    float
        The log-likelihood; -inf with fewer than two members left.

    """
    finite = members[np.all(np.isfinite(members), axis=1)]
    if finite.shape[0] < 2:
        return float("-inf")
    count = finite.shape[0]
    covariance = shrunk_covariance(finite) * (1.0 + 1.0 / count)
    covariance += np.diag(np.asarray(measurement_error, dtype=float) ** 2)
    return float(multivariate_normal.logpdf(observed, mean=finite.mean(axis=0),
                                            cov=covariance))


def pooled_covariance(runs: list[np.ndarray]) -> np.ndarray:
    """The ensembles' scatter about their own means, pooled over several guesses.

    Each run's members deviate from their mean by what the recording does not fix
    (:mod:`slipwave.fit.ensemble`); near the optimum that scatter changes little from
    one guess to the next, while a handful of members per guess estimates it badly: a
    feature on which four members happen to agree gets a variance near 0, and the
    log-likelihood of the next guess, 0.3 % away, differs by thousands. The deviations
    of every run given are therefore pooled (degrees of freedom: members less one per
    run) and their correlations shrunk as in :func:`shrunk_covariance`.

    Parameters
    ----------
    runs
        Each run's members, shape (K_i, features), rows with NaN left out.

    Returns
    -------
    numpy.ndarray
        Shape (features, features).

    Examples
    --------
    >>> runs = [np.array([[0.0, 1.0], [2.0, 1.0]]), np.array([[10.0, 3.0], [12.0, 5.0]])]
    >>> np.diag(pooled_covariance(runs)).round(9).tolist()
    [2.0, 1.0]
    """
    deviations, freedom = [], 0
    for run in runs:
        finite = run[np.all(np.isfinite(run), axis=1)]
        if finite.shape[0] >= 2:
            deviations.append(finite - finite.mean(axis=0))
            freedom += finite.shape[0] - 1
    if not deviations:
        raise ValueError("no run has two members to pool")
    stacked = np.vstack(deviations)
    return _shrunk(stacked, np.sqrt(np.sum(stacked**2, axis=0) / freedom))


def pooled_logliks(observed: np.ndarray, runs: list[np.ndarray], covariance: np.ndarray,
                   measurement_error: np.ndarray) -> np.ndarray:
    """Each run's synthetic log-likelihood with a pooled covariance.

    log N(observed; the run's mean, covariance (1 + 1/K) + diag(measurement_error^2)).

    Parameters
    ----------
    observed
        The measured feature vector.
    runs
        Each guess's members, shape (K_i, features).
    covariance
        The scatter of one member (:func:`pooled_covariance`).
    measurement_error
        The measured features' standard errors.

    Returns
    -------
    numpy.ndarray
        One log-likelihood per run; -inf for a run with no member the solver followed.

    """
    out = np.full(len(runs), -np.inf)
    floor = np.diag(np.asarray(measurement_error, dtype=float) ** 2)
    for k, run in enumerate(runs):
        finite = run[np.all(np.isfinite(run), axis=1)]
        if finite.shape[0]:
            out[k] = multivariate_normal.logpdf(
                observed, mean=finite.mean(axis=0),
                cov=covariance * (1.0 + 1.0 / finite.shape[0]) + floor)
    return out


def emulated_logliks(observed: np.ndarray, means: np.ndarray, variances: np.ndarray,
                     covariance: np.ndarray, measurement_error: np.ndarray) -> np.ndarray:
    """The synthetic log-likelihood of emulated features.

    log N(observed; mean, covariance + diag(variance + measurement_error^2)) at each
    point: the emulator's variance of a guess's mean stands for the ensemble's Sigma / K
    and for what the emulator has not seen.

    Parameters
    ----------
    observed
        The measured feature vector.
    means, variances
        The emulated features' means and variances, shape (n, features).
    covariance
        The scatter of one member (:func:`pooled_covariance`).
    measurement_error
        The measured features' standard errors (with the model's, in quadrature).

    Returns
    -------
    numpy.ndarray
        One log-likelihood per point.

    Examples
    --------
    >>> rate = emulated_logliks(np.zeros(2), np.array([[0.0, 0.0], [0.3, 0.0]]),
    ...                         np.zeros((2, 2)), np.eye(2) * 0.01, np.full(2, 0.0))
    >>> (rate[0] - rate[1]).round(6).item()
    4.5
    """
    means = np.atleast_2d(means)
    totals = covariance[None, :, :] + np.einsum(
        "ij,nj->nij", np.eye(observed.size), variances + np.asarray(measurement_error)**2)
    factors = np.linalg.cholesky(totals)
    scaled = np.linalg.solve(factors, (observed[None, :] - means)[:, :, None])[:, :, 0]
    log_determinant = 2.0 * np.log(np.diagonal(factors, axis1=1, axis2=2)).sum(axis=1)
    return -0.5 * ((scaled**2).sum(axis=1) + log_determinant
                   + observed.size * np.log(2.0 * np.pi))


class SyntheticLikelihood:
    """A test's synthetic likelihood: the runs' log-likelihoods, their scatter pooled.

    Parameters
    ----------
    observed
        The measured feature vector.
    measurement_error
        Its standard errors.

    """

    def __init__(self, observed: np.ndarray, measurement_error: np.ndarray):
        self.observed = observed
        self.measurement_error = measurement_error

    def __call__(self, runs: list[np.ndarray], pool: np.ndarray,
                 model_error: np.ndarray | None = None) -> np.ndarray:
        """Each run's log-likelihood, the scatter pooled over the runs in ``pool``.

        Parameters
        ----------
        runs
            Each guess's members, shape (K_i, features).
        pool
            Which runs to pool the scatter over (every run with two members or more
            when none of them has).
        model_error
            The model's own error of each feature (the mesh's:
            :func:`~slipwave.fit.ensemble.mesh_error`), added to the measurement's in
            quadrature; none by default.

        Returns
        -------
        numpy.ndarray
            One per run (:func:`pooled_logliks`).

        """
        chosen = [run for run, kept in zip(runs, pool, strict=True) if kept]
        try:
            covariance = pooled_covariance(chosen)
        except ValueError:
            covariance = pooled_covariance(runs)
        return pooled_logliks(self.observed, runs, covariance, self._error(model_error))

    def emulated(self, runs: list[np.ndarray], model_error: np.ndarray | None = None
                 ) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        """The log-likelihood of emulated features, the scatter pooled over every run.

        Parameters
        ----------
        runs
            Each guess's members, shape (K_i, features).
        model_error
            As in :meth:`__call__`.

        Returns
        -------
        callable
            ``(means, variances) -> log-likelihoods`` (:func:`emulated_logliks`).

        """
        return partial(emulated_logliks, self.observed, covariance=pooled_covariance(runs),
                       measurement_error=self._error(model_error))

    def _error(self, model_error: np.ndarray | None) -> np.ndarray:
        """The measurement's errors, with the model's in quadrature where given."""
        if model_error is None:
            return self.measurement_error
        return np.hypot(self.measurement_error, model_error)
