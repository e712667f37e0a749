"""The leave-subjects-out check of the full-range blend: folds, the fitting rule, the fallback."""

from __future__ import annotations

import math

import numpy as np
import pytest

from roadgaze.evaluation import GroundTruth, ImageEstimate, evaluate, format_report
from roadgaze.evaluation.full_range_cv import cross_validate_full_range
from roadgaze.pose.geometry import forward_model

TRUE_YAW_DEG = np.repeat(np.arange(-90.0, 90.1, 15.0), 3)


def _data(subjects: int, cue_gain: float | None) -> tuple[list[GroundTruth], list[ImageEstimate]]:
    """Each subject sees every 15 deg yaw three times; the boundaries and centre come from the
    paper's forward model with a subject-dependent face, the cue is the true yaw times
    `cue_gain` (None: no cue)."""
    truths, estimates = [], []
    for subject in range(1, subjects + 1):
        rng = np.random.default_rng(subject)
        face = forward_model(TRUE_YAW_DEG, half_width_px=60.0 + 5.0 * subject)
        for i, yaw in enumerate(TRUE_YAW_DEG):
            name = f"s{subject}-{i}"
            truths.append(GroundTruth(name, float(yaw), 0.0, str(subject)))
            cue = None if cue_gain is None else float(yaw * cue_gain + rng.normal(0.0, 2.0))
            estimates.append(
                ImageEstimate(
                    file=name,
                    face=True,
                    n_faces=1,
                    mediapipe_yaw_deg=cue,
                    x_left_px=float(face.x_left[i]),
                    x_right_px=float(face.x_right[i]),
                    x_center_px=float(face.x_center[i] + rng.normal(0.0, 1.0)),
                )
            )
    return truths, estimates


def test_one_fold_per_subject_and_out_of_sample_gain_beyond_the_range() -> None:
    truths, estimates = _data(4, cue_gain=0.6)
    result = cross_validate_full_range(truths, estimates)
    assert result is not None
    assert [fold.held_out for fold in result.folds] == ["1", "2", "3", "4"]
    assert all(fold.constants is not None for fold in result.folds)
    every = result.ranges["all"]
    assert every["service_cv"].n_valid == len(truths)
    # Center-CE saturates near 60 deg on the forward model; the blend recovers the tails.
    assert every["service_cv"].mae_deg < every["center_ce"].mae_deg - 3.0
    inner = result.ranges["abs_yaw_le_60"]
    assert inner["service_cv"].mae_deg <= inner["center_ce"].mae_deg
    by_bin = dict(result.bins)
    assert by_bin[90.0]["service_cv"].mae_deg < by_bin[90.0]["center_ce"].mae_deg


def test_without_a_cue_every_fold_falls_back_to_center_ce() -> None:
    truths, estimates = _data(3, cue_gain=None)
    result = cross_validate_full_range(truths, estimates)
    assert result is not None
    assert all(fold.constants is None for fold in result.folds)
    every = result.ranges["all"]
    assert every["service_cv"].mae_deg == pytest.approx(every["center_ce"].mae_deg)


def test_no_subjects_no_cross_validation_and_the_report_prints_it() -> None:
    truths, estimates = _data(2, cue_gain=0.6)
    unlabelled = [GroundTruth(t.file, t.yaw_deg, t.pitch_deg) for t in truths]
    assert cross_validate_full_range(unlabelled, estimates) is None
    assert evaluate("toy", unlabelled, estimates).cross_validation is None
    report = evaluate("toy", truths, estimates)
    assert report.cross_validation is not None
    text = format_report(report)
    assert "leaving each subject out" in text and "bias (mean signed error" in text
    cv = report.to_json_dict()["cross_validation"]
    assert len(cv["folds"]) == 2 and math.isfinite(cv["ranges"]["all"]["service_cv"]["mae_deg"])
