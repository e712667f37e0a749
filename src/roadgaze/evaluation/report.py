"""Scoring estimates against ground truth: per model, for the service's yaw and for MediaPipe's
own yaw, over |yaw| <= 60 deg, over all rows and per 15 deg bin; pitch against the tilt and the
lap classification (`roadgaze.evaluation.pitch`); the report as text, JSON, CSV and a plot.

Scoring: detection rate = images with a face / images; a model's errors (estimate minus truth)
are taken over the images where a face was found and the model could explain the geometry
(`valid`); MAE, RMSE and median are of those errors.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.evaluation.eyes import EyeEstimate, EyeReport, evaluate_eyes, format_eye_report
from roadgaze.evaluation.full_range_cv import (
    CrossValidation,
    cross_validate_full_range,
    format_cross_validation,
)
from roadgaze.evaluation.ground_truth import GroundTruth
from roadgaze.evaluation.images import MODEL_NAMES, ImageEstimate
from roadgaze.evaluation.pitch import PitchReport, evaluate_pitch, format_pitch_report
from roadgaze.evaluation.stats import ErrorStats, error_stats
from roadgaze.pose.geometry import PAPER_CONSTANTS, FaceModelConstants
from roadgaze.types import FloatArray

PEER = "mediapipe"
"""MediaPipe's own yaw from its facial transformation matrix, the peer we compare against."""
SERVICE = "service"
"""The service's yaw (`geometry.model`: the full-range blend by default)."""
METHODS: tuple[str, ...] = (*MODEL_NAMES, SERVICE, PEER)
METHOD_LABELS: Mapping[str, str] = {
    "cylindrical": "Cylindrical",
    "ellipsoidal": "Ellipsoidal",
    "ce": "CE",
    "center_ce": "Center-CE",
    "boundary_ce": "Boundary-CE",
    SERVICE: "Service yaw",
    PEER: "MediaPipe matrix",
}
PAPER_RANGE_DEG = 60.0
BIN_WIDTH_DEG = 15.0
PREDICTION_COLUMNS: tuple[str, ...] = (
    "file",
    "face",
    "yaw_cylindrical",
    "yaw_ellipsoidal",
    "yaw_ce",
    "yaw_center_ce",
    "yaw_boundary_ce",
    "yaw_mediapipe",
    "yaw_deg",
    "pitch_deg",
    "roll_deg",
    "zone",
    "pitch_mediapipe",
    "pitch_geometric",
    "gaze_yaw_deg",
    "gaze_pitch_deg",
    "eye_openness",
    "eyes_closed",
)
"""`yaw_deg`, `pitch_deg`, `zone`: the service's (neutral 0); `roll_deg`: the eye line's;
`gaze_*`: head + eyes (the head alone where the eyes give no direction); `eye_openness`: lid gap
/ eye width; `eyes_closed`: 1 closed, 0 open, empty when the eyes cannot be judged."""


@dataclass(frozen=True, slots=True)
class ScoredSet:
    """Aligned arrays of one evaluation: truth, face found, and each method's estimate."""

    files: tuple[str, ...]
    true_yaw_deg: FloatArray
    face: npt.NDArray[np.bool_]
    estimates_deg: Mapping[str, FloatArray]


def align(truths: Sequence[GroundTruth], estimates: Sequence[ImageEstimate]) -> ScoredSet:
    """Pair ground-truth rows with their estimates (same order, same length)."""
    if len(truths) != len(estimates):
        raise ValueError(f"{len(truths)} ground-truth rows but {len(estimates)} estimates")
    estimates_deg: dict[str, FloatArray] = {}
    for name in MODEL_NAMES:
        values = [e.yaw_deg_by_model.get(name) for e in estimates]
        estimates_deg[name] = np.array([math.nan if v is None else v for v in values])
    peer = [e.mediapipe_yaw_deg for e in estimates]
    estimates_deg[PEER] = np.array([math.nan if v is None else v for v in peer])
    service = [e.yaw_deg for e in estimates]
    estimates_deg[SERVICE] = np.array([math.nan if v is None else v for v in service])
    return ScoredSet(
        files=tuple(t.file for t in truths),
        true_yaw_deg=np.array([t.yaw_deg for t in truths], dtype=np.float64),
        face=np.array([e.face for e in estimates], dtype=bool),
        estimates_deg=estimates_deg,
    )


@dataclass(frozen=True, slots=True)
class BinStats:
    center_deg: float
    stats: Mapping[str, ErrorStats]


@dataclass(frozen=True, slots=True)
class EvaluationReport:
    """Every figure `roadgaze eval` prints."""

    dataset: str
    n_rows: int
    n_skipped_pitch90: int
    n_unreadable: int
    constants: FaceModelConstants
    ranges: Mapping[str, Mapping[str, ErrorStats]]
    """'abs_yaw_le_60' and 'all' -> method -> stats."""
    bins: tuple[BinStats, ...]
    refit: Mapping[str, Any] | None = None
    pitch: PitchReport | None = None
    eyes: EyeReport | None = None
    cross_validation: CrossValidation | None = None
    """The full-range blend with its constants re-fitted leaving each subject out (data sets
    with a `subject` column)."""

    def to_json_dict(self) -> dict[str, Any]:
        return {
            "dataset": self.dataset,
            "n_rows": self.n_rows,
            "n_skipped_pitch90": self.n_skipped_pitch90,
            "n_unreadable": self.n_unreadable,
            "constants": {
                "alpha": self.constants.alpha,
                "beta": self.constants.beta,
                "gamma_c": self.constants.gamma_c,
                "gamma_b": self.constants.gamma_b,
            },
            "ranges": {
                key: {m: s.to_json_dict() for m, s in per_method.items()}
                for key, per_method in self.ranges.items()
            },
            "bins": [
                {
                    "center_deg": b.center_deg,
                    "methods": {m: s.to_json_dict() for m, s in b.stats.items()},
                }
                for b in self.bins
            ],
            "refit": self.refit,
            "pitch": None if self.pitch is None else self.pitch.to_json_dict(),
            "eyes": None if self.eyes is None else self.eyes.to_json_dict(),
            "cross_validation": (
                None if self.cross_validation is None else self.cross_validation.to_json_dict()
            ),
        }


RANGE_KEYS: Mapping[str, str] = {"abs_yaw_le_60": "|yaw| <= 60", "all": "all"}


def evaluate(
    dataset: str,
    truths: Sequence[GroundTruth],
    estimates: Sequence[ImageEstimate],
    skipped: int = 0,
    constants: FaceModelConstants = PAPER_CONSTANTS,
) -> EvaluationReport:
    """Score estimates against ground truth over |yaw| <= 60, all rows, and 15 deg bins."""
    scored = align(truths, estimates)
    truth = scored.true_yaw_deg
    masks = {"abs_yaw_le_60": np.abs(truth) <= PAPER_RANGE_DEG, "all": np.ones_like(truth, bool)}
    ranges = {
        key: {
            m: error_stats(truth[mask], scored.estimates_deg[m][mask], scored.face[mask])
            for m in METHODS
        }
        for key, mask in masks.items()
    }
    bin_index = np.round(truth / BIN_WIDTH_DEG)
    bins = []
    for index in np.unique(bin_index):
        mask = bin_index == index
        bins.append(
            BinStats(
                center_deg=float(index * BIN_WIDTH_DEG),
                stats={
                    m: error_stats(truth[mask], scored.estimates_deg[m][mask], scored.face[mask])
                    for m in METHODS
                },
            )
        )
    return EvaluationReport(
        dataset=dataset,
        n_rows=len(truths),
        n_skipped_pitch90=skipped,
        n_unreadable=sum(1 for e in estimates if e.error is not None),
        constants=constants,
        ranges=ranges,
        bins=tuple(bins),
        pitch=evaluate_pitch(truths, estimates),
        eyes=evaluate_eyes(truths, estimates),
        cross_validation=cross_validate_full_range(truths, estimates, constants),
    )


def fmt(value: float, digits: int = 2) -> str:
    """A number for a table; '-' for NaN."""
    return f"{value:.{digits}f}" if math.isfinite(value) else "-"


def format_report(report: EvaluationReport) -> str:
    """The summary table, then the per-bin MAE table, as plain text."""
    lines = [
        f"dataset {report.dataset}: {report.n_rows} images scored "
        f"({report.n_skipped_pitch90} skipped with |pitch| = 90, "
        f"{report.n_unreadable} unreadable)",
        f"constants: alpha={report.constants.alpha} beta={report.constants.beta} "
        f"gamma_c={report.constants.gamma_c} gamma_b={report.constants.gamma_b}",
        "",
    ]
    header = f"{'method':<17} {'range':<12} {'n':>5} {'det%':>6} {'valid%':>7} "
    header += f"{'MAE':>6} {'RMSE':>6} {'median':>7} {'bias':>6}"
    lines.append(header)
    lines.append("-" * len(header))
    for key, label in RANGE_KEYS.items():
        for method in METHODS:
            s = report.ranges[key][method]
            lines.append(
                f"{METHOD_LABELS[method]:<17} {label:<12} {s.n_images:>5} "
                f"{fmt(100 * s.detection_rate, 1):>6} {fmt(100 * s.valid_rate, 1):>7} "
                f"{fmt(s.mae_deg):>6} {fmt(s.rmse_deg):>6} {fmt(s.median_deg):>7} "
                f"{fmt(s.bias_deg):>6}"
            )
        lines.append("")
    bin_header = f"{'yaw':>5} {'n':>5} {'det%':>6} " + " ".join(
        f"{METHOD_LABELS[m][:11]:>11}" for m in METHODS
    )
    for title, value in (
        ("MAE (deg) per 15 deg bin of true yaw (det% = face found):", "mae_deg"),
        ("bias (mean signed error, deg) per 15 deg bin of true yaw:", "bias_deg"),
    ):
        lines += [title, bin_header, "-" * len(bin_header)]
        for b in report.bins:
            first = b.stats[MODEL_NAMES[0]]
            lines.append(
                f"{b.center_deg:>5.0f} {first.n_images:>5} "
                f"{fmt(100 * first.detection_rate, 1):>6} "
                + " ".join(f"{fmt(getattr(b.stats[m], value)):>11}" for m in METHODS)
            )
        lines.append("")
    lines.pop()
    if report.cross_validation is not None:
        lines.append("")
        lines.append(format_cross_validation(report.cross_validation))
    if report.pitch is not None:
        lines.append("")
        lines.append(format_pitch_report(report.pitch))
    if report.eyes is not None:
        lines.append("")
        lines.append(format_eye_report(report.eyes))
    if report.refit is not None:
        lines.append("")
        from roadgaze.evaluation.refit import format_refit

        lines.append(format_refit(report.refit))
    return "\n".join(lines)


def write_predictions(path: Path, estimates: Iterable[ImageEstimate]) -> None:
    """CSV with PREDICTION_COLUMNS; empty cells where there is no estimate."""

    def cell(value: float | None) -> str:
        return "" if value is None else f"{value:.3f}"

    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream)
        writer.writerow(PREDICTION_COLUMNS)
        for e in estimates:
            writer.writerow(
                [e.file, int(e.face)]
                + [cell(e.yaw_deg_by_model.get(name)) for name in MODEL_NAMES]
                + [cell(e.mediapipe_yaw_deg), cell(e.yaw_deg), cell(e.pitch_deg)]
                + [cell(e.roll_deg), e.zone or ""]
                + [cell(e.mediapipe_pitch_deg), cell(e.pitch_geometric_deg)]
                + _eye_cells(e.eyes, cell)
            )


def _eye_cells(eyes: EyeEstimate | None, cell: Callable[[float | None], str]) -> list[str]:
    if eyes is None:
        return ["", "", "", ""]
    closed = "" if eyes.closed is None else str(int(eyes.closed))
    return [cell(eyes.gaze_yaw_deg), cell(eyes.gaze_pitch_deg), cell(eyes.openness), closed]


def write_report(path: Path, report: EvaluationReport) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(report.to_json_dict(), indent=2) + "\n", encoding="utf-8")


def save_plot(
    path: Path, truths: Sequence[GroundTruth], estimates: Sequence[ImageEstimate]
) -> None:
    """Estimated vs true yaw, one panel per model and one for the peer (like the paper's figs)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scored = align(truths, estimates)
    figure, axes = plt.subplots(2, 4, figsize=(17, 8.5), sharex=True, sharey=True)
    limit = max(90.0, float(np.max(np.abs(scored.true_yaw_deg))))
    for axis in axes.ravel()[len(METHODS) :]:
        axis.set_visible(False)
    for axis, method in zip(axes.ravel(), METHODS, strict=False):
        estimate = scored.estimates_deg[method]
        valid = np.isfinite(estimate) & scored.face
        truth = scored.true_yaw_deg
        axis.scatter(truth[valid], estimate[valid], s=6, alpha=0.25, color="tab:blue")
        levels = np.unique(truth[valid])
        if levels.size <= 40:
            means = [np.mean(estimate[valid][truth[valid] == v]) for v in levels]
            axis.plot(levels, means, "o-", color="tab:red", ms=3, lw=1, label="mean")
        axis.plot([-limit, limit], [-limit, limit], "k--", lw=0.8, label="ideal")
        inner = valid & (np.abs(truth) <= PAPER_RANGE_DEG)
        mae = float(np.mean(np.abs(estimate[inner] - truth[inner]))) if inner.any() else math.nan
        axis.set_title(f"{METHOD_LABELS[method]} (MAE |yaw|<=60: {fmt(mae)} deg)")
        axis.grid(True, alpha=0.3)
        axis.set_xlim(-limit, limit)
        axis.set_ylim(-limit, limit)
    for axis in axes[1]:
        axis.set_xlabel("true yaw (deg)")
    for axis in axes[:, 0]:
        axis.set_ylabel("estimated yaw (deg)")
    axes[0, 0].legend(loc="upper left")
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)
    plt.close(figure)
