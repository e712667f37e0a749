"""Pitch on labelled stills: rank correlation and bias against the tilt, and lap vs level.

Pointing'04's tilt labels are directions the subjects looked at (part of each tilt is done with
the eyes) in 15-30 deg steps, so the rank correlation (Spearman) is the fair measure of a head
pitch estimate and the per-tilt mean error shows how much of the tilt the head does. The `lap`
classification: stills labelled tilt -60 (looking down into the lap) against stills labelled
|tilt| <= 15 (level), by the service's zone (neutral 0, each still a first sample).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from roadgaze.evaluation.ground_truth import GroundTruth
from roadgaze.evaluation.images import ImageEstimate
from roadgaze.evaluation.stats import error_stats, json_float, separation_auc, spearman

__all__ = [
    "LAP_TILT_DEG",
    "LEVEL_TILT_DEG",
    "PITCH_METHOD_LABELS",
    "LapRow",
    "PitchMethodReport",
    "PitchReport",
    "TiltStats",
    "evaluate_pitch",
    "format_pitch_report",
]

LAP_TILT_DEG = -60.0
LEVEL_TILT_DEG = 15.0
DOWN_ZONES = ("lap", "cluster", "centre_stack")
PITCH_METHOD_LABELS: Mapping[str, str] = {
    "service": "Service pitch",
    "matrix": "MediaPipe matrix",
    "geometric": "Geometric (P4)",
}


@dataclass(frozen=True, slots=True)
class TiltStats:
    """One labelled tilt: images, faces with an estimate, mean estimate, mean error, MAE."""

    tilt_deg: float
    n_images: int
    n_valid: int
    mean_deg: float
    bias_deg: float
    mae_deg: float


@dataclass(frozen=True, slots=True)
class PitchMethodReport:
    spearman: float
    """Rank correlation with the tilt over every image with an estimate."""
    spearman_yaw_le_60: float
    """The same over the images labelled |yaw| <= 60."""
    lap_auc: float
    """Probability that a tilt -60 still reads lower than a level (|tilt| <= 15) one."""
    tilts: tuple[TiltStats, ...]


@dataclass(frozen=True, slots=True)
class LapRow:
    """Zone classification of lap and level stills within one range of labelled |yaw|."""

    max_abs_yaw_deg: float
    n_lap: int
    lap_as_lap: int
    lap_as_down: int
    """Tilt -60 stills given any looking-down zone (lap, cluster, centre stack)."""
    n_level: int
    level_as_lap: int
    level_as_road: int


@dataclass(frozen=True, slots=True)
class PitchReport:
    methods: Mapping[str, PitchMethodReport]
    lap: tuple[LapRow, ...]

    def to_json_dict(self) -> dict[str, Any]:
        return {
            "methods": {
                name: {
                    "spearman": json_float(m.spearman),
                    "spearman_abs_yaw_le_60": json_float(m.spearman_yaw_le_60),
                    "lap_auc": json_float(m.lap_auc),
                    "tilts": [
                        {
                            "tilt_deg": t.tilt_deg,
                            "n_images": t.n_images,
                            "n_valid": t.n_valid,
                            "mean_deg": json_float(t.mean_deg),
                            "bias_deg": json_float(t.bias_deg),
                            "mae_deg": json_float(t.mae_deg),
                        }
                        for t in m.tilts
                    ],
                }
                for name, m in self.methods.items()
            },
            "lap": [
                {
                    "max_abs_yaw_deg": row.max_abs_yaw_deg,
                    "n_lap": row.n_lap,
                    "lap_as_lap": row.lap_as_lap,
                    "lap_as_down": row.lap_as_down,
                    "n_level": row.n_level,
                    "level_as_lap": row.level_as_lap,
                    "level_as_road": row.level_as_road,
                }
                for row in self.lap
            ],
        }


def _value(value: float | None) -> float:
    return math.nan if value is None else value


def evaluate_pitch(
    truths: Sequence[GroundTruth], estimates: Sequence[ImageEstimate]
) -> PitchReport | None:
    """Pitch against the tilt labels; None when the data set has no pitch labels."""
    if len(truths) != len(estimates):
        raise ValueError(f"{len(truths)} ground-truth rows but {len(estimates)} estimates")
    tilt = np.array([_value(t.pitch_deg) for t in truths])
    if not np.any(np.isfinite(tilt)):
        return None
    yaw = np.array([t.yaw_deg for t in truths])
    face = np.array([e.face for e in estimates], dtype=bool)
    series = {
        "service": np.array([_value(e.pitch_deg) for e in estimates]),
        "matrix": np.array([_value(e.mediapipe_pitch_deg) for e in estimates]),
        "geometric": np.array([_value(e.pitch_geometric_deg) for e in estimates]),
    }
    lap_rows = np.isclose(tilt, LAP_TILT_DEG)
    level_rows = np.abs(tilt) <= LEVEL_TILT_DEG
    methods = {}
    for name, estimate in series.items():
        estimate = np.where(face, estimate, np.nan)
        tilts = []
        for level in np.unique(tilt[np.isfinite(tilt)]):
            rows = tilt == level
            stats = error_stats(tilt[rows], estimate[rows], face[rows])
            valid = rows & np.isfinite(estimate)
            tilts.append(
                TiltStats(
                    tilt_deg=float(level),
                    n_images=int(rows.sum()),
                    n_valid=stats.n_valid,
                    mean_deg=float(estimate[valid].mean()) if valid.any() else math.nan,
                    bias_deg=stats.bias_deg,
                    mae_deg=stats.mae_deg,
                )
            )
        inner = np.abs(yaw) <= 60.0
        methods[name] = PitchMethodReport(
            spearman=spearman(tilt, estimate),
            spearman_yaw_le_60=spearman(tilt[inner], estimate[inner]),
            lap_auc=separation_auc(estimate[lap_rows], estimate[level_rows]),
            tilts=tuple(tilts),
        )
    zones = np.array([e.zone if e.face else None for e in estimates], dtype=object)
    lap = []
    for max_yaw in (15.0, 30.0, 90.0):
        near = (np.abs(yaw) <= max_yaw) & face
        lap_zones, level_zones = zones[near & lap_rows], zones[near & level_rows]
        lap.append(
            LapRow(
                max_abs_yaw_deg=max_yaw,
                n_lap=int((near & lap_rows).sum()),
                lap_as_lap=int(np.sum(lap_zones == "lap")),
                lap_as_down=int(sum(z in DOWN_ZONES for z in lap_zones)),
                n_level=int((near & level_rows).sum()),
                level_as_lap=int(np.sum(level_zones == "lap")),
                level_as_road=int(np.sum(level_zones == "road")),
            )
        )
    return PitchReport(methods=methods, lap=tuple(lap))


def _percent(count: int, total: int) -> str:
    return f"{100.0 * count / total:5.1f}%" if total else "    -"


def format_pitch_report(report: PitchReport) -> str:
    """The pitch tables as plain text."""

    def number(value: float, digits: int = 1) -> str:
        return f"{value:+.{digits}f}" if math.isfinite(value) else "-"

    lines = [
        "Pitch against the labelled tilt (images with a face; service pitch: neutral 0):",
        f"{'method':<17} {'Spearman':>8} {'|yaw|<=60':>9} {'lap AUC':>8}   mean estimate "
        "(mean error) per tilt",
    ]
    for name, method in report.methods.items():
        per_tilt = "  ".join(
            f"{t.tilt_deg:+.0f}: {number(t.mean_deg)} ({number(t.bias_deg)})" for t in method.tilts
        )
        lines.append(
            f"{PITCH_METHOD_LABELS[name]:<17} {method.spearman:8.3f} "
            f"{method.spearman_yaw_le_60:9.3f} {method.lap_auc:8.3f}   {per_tilt}"
        )
    lines.append("")
    lines.append(
        f"lap vs level by the service's zone (tilt {LAP_TILT_DEG:g} against |tilt| <= "
        f"{LEVEL_TILT_DEG:g}; neutral 0):"
    )
    lines.append(
        f"{'labelled |yaw|':>14} {'lap n':>6} {'-> lap':>7} {'-> down':>8} "
        f"{'level n':>8} {'-> lap':>7} {'-> road':>8}"
    )
    for row in report.lap:
        lines.append(
            f"{f'<= {row.max_abs_yaw_deg:g}':>14} {row.n_lap:>6} "
            f"{_percent(row.lap_as_lap, row.n_lap):>7} {_percent(row.lap_as_down, row.n_lap):>8} "
            f"{row.n_level:>8} {_percent(row.level_as_lap, row.n_level):>7} "
            f"{_percent(row.level_as_road, row.n_level):>8}"
        )
    lines.append("-> down: lap, cluster or centre stack (the zones below the road)")
    return "\n".join(lines)
