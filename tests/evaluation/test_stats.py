"""The one error-statistics type: every figure checked on a hand-computed case."""

from __future__ import annotations

import math

import numpy as np

from roadgaze.evaluation.stats import error_stats, range_stats


def test_range_stats_separate_the_sign_bias_from_the_offset() -> None:
    truth = np.array([-20.0, -10.0, 10.0, 20.0])
    estimate = np.array([-19.0, np.nan, 9.0, 17.0]) + 1.0  # +1 offset, magnitude shrunk
    result = range_stats("model", truth, estimate, 0.0, 30.0, include_high=True).stats
    assert (result.n_images, result.n_valid) == (4, 3)
    np.testing.assert_allclose(result.mae_deg, (2 + 0 + 2) / 3)
    np.testing.assert_allclose(result.bias_deg, (2 + 0 - 2) / 3)
    np.testing.assert_allclose(result.sign_bias_deg, 0.5 * (-1.0 - 2.0))
    assert result.max_deg == 2.0


def test_range_bounds_include_the_high_end_only_when_asked() -> None:
    truth = np.array([0.0, 15.0, 30.0])
    estimate = truth + 1.0
    assert range_stats("m", truth, estimate, 0.0, 30.0).stats.n_images == 2
    assert range_stats("m", truth, estimate, 0.0, 30.0, include_high=True).stats.n_images == 3


def test_no_valid_estimate_gives_nan_not_an_error() -> None:
    stats = error_stats(np.array([1.0, 2.0]), np.array([np.nan, np.nan]))
    assert stats.n_valid == 0 and stats.undefined == 2
    assert math.isnan(stats.mae_deg) and math.isnan(stats.sign_bias_deg)
    assert stats.to_json_dict()["mae_deg"] is None
