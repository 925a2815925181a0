"""The features' emulator: features some runs lack, its predictions, warm refits."""

from __future__ import annotations

import numpy as np
import pytest

from slipwave.errors import SlipwaveError
from slipwave.fit.emulator import MIN_VALUES, emulate

BOX = np.array([[0.0, 1.0], [0.0, 1.0]])


def loglik_of(means: np.ndarray, variances: np.ndarray) -> np.ndarray:
    return -0.5 * ((means - 0.5) ** 2 / (variances + 0.01)).sum(axis=1)


def test_a_feature_some_runs_lack_is_learnt_from_the_others() -> None:
    points = np.random.default_rng(3).random((30, 2))
    features = np.column_stack([points.sum(axis=1), 2.0 * points[:, 0]])
    features[points[:, 1] > 0.5, 1] = np.nan  # lacked by half the runs
    emulator = emulate(points, features, BOX, loglik_of, seed=0)
    means, _ = emulator.predict(np.array([[0.3, 0.2], [0.7, 0.4]]))
    np.testing.assert_allclose(means[:, 1], [0.6, 1.4], atol=0.02)


def test_a_feature_too_few_runs_have_stands_at_its_absent_value() -> None:
    points = np.random.default_rng(4).random((20, 2))
    features = np.column_stack([points[:, 0], np.full(20, np.nan)])
    features[: MIN_VALUES - 1, 1] = 5.0
    with pytest.raises(SlipwaveError, match="feature 1 has 2 values of 20 runs"):
        emulate(points, features, BOX, loglik_of, seed=0)
    emulator = emulate(points, features, BOX, loglik_of, seed=0,
                       absent=np.array([np.nan, 1.0]))
    means, _ = emulator.predict(points[MIN_VALUES - 1:])
    np.testing.assert_allclose(means[:, 1], 1.0, atol=0.1)


def test_the_emulator_predicts_what_its_processes_predict() -> None:
    """Its stacked prediction is each process's own, to rounding, a feature lacked by
    some runs (fewer runs, padded) included."""
    rng = np.random.default_rng(5)
    points = rng.random((25, 2))
    features = np.column_stack([np.sin(3.0 * points[:, 0]) + points[:, 1] ** 2,
                                points[:, 0] * points[:, 1] + rng.normal(0.0, 0.01, 25),
                                np.exp(points[:, 1])])
    features[:6, 2] = np.nan
    emulator = emulate(points, features, BOX, loglik_of, seed=0)
    queries = np.vstack([rng.random((7, 2)), points[10:12]])  # two on runs: variance ~0
    means, variances = emulator.predict(queries)
    for k, process in enumerate(emulator.processes):
        mean, sd = process.predict(queries, return_std=True)
        np.testing.assert_allclose(means[:, k], mean, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(variances[:, k], sd**2, rtol=1e-6,
                                   atol=1e-9 * float(np.var(features[:, k][6:])))


def test_a_warm_refit_starts_once_from_the_last_fit_and_predicts_as_a_fresh_one() -> None:
    rng = np.random.default_rng(6)
    points = rng.random((32, 2))
    features = np.column_stack([np.sin(3.0 * points[:, 0]) + points[:, 1] ** 2,
                                np.exp(points[:, 1])])
    first = emulate(points[:28], features[:28], BOX, loglik_of, seed=0)
    warm = emulate(points, features, BOX, loglik_of, seed=1, previous=first)
    fresh = emulate(points, features, BOX, loglik_of, seed=1)
    assert all(process.n_restarts_optimizer == 0 for process in warm.processes)
    assert all(process.n_restarts_optimizer > 0 for process in fresh.processes)
    queries = rng.random((50, 2))
    np.testing.assert_allclose(warm.predict(queries)[0], fresh.predict(queries)[0],
                               atol=0.01)
