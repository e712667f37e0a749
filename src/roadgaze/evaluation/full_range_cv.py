"""Leave-subjects-out check of the full-range blend (F1): its two constants re-fitted without the
subject they are scored on (pure numpy).

For each subject of a data set with a `subject` column, the blend's cue start and end (degrees of
|MediaPipe matrix yaw|) are fitted on the other subjects by the rule that chose the shipped
constants (docs/pose.md): on a 2.5 deg grid, the pair with the lowest MAE over all poses among
those whose MAE within +-60 deg is at least `margin_deg` below Center-CE's on the same subjects;
when no pair qualifies, the fold uses Center-CE alone. The held-out subject is then scored with
that fold's pair. Every figure is therefore out of sample: no image is scored by constants fitted
on its own subject. Errors are taken over the images with a face, as everywhere in the report.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from roadgaze.evaluation.ground_truth import GroundTruth
from roadgaze.evaluation.images import ImageEstimate
from roadgaze.evaluation.stats import ErrorStats, error_stats
from roadgaze.pose.fullrange import FullRangeConstants, clipped_cylinder_deg, full_range_yaw_deg
from roadgaze.pose.geometry import PAPER_CONSTANTS, FaceModelConstants, center_ce
from roadgaze.types import FloatArray

PAPER_RANGE_DEG = 60.0
BIN_WIDTH_DEG = 15.0
GRID_STEP_DEG = 2.5
START_GRID_DEG = np.arange(10.0, 60.0 + 1e-9, GRID_STEP_DEG)
END_GRID_DEG = np.arange(30.0, 100.0 + 1e-9, GRID_STEP_DEG)
CV_METHODS: tuple[str, ...] = ("center_ce", "cylindrical", "service_cv")
"""Center-CE, the clipped cylinder and the blend with leave-subjects-out constants."""


@dataclass(frozen=True, slots=True)
class FoldFit:
    """The constants one fold chose; None when no pair beat Center-CE by the margin."""

    held_out: str
    constants: FullRangeConstants | None


@dataclass(frozen=True, slots=True)
class CrossValidation:
    """Out-of-sample figures of the full-range blend, per 15 deg bin and over two ranges."""

    margin_deg: float
    folds: tuple[FoldFit, ...]
    ranges: Mapping[str, Mapping[str, ErrorStats]]
    """'abs_yaw_le_60' and 'all' -> method (`CV_METHODS`) -> stats."""
    bins: tuple[tuple[float, Mapping[str, ErrorStats]], ...]
    """(bin centre in degrees, method -> stats) in increasing order."""

    def to_json_dict(self) -> dict[str, Any]:
        return {
            "margin_deg": self.margin_deg,
            "folds": [
                {
                    "held_out": fold.held_out,
                    "cue_start_deg": None
                    if fold.constants is None
                    else fold.constants.cue_start_deg,
                    "cue_end_deg": None if fold.constants is None else fold.constants.cue_end_deg,
                }
                for fold in self.folds
            ],
            "ranges": {
                key: {m: s.to_json_dict() for m, s in per.items()}
                for key, per in self.ranges.items()
            },
            "bins": [
                {"center_deg": centre, "methods": {m: s.to_json_dict() for m, s in per.items()}}
                for centre, per in self.bins
            ],
        }


def _column(estimates: Sequence[ImageEstimate], name: str) -> FloatArray:
    values = [getattr(e, name) for e in estimates]
    return np.array([math.nan if v is None else v for v in values], dtype=np.float64)


def _candidates() -> list[FullRangeConstants]:
    return [
        FullRangeConstants(float(start), float(end))
        for start in START_GRID_DEG
        for end in END_GRID_DEG
        if end >= start + 5.0
    ]


def cross_validate_full_range(
    truths: Sequence[GroundTruth],
    estimates: Sequence[ImageEstimate],
    constants: FaceModelConstants = PAPER_CONSTANTS,
    margin_deg: float = 0.1,
) -> CrossValidation | None:
    """Leave-one-subject-out figures of (F1); None without at least two labelled subjects."""
    subjects = np.array([t.subject or "" for t in truths])
    names = sorted({s for s in subjects.tolist() if s}, key=lambda s: (len(s), s))
    if len(names) < 2 or len(truths) != len(estimates):
        return None
    truth = np.array([t.yaw_deg for t in truths], dtype=np.float64)
    face = np.array([e.face for e in estimates], dtype=bool)
    left, right = _column(estimates, "x_left_px"), _column(estimates, "x_right_px")
    centre, cue = _column(estimates, "x_center_px"), _column(estimates, "mediapipe_yaw_deg")
    inner = np.asarray(center_ce(left, right, centre, constants), dtype=np.float64)
    candidates = _candidates()
    # Per candidate and subject: summed absolute errors and counts, all poses and within +-60.
    index = np.array([names.index(s) if s in names else -1 for s in subjects.tolist()])
    inside = np.abs(truth) <= PAPER_RANGE_DEG

    def sums(yaw: FloatArray) -> FloatArray:
        valid = face & np.isfinite(yaw) & (index >= 0)
        error = np.where(valid, np.abs(yaw - truth), 0.0)
        table = np.zeros((4, len(names)))
        for row, mask in enumerate((valid, valid & inside)):
            table[2 * row] = np.bincount(index[mask], error[mask], len(names))
            table[2 * row + 1] = np.bincount(index[mask], None, len(names))
        return table

    baseline = sums(inner)
    tables = [
        sums(np.asarray(full_range_yaw_deg(left, right, centre, cue, c, constants)))
        for c in candidates
    ]
    folds: list[FoldFit] = []
    service = np.full(truth.shape, np.nan)
    for held, name in enumerate(names):
        keep = np.arange(len(names)) != held
        base_inside = baseline[2, keep].sum() / baseline[3, keep].sum()
        best: tuple[float, FullRangeConstants] | None = None
        for candidate, table in zip(candidates, tables, strict=True):
            within = table[2, keep].sum() / table[3, keep].sum()
            if within > base_inside - margin_deg:
                continue
            overall = table[0, keep].sum() / table[1, keep].sum()
            if best is None or overall < best[0]:
                best = (overall, candidate)
        chosen = None if best is None else best[1]
        folds.append(FoldFit(name, chosen))
        rows = index == held
        service[rows] = (
            inner[rows]
            if chosen is None
            else full_range_yaw_deg(
                left[rows], right[rows], centre[rows], cue[rows], chosen, constants
            )
        )
    estimates_deg = {
        "center_ce": inner,
        "cylindrical": np.asarray(clipped_cylinder_deg(left, right, centre), dtype=np.float64),
        "service_cv": service,
    }
    scored = index >= 0
    masks = {"abs_yaw_le_60": scored & inside, "all": scored}
    ranges = {
        key: {m: error_stats(truth[mask], v[mask], face[mask]) for m, v in estimates_deg.items()}
        for key, mask in masks.items()
    }
    bin_index = np.round(truth / BIN_WIDTH_DEG)
    bins = tuple(
        (
            float(i * BIN_WIDTH_DEG),
            {m: error_stats(truth[mask], v[mask], face[mask]) for m, v in estimates_deg.items()},
        )
        for i in np.unique(bin_index[scored])
        for mask in [scored & (bin_index == i)]
    )
    return CrossValidation(margin_deg, tuple(folds), ranges, bins)


def format_cross_validation(result: CrossValidation) -> str:
    """The folds' constants, then MAE / bias per bin of Center-CE, the cylinder and the blend."""

    def cell(stats: ErrorStats) -> str:
        if not math.isfinite(stats.mae_deg):
            return f"{'-':>13}"
        return f"{stats.mae_deg:>6.2f}/{stats.bias_deg:>+6.1f}"

    chosen = ", ".join(
        f"{fold.held_out}: "
        + (
            "Center-CE"
            if fold.constants is None
            else f"{fold.constants.cue_start_deg:g}-{fold.constants.cue_end_deg:g}"
        )
        for fold in result.folds
    )
    lines = [
        "full-range blend, constants re-fitted leaving each subject out "
        f"(lowest all-pose MAE with the MAE within +-60 at least {result.margin_deg:g} deg below "
        "Center-CE's on the other subjects):",
        f"cue start-end (deg) per held-out subject: {chosen}",
        f"{'yaw':>5} {'n':>5} {'det%':>6} {'Center-CE':>13} {'cylinder':>13} {'blend (LOSO)':>13}"
        "   (MAE/bias, deg)",
    ]
    for centre, per in result.bins:
        first = per[CV_METHODS[0]]
        lines.append(
            f"{centre:>5.0f} {first.n_images:>5} {100 * first.detection_rate:>6.1f} "
            + " ".join(cell(per[m]) for m in CV_METHODS)
        )
    for key, label in (("abs_yaw_le_60", "|yaw|<=60"), ("all", "all")):
        per = result.ranges[key]
        lines.append(f"{label:>11} {'':>6} " + " ".join(cell(per[m]) for m in CV_METHODS))
    return "\n".join(lines)
