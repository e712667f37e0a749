"""The condition suite: the service on labelled stills under each cabin condition, side by side.

Every image with |yaw| <= 60 (the paper's range) is read once, run clean, then run under each
condition (`roadgaze.evaluation.conditions`; the face-drawing conditions use the clean image's
landmarks, or the fixed face box when the clean image has no face). Per condition:

- **faces found**: share of the images in which the service found a face;
- **yaw MAE / pitch MAE**: the service's yaw and pitch (neutral 0) against the labels, over the
  faces found;
- **eyes**: on the faces found with |tilt| <= 30 (open-eyed faces), the share called open, closed
  and not judged;
- **road on level frontal faces**: on the faces found with |yaw| <= 15 and |tilt| <= 15, the
  share whose zone is `road`.
"""

from __future__ import annotations

import math
import multiprocessing
from collections.abc import Sequence
from contextlib import closing
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from roadgaze.config import Config
from roadgaze.errors import SourceError
from roadgaze.evaluation.conditions import apply_condition
from roadgaze.evaluation.ground_truth import GroundTruth
from roadgaze.evaluation.images import ImageEstimate, StillPose, estimate_from_detection, read_image
from roadgaze.evaluation.stats import json_float
from roadgaze.types import EyeStatus, LandmarkDetector

RANGE_DEG = 60.0
OPEN_EYED_TILT_DEG = 30.0
LEVEL_YAW_DEG = 15.0
LEVEL_TILT_DEG = 15.0


@dataclass(frozen=True, slots=True)
class ConditionRow:
    """One condition's figures (see the module docstring); MAEs in degrees, NaN without faces."""

    condition: str
    images: int
    faces: int
    yaw_mae_deg: float
    pitch_mae_deg: float
    eye_faces: int
    eyes_open: int
    eyes_closed: int
    level_faces: int
    level_road: int
    faces_by_subject: tuple[tuple[str, int, int], ...] = ()
    """(subject, faces found, images) per subject, in the order of their first image, when the
    ground truth names subjects."""

    @property
    def faces_rate(self) -> float:
        return self.faces / self.images if self.images else math.nan

    def to_json_dict(self) -> dict[str, Any]:
        return {
            "condition": self.condition,
            "images": self.images,
            "faces": self.faces,
            "faces_rate": json_float(self.faces_rate),
            "yaw_mae_deg": json_float(self.yaw_mae_deg),
            "pitch_mae_deg": json_float(self.pitch_mae_deg),
            "eye_faces": self.eye_faces,
            "eyes_open": self.eyes_open,
            "eyes_closed": self.eyes_closed,
            "eyes_not_judged": self.eye_faces - self.eyes_open - self.eyes_closed,
            "level_faces": self.level_faces,
            "level_road": self.level_road,
            "subjects": [
                {"subject": subject, "faces": faces, "images": images}
                for subject, faces, images in self.faces_by_subject
            ],
        }


def run_conditions(
    detector: LandmarkDetector,
    still: StillPose,
    path: Path,
    name: str,
    conditions: Sequence[str],
) -> tuple[ImageEstimate, ...]:
    """One image under each condition (the first must be `clean`), landmarks dropped."""
    try:
        clean = read_image(path)
    except SourceError as exc:
        return tuple(ImageEstimate(file=name, face=False, error=str(exc)) for _ in conditions)
    landmarks = None
    estimates = []
    for condition in conditions:
        image = apply_condition(condition, clean, landmarks, name)
        estimate = estimate_from_detection(
            name, detector.detect(image), still.pose.constants, still
        )
        if condition == "clean":
            landmarks = estimate.landmarks_px
        estimates.append(replace(estimate, landmarks_px=None))
    return tuple(estimates)


_worker: dict[str, Any] = {}


def _init_worker(config: Config, model_path: Path, conditions: Sequence[str]) -> None:
    from multiprocessing.util import Finalize

    from roadgaze.evaluation.images import still_detector

    detector = still_detector(config.landmarks, model_path)
    _worker.update(detector=detector, still=StillPose.from_config(config), conditions=conditions)
    Finalize(None, detector.close, exitpriority=10)


def _worker_run(job: tuple[Path, str]) -> tuple[ImageEstimate, ...]:
    return run_conditions(_worker["detector"], _worker["still"], *job, _worker["conditions"])


def suite_truths(truths: Sequence[GroundTruth]) -> list[GroundTruth]:
    """The rows the suite scores: |yaw| <= 60."""
    return [truth for truth in truths if abs(truth.yaw_deg) <= RANGE_DEG]


def estimate_conditions(
    dataset: Path,
    truths: Sequence[GroundTruth],
    conditions: Sequence[str],
    config: Config,
    model_path: Path,
    workers: int = 1,
    progress: bool = False,
) -> list[tuple[ImageEstimate, ...]]:
    """Per row of `truths`, its estimate under each condition, in `conditions` order."""
    from tqdm import tqdm

    jobs = [(dataset / truth.file, truth.file) for truth in truths]
    results: list[tuple[ImageEstimate, ...]] = []
    with tqdm(
        total=len(jobs), desc="conditions", unit="img", disable=None if progress else True
    ) as bar:
        if workers <= 1:
            from roadgaze.evaluation.images import still_detector

            still = StillPose.from_config(config)
            with closing(still_detector(config.landmarks, model_path)) as detector:
                for path, name in jobs:
                    results.append(run_conditions(detector, still, path, name, conditions))
                    bar.update(1)
            return results
        context = multiprocessing.get_context("spawn")
        with context.Pool(workers, _init_worker, (config, model_path, tuple(conditions))) as pool:
            for estimates in pool.imap(_worker_run, jobs, chunksize=4):
                results.append(estimates)
                bar.update(1)
    return results


def _mae(pairs: list[tuple[float, float | None]]) -> float:
    errors = [abs(estimate - label) for label, estimate in pairs if estimate is not None]
    return float(np.mean(errors)) if errors else math.nan


def score_condition(
    condition: str, truths: Sequence[GroundTruth], estimates: Sequence[ImageEstimate]
) -> ConditionRow:
    """The figures of one condition over `truths` and their estimates under it."""
    found = [(t, e) for t, e in zip(truths, estimates, strict=True) if e.face]
    with_tilt = [(t, e) for t, e in found if t.pitch_deg is not None]
    open_eyed = [
        e.eyes.status
        for t, e in with_tilt
        if e.eyes is not None and abs(t.pitch_deg or 0.0) <= OPEN_EYED_TILT_DEG
    ]
    level = [
        e.zone
        for t, e in with_tilt
        if abs(t.yaw_deg) <= LEVEL_YAW_DEG and abs(t.pitch_deg or 0.0) <= LEVEL_TILT_DEG
    ]
    by_subject: dict[str, list[int]] = {}
    for truth, estimate in zip(truths, estimates, strict=True):
        if truth.subject is not None:
            counts = by_subject.setdefault(truth.subject, [0, 0])
            counts[0] += estimate.face
            counts[1] += 1
    return ConditionRow(
        faces_by_subject=tuple((name, found, n) for name, (found, n) in by_subject.items()),
        condition=condition,
        images=len(truths),
        faces=len(found),
        yaw_mae_deg=_mae([(t.yaw_deg, e.yaw_deg) for t, e in found]),
        pitch_mae_deg=_mae([(t.pitch_deg or 0.0, e.pitch_deg) for t, e in with_tilt]),
        eye_faces=len(open_eyed),
        eyes_open=sum(status is EyeStatus.OPEN for status in open_eyed),
        eyes_closed=sum(status is EyeStatus.CLOSED for status in open_eyed),
        level_faces=len(level),
        level_road=sum(zone == "road" for zone in level),
    )


def score_conditions(
    conditions: Sequence[str],
    truths: Sequence[GroundTruth],
    results: Sequence[tuple[ImageEstimate, ...]],
) -> list[ConditionRow]:
    """One row per condition, in order."""
    return [
        score_condition(name, truths, [estimates[i] for estimates in results])
        for i, name in enumerate(conditions)
    ]


def _percent(count: int, total: int) -> str:
    return f"{100.0 * count / total:.1f}" if total else "-"


def format_condition_table(rows: Sequence[ConditionRow]) -> str:
    """The rows as a Markdown table (eyes and road as % of the faces found that qualify)."""
    lines = [
        "| condition | faces found % | yaw MAE | pitch MAE | eyes open % | eyes closed % "
        "| eyes not judged % | road on level frontal % |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        not_judged = row.eye_faces - row.eyes_open - row.eyes_closed
        lines.append(
            f"| {row.condition} | {_percent(row.faces, row.images)} ({row.faces}/{row.images}) "
            f"| {row.yaw_mae_deg:.2f} | {row.pitch_mae_deg:.2f} "
            f"| {_percent(row.eyes_open, row.eye_faces)} "
            f"| {_percent(row.eyes_closed, row.eye_faces)} "
            f"| {_percent(not_judged, row.eye_faces)} "
            f"| {_percent(row.level_road, row.level_faces)} ({row.level_faces}) |"
        )
    return "\n".join(lines)


def format_subject_table(rows: Sequence[ConditionRow]) -> str | None:
    """Faces found % per subject (a column each) and condition (a row each), as Markdown; None
    when the ground truth names no subjects."""
    subjects = [subject for subject, _, _ in rows[0].faces_by_subject] if rows else []
    if not subjects:
        return None
    lines = [
        "| faces found % by subject | " + " | ".join(subjects) + " |",
        "|---|" + "---|" * len(subjects),
    ]
    for row in rows:
        cells = [_percent(found, images) for _, found, images in row.faces_by_subject]
        lines.append(f"| {row.condition} | " + " | ".join(cells) + " |")
    return "\n".join(lines)
