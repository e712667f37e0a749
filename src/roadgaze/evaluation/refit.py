"""A global least-MAE re-fit of each model's constants, to bound what a re-fit could gain."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from roadgaze.evaluation.ground_truth import GroundTruth
from roadgaze.evaluation.images import ImageEstimate
from roadgaze.evaluation.report import METHOD_LABELS, PAPER_RANGE_DEG, align
from roadgaze.pose.geometry import PAPER_CONSTANTS, YAW_MODELS, FaceModelConstants
from roadgaze.types import FloatArray

_FITTED_PARAMETERS: Mapping[str, tuple[str, ...]] = {
    "ellipsoidal": ("alpha", "beta"),
    "ce": ("beta",),
    "center_ce": ("beta", "gamma_c"),
    "boundary_ce": ("beta", "gamma_b"),
}


def refit_constants(
    truths: Sequence[GroundTruth],
    estimates: Sequence[ImageEstimate],
    constants: FaceModelConstants = PAPER_CONSTANTS,
) -> dict[str, Any]:
    """One global least-MAE fit of each model's constants on |yaw| <= 60 (all images together).

    In-sample figures: the fit sees the same images it is scored on, so it bounds what a re-fit
    can gain; the paper's constants stay the default everywhere else.
    """
    from dataclasses import replace

    scored = align(truths, estimates)
    keep = scored.face & (np.abs(scored.true_yaw_deg) <= PAPER_RANGE_DEG)
    x_left = np.array([e.x_left_px if e.x_left_px is not None else math.nan for e in estimates])
    x_right = np.array([e.x_right_px if e.x_right_px is not None else math.nan for e in estimates])
    x_center = np.array(
        [e.x_center_px if e.x_center_px is not None else math.nan for e in estimates]
    )
    x_left, x_right, x_center = x_left[keep], x_right[keep], x_center[keep]
    truth = scored.true_yaw_deg[keep]
    result: dict[str, Any] = {"n_images": int(truth.size), "models": {}}

    for name, parameters in _FITTED_PARAMETERS.items():
        model = YAW_MODELS[name]

        def objective(
            values: FloatArray,
            model: Callable[..., Any] = model,
            parameters: tuple[str, ...] = parameters,
        ) -> float:
            trial = replace(constants, **dict(zip(parameters, map(float, values), strict=True)))
            if trial.beta <= 1.0 or trial.alpha < 0 or trial.gamma_c < 0 or trial.gamma_b < 0:
                return 1e6
            estimate = np.asarray(model(x_left, x_right, x_center, trial))
            errors = np.where(np.isfinite(estimate), estimate - truth, 90.0)
            return float(np.mean(np.abs(errors)))

        start = np.array([getattr(constants, p) for p in parameters], dtype=np.float64)
        best_values, best_mae = _grid_minimize(objective, start)
        fitted = dict(zip(parameters, (round(float(v), 4) for v in best_values), strict=True))
        result["models"][name] = {
            "paper_mae_deg": round(objective(start), 4),
            "refit_mae_deg": round(best_mae, 4),
            "constants": fitted,
        }
    return result


def _grid_minimize(
    objective: Callable[[FloatArray], float], start: FloatArray, rounds: int = 4
) -> tuple[FloatArray, float]:
    """Coarse-to-fine grid search around `start` (1 or 2 parameters); returns (best, value)."""
    import itertools

    best = start.copy()
    best_value = objective(best)
    span = np.maximum(np.abs(start), 0.25)
    for _ in range(rounds):
        axes = [np.linspace(c - s, c + s, 21) for c, s in zip(best, span, strict=True)]
        for point in itertools.product(*axes):
            candidate = np.array(point, dtype=np.float64)
            value = objective(candidate)
            if value < best_value:
                best, best_value = candidate, value
        span = span / 5.0
    return best, best_value


def format_refit(refit: Mapping[str, Any]) -> str:
    lines = [
        f"global re-fit of the constants on |yaw| <= 60 ({refit['n_images']} images, in-sample; "
        "invalid estimates count as 90 deg errors):",
        f"{'model':<13} {'paper MAE':>10} {'refit MAE':>10}  constants",
    ]
    for name, entry in refit["models"].items():
        constants = ", ".join(f"{k}={v}" for k, v in entry["constants"].items())
        lines.append(
            f"{METHOD_LABELS[name]:<13} {entry['paper_mae_deg']:>10.2f} "
            f"{entry['refit_mae_deg']:>10.2f}  {constants}"
        )
    return "\n".join(lines)
