"""The features' emulator: features some runs lack."""

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
