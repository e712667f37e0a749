"""Which landmarks make the face boundaries and centre: re-scoring stored landmarks per choice."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from roadgaze.evaluation.ground_truth import GroundTruth
from roadgaze.evaluation.images import MODEL_NAMES, ImageEstimate, yaw_by_model
from roadgaze.evaluation.report import METHOD_LABELS, PAPER_RANGE_DEG, align, fmt
from roadgaze.evaluation.stats import ErrorStats, error_stats
from roadgaze.landmarks.features import (
    DEFAULT_CHOICE,
    LandmarkChoice,
    boundaries_and_center,
    remove_roll,
)
from roadgaze.pose.geometry import PAPER_CONSTANTS, FaceModelConstants


def rescore_landmark_choice(
    estimates: Sequence[ImageEstimate], choice: LandmarkChoice, constants: FaceModelConstants
) -> list[ImageEstimate]:
    """The estimates recomputed from the stored driver landmarks under another landmark choice."""

    result = []
    for e in estimates:
        if e.landmarks_px is None or e.roll_deg is None:
            result.append(e)
            continue
        upright = remove_roll(e.landmarks_px, e.roll_deg)
        x_left, x_right, x_center = boundaries_and_center(upright, choice)
        result.append(
            replace(
                e,
                x_left_px=x_left,
                x_right_px=x_right,
                x_center_px=x_center,
                yaw_deg_by_model=yaw_by_model(x_left, x_right, x_center, constants),
            )
        )
    return result


def compare_landmark_choices(
    truths: Sequence[GroundTruth],
    estimates: Sequence[ImageEstimate],
    choices: Sequence[LandmarkChoice],
    constants: FaceModelConstants = PAPER_CONSTANTS,
) -> list[tuple[LandmarkChoice, Mapping[str, ErrorStats]]]:
    """Each choice's |yaw| <= 60 stats per model, all images scored together (never per subject)."""
    truth = np.array([t.yaw_deg for t in truths])
    inner = np.abs(truth) <= PAPER_RANGE_DEG
    rows: list[tuple[LandmarkChoice, Mapping[str, ErrorStats]]] = []
    for choice in choices:
        scored = align(truths, rescore_landmark_choice(estimates, choice, constants))
        rows.append(
            (
                choice,
                {
                    m: error_stats(truth[inner], scored.estimates_deg[m][inner], scored.face[inner])
                    for m in MODEL_NAMES
                },
            )
        )
    return rows


def format_landmark_comparison(
    rows: Sequence[tuple[LandmarkChoice, Mapping[str, ErrorStats]]],
) -> str:
    """Markdown table: choice, Center-CE MAE and valid rate, then the other models' MAE."""
    header = (
        "| landmark choice (boundaries / centre) | Center-CE MAE | Center-CE valid % | "
        + " | ".join(f"{METHOD_LABELS[m]} MAE" for m in MODEL_NAMES if m != "center_ce")
        + " |"
    )
    lines = [header, "|" + "---|" * (3 + len(MODEL_NAMES) - 1)]
    for choice, stats in rows:
        marker = " **(default)**" if choice == DEFAULT_CHOICE else ""
        center = stats["center_ce"]
        lines.append(
            f"| {choice.name}{marker} | {fmt(center.mae_deg)} | "
            f"{fmt(100 * center.valid_rate, 1)} | "
            + " | ".join(fmt(stats[m].mae_deg) for m in MODEL_NAMES if m != "center_ce")
            + " |"
        )
    return "\n".join(lines)
