"""The one error-statistics type: every figure checked on a hand-computed case."""

from __future__ import annotations

import math

import numpy as np
import pytest

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


def test_spearman_and_auc_against_hand_computed_values() -> None:
    from roadgaze.evaluation.stats import average_ranks, separation_auc, spearman

    np.testing.assert_allclose(average_ranks([10.0, 30.0, 20.0, 20.0]), [1.0, 4.0, 2.5, 2.5])
    assert spearman([1, 2, 3, 4], [10, 20, 35, 100]) == 1.0  # monotonic, not linear
    assert spearman([1, 2, 3, 4], [4, 3, 2, 1]) == -1.0
    # d = ranks differ by (0, 0, 1, -1): 1 - 6 * 2 / (4 * 15) = 0.8 without ties
    assert spearman([1, 2, 3, 4], [1, 2, 4, 3]) == pytest.approx(0.8)
    assert np.isnan(spearman([1, 2], [1, 2]))
    assert np.isnan(spearman([1, 1, 1], [1, 2, 3]))
    assert separation_auc([1, 2, 3], [4, 5]) == 1.0
    assert separation_auc([4, 5], [1, 2, 3]) == 0.0
    assert separation_auc([1, 3], [2, 2]) == pytest.approx(0.5)  # half the pairs below
    assert separation_auc([2], [2]) == pytest.approx(0.5)  # a tie counts half
    assert np.isnan(separation_auc([], [1.0]))
