"""Evaluation: pose and eyes on stills scored against ground truth, the paper's experiments."""

from roadgaze.evaluation.eyes import (
    EyeEstimate,
    EyeReport,
    evaluate_eyes,
    format_eye_report,
    still_eyes,
)
from roadgaze.evaluation.ground_truth import GroundTruth, load_ground_truth
from roadgaze.evaluation.images import (
    MODEL_NAMES,
    ImageEstimate,
    estimate_from_detection,
    estimate_image,
    estimate_images,
    read_image,
    yaw_by_model,
)
from roadgaze.evaluation.landmark_choices import (
    compare_landmark_choices,
    format_landmark_comparison,
    rescore_landmark_choice,
)
from roadgaze.evaluation.pitch import (
    PitchReport,
    evaluate_pitch,
    format_pitch_report,
)
from roadgaze.evaluation.refit import format_refit, refit_constants
from roadgaze.evaluation.report import (
    METHOD_LABELS,
    METHODS,
    PAPER_RANGE_DEG,
    PEER,
    PREDICTION_COLUMNS,
    SERVICE,
    EvaluationReport,
    align,
    evaluate,
    format_report,
    save_plot,
    write_predictions,
    write_report,
)
from roadgaze.evaluation.stats import ErrorStats, RangeStats, error_stats, range_stats

__all__ = [
    "METHODS",
    "METHOD_LABELS",
    "MODEL_NAMES",
    "PAPER_RANGE_DEG",
    "PEER",
    "PREDICTION_COLUMNS",
    "SERVICE",
    "ErrorStats",
    "EvaluationReport",
    "EyeEstimate",
    "EyeReport",
    "GroundTruth",
    "ImageEstimate",
    "PitchReport",
    "RangeStats",
    "align",
    "compare_landmark_choices",
    "error_stats",
    "estimate_from_detection",
    "estimate_image",
    "estimate_images",
    "evaluate",
    "evaluate_eyes",
    "evaluate_pitch",
    "format_eye_report",
    "format_landmark_comparison",
    "format_pitch_report",
    "format_refit",
    "format_report",
    "load_ground_truth",
    "range_stats",
    "read_image",
    "refit_constants",
    "rescore_landmark_choice",
    "save_plot",
    "still_eyes",
    "write_predictions",
    "write_report",
    "yaw_by_model",
]
