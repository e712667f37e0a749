"""Error statistics: the one type every accuracy figure of roadgaze is made of (pure numpy)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.types import FloatArray


@dataclass(frozen=True, slots=True)
class ErrorStats:
    """Errors (estimate minus truth, degrees) of one method over a set of images or frames.

    The errors are taken over the `n_valid` items that have a face and a finite estimate.
    """

    n_images: int
    n_faces: int
    n_valid: int
    mae_deg: float
    rmse_deg: float
    median_deg: float
    """Median absolute error."""
    bias_deg: float
    """Mean signed error."""
    max_deg: float
    """Largest absolute error."""
    sign_bias_deg: float
    """Half the difference of the mean errors at positive and at negative truth: the part of the
    error that grows with |angle| (< 0: magnitudes underestimated); an offset common to both
    signs cancels. NaN unless both signs are present."""

    @property
    def detection_rate(self) -> float:
        return self.n_faces / self.n_images if self.n_images else math.nan

    @property
    def valid_rate(self) -> float:
        return self.n_valid / self.n_images if self.n_images else math.nan

    @property
    def undefined(self) -> int:
        """Items with a face whose estimate is not finite (the model could not explain them)."""
        return self.n_faces - self.n_valid

    def to_json_dict(self) -> dict[str, Any]:
        return {
            "n_images": self.n_images,
            "n_faces": self.n_faces,
            "n_valid": self.n_valid,
            "detection_rate": json_float(self.detection_rate),
            "valid_rate": json_float(self.valid_rate),
            "mae_deg": json_float(self.mae_deg),
            "rmse_deg": json_float(self.rmse_deg),
            "median_abs_error_deg": json_float(self.median_deg),
            "bias_deg": json_float(self.bias_deg),
        }


def json_float(value: float) -> float | None:
    """`value` rounded to 4 decimals for JSON; None for NaN or infinity."""
    return round(value, 4) if math.isfinite(value) else None


def error_stats(
    true_deg: npt.ArrayLike,
    estimate_deg: npt.ArrayLike,
    face: npt.NDArray[np.bool_] | None = None,
) -> ErrorStats:
    """Statistics of `estimate - true` where finite; `face` marks items with a face (all when
    None)."""
    truth = np.asarray(true_deg, dtype=np.float64)
    estimate = np.asarray(estimate_deg, dtype=np.float64)
    found = np.ones(truth.shape, dtype=bool) if face is None else np.asarray(face, dtype=bool)
    valid = np.isfinite(estimate) & found
    errors = estimate[valid] - truth[valid]
    nan = math.nan
    if errors.size == 0:
        mae = rmse = median = bias = largest = nan
    else:
        mae = float(np.mean(np.abs(errors)))
        rmse = float(np.sqrt(np.mean(errors**2)))
        median = float(np.median(np.abs(errors)))
        bias = float(np.mean(errors))
        largest = float(np.max(np.abs(errors)))
    sign = np.sign(truth[valid])
    positive, negative = errors[sign > 0], errors[sign < 0]
    sign_bias = (
        0.5 * (float(positive.mean()) - float(negative.mean()))
        if positive.size and negative.size
        else nan
    )
    return ErrorStats(
        n_images=int(truth.size),
        n_faces=int(np.count_nonzero(found)),
        n_valid=int(errors.size),
        mae_deg=mae,
        rmse_deg=rmse,
        median_deg=median,
        bias_deg=bias,
        max_deg=largest,
        sign_bias_deg=sign_bias,
    )


@dataclass(frozen=True, slots=True)
class RangeStats:
    """`ErrorStats` of one method over the items whose |truth| lies in [low_deg, high_deg)."""

    label: str
    low_deg: float
    high_deg: float
    stats: ErrorStats


def range_stats(
    label: str,
    true_deg: FloatArray,
    estimate_deg: FloatArray,
    low_deg: float,
    high_deg: float,
    include_high: bool = False,
) -> RangeStats:
    """Errors over low <= |truth| < high (<= high with `include_high`)."""
    magnitude = np.abs(true_deg)
    inside = (magnitude >= low_deg) & (
        (magnitude <= high_deg) if include_high else (magnitude < high_deg)
    )
    return RangeStats(label, low_deg, high_deg, error_stats(true_deg[inside], estimate_deg[inside]))


def average_ranks(values: npt.ArrayLike) -> FloatArray:
    """Ranks 1..n of `values`, ties sharing the mean of their ranks."""
    data = np.asarray(values, dtype=np.float64)
    order = np.argsort(data, kind="mergesort")
    ranks = np.empty(data.size)
    ranks[order] = np.arange(1, data.size + 1, dtype=np.float64)
    _, inverse, counts = np.unique(data, return_inverse=True, return_counts=True)
    sums = np.bincount(inverse, weights=ranks)
    return np.asarray((sums / counts)[inverse], dtype=np.float64)


def spearman(a: npt.ArrayLike, b: npt.ArrayLike) -> float:
    """Spearman's rank correlation of the pairs where both are finite; NaN for fewer than three
    pairs or a constant side."""
    x = np.asarray(a, dtype=np.float64)
    y = np.asarray(b, dtype=np.float64)
    both = np.isfinite(x) & np.isfinite(y)
    if np.count_nonzero(both) < 3:
        return math.nan
    rank_x, rank_y = average_ranks(x[both]), average_ranks(y[both])
    if np.ptp(rank_x) == 0 or np.ptp(rank_y) == 0:
        return math.nan
    return float(np.corrcoef(rank_x, rank_y)[0, 1])


def separation_auc(low: npt.ArrayLike, high: npt.ArrayLike) -> float:
    """Probability that a finite value of `low` lies below one of `high` (ties count half): the
    area under the ROC curve of telling the two apart by a threshold. NaN if either is empty."""
    below = np.asarray(low, dtype=np.float64)
    above = np.asarray(high, dtype=np.float64)
    below, above = below[np.isfinite(below)], above[np.isfinite(above)]
    if below.size == 0 or above.size == 0:
        return math.nan
    ranks = average_ranks(np.concatenate([below, above]))
    rank_sum = float(ranks[below.size :].sum())
    return (rank_sum - above.size * (above.size + 1) / 2.0) / (below.size * above.size)
