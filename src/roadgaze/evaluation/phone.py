"""Phone use on labelled stills: the features of each image, the shipped classifier's scores,
and the figures leaving drivers out (`roadgaze eval DATASET --task phone`,
`scripts/train-phone.py`).

A data set is a folder with `ground_truth.csv` (`file,phone_use` and optional `class`,
`subject`). Each image goes through the hand stage and the face landmarker as stills (the
configured models), then `roadgaze.phone.features.frame_vector`: the very vector the service
judges; an image is phone use when its score reaches the threshold or a hand is held up in front
(`roadgaze.phone.held_up`), as the service judges it. Leaving drivers out: the classifier is
refitted on all drivers but one and scores that one's images; the threshold is the score that
keeps the false-positive rate over all negatives at `TARGET_FPR`, read from those held-out
scores (so it is chosen without the driver it is applied to only in the sense that every
driver's scores are out-of-fold).
"""

from __future__ import annotations

import csv
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.errors import DatasetError, SourceError
from roadgaze.phone.boosting import BoostSettings, fit, predict
from roadgaze.phone.held_up import held_up_rows

TARGET_FPR = 0.10
CLASS_NAMES = {
    "c0": "safe driving",
    "c1": "texting, right",
    "c2": "phone, right ear",
    "c3": "texting, left",
    "c4": "phone, left ear",
    "c5": "radio",
    "c6": "drinking",
    "c7": "reaching behind",
    "c8": "hair and makeup",
    "c9": "passenger",
}


@dataclass(frozen=True, slots=True)
class PhoneTruth:
    """One labelled image."""

    file: str
    phone_use: bool
    label: str = ""
    """The image's class (e.g. `c6`), '' without a `class` column."""
    subject: str = ""
    """The driver, '' without a `subject` column."""


def load_phone_truth(dataset: Path) -> list[PhoneTruth]:
    """The rows of `dataset/ground_truth.csv`; DatasetError (one line) when it is not usable."""
    path = dataset / "ground_truth.csv"
    if not path.is_file():
        raise DatasetError(f"{path} not found; the folder needs a ground_truth.csv")
    rows: list[PhoneTruth] = []
    with path.open(newline="", encoding="utf-8") as stream:
        reader = csv.DictReader(stream)
        columns = set(reader.fieldnames or [])
        if not {"file", "phone_use"} <= columns:
            raise DatasetError(
                f"{path}: needs columns file,phone_use; found {','.join(sorted(columns))}"
            )
        for line, row in enumerate(reader, start=2):
            value = (row.get("phone_use") or "").strip().lower()
            if value not in {"0", "1", "true", "false"} or not row.get("file"):
                raise DatasetError(
                    f"{path}:{line}: expected a file and phone_use 0/1, found "
                    f"{str(row.get('file'))[:40]!r}/{value[:10]!r}"
                )
            rows.append(
                PhoneTruth(
                    row["file"],
                    value in {"1", "true"},
                    (row.get("class") or "").strip(),
                    (row.get("subject") or "").strip(),
                )
            )
    if not rows:
        raise DatasetError(f"{path} lists no images")
    return rows


@dataclass(frozen=True, slots=True)
class Features:
    """The feature matrix of a data set (rows in the order of the truths; NaN rows: unreadable
    images), with the truths."""

    truths: tuple[PhoneTruth, ...]
    x: npt.NDArray[np.float64]
    judged: npt.NDArray[np.bool_]
    """Rows the judgement can judge (a hand or a face was found)."""

    @property
    def labels(self) -> npt.NDArray[np.int_]:
        return np.array([int(truth.phone_use) for truth in self.truths])

    @property
    def groups(self) -> npt.NDArray[np.str_]:
        return np.array([truth.subject for truth in self.truths])

    @property
    def classes(self) -> npt.NDArray[np.str_]:
        return np.array([truth.label for truth in self.truths])


def image_features(
    dataset: Path,
    truths: Sequence[PhoneTruth],
    config: Any,
    progress: bool = False,
    condition: str = "clean",
) -> Features:
    """Every image's feature vector (hands and face as stills), each image first put under
    `condition` (`roadgaze.evaluation.conditions.apply_condition`: seeded by its file name; one
    that draws on the face gets the fixed face box); DatasetError without the hand models or
    when no image can be read."""
    from roadgaze.errors import ModelError
    from roadgaze.evaluation.conditions import apply_condition
    from roadgaze.evaluation.images import read_image
    from roadgaze.landmarks.hands.stage import HandStage
    from roadgaze.landmarks.landmarker import Landmarker
    from roadgaze.landmarks.model_store import resolve_model
    from roadgaze.phone.features import FEATURES, frame_vector
    from roadgaze.phone.judge import face_box

    stage = HandStage.from_config(config)
    if stage is None:
        raise ModelError("phone evaluation needs the hand models: run `roadgaze model fetch hands`")
    faces = Landmarker(config.landmarks, resolve_model(config.model), video=False)
    x = np.full((len(truths), len(FEATURES)), np.nan)
    judged = np.zeros(len(truths), bool)
    try:
        for row, truth in enumerate(_progress(truths, progress)):
            try:
                image = read_image(dataset / truth.file)
            except (OSError, ValueError, SourceError):
                continue
            image = apply_condition(condition, image, None, truth.file)
            hands = stage.run(image, None)
            face = faces.detect(image).driver
            box = face_box(face)
            head = (
                (None, None) if face is None else (face.mediapipe_yaw_deg, face.mediapipe_pitch_deg)
            )
            body = hands.body_arrays
            x[row] = frame_vector(hands.hands, box, hands.size, head, body)
            judged[row] = bool(hands.hands) or box is not None or body is not None
    finally:
        stage.close()
        faces.close()
    if np.isnan(x).all():
        raise DatasetError(f"none of the {len(truths)} images under {dataset} could be read")
    return Features(tuple(truths), x, judged)


def _progress(items: Sequence[PhoneTruth], show: bool) -> Iterator[PhoneTruth]:
    if not show:
        yield from items
        return
    from tqdm import tqdm

    yield from tqdm(items, desc="phone", unit="image", leave=False)


def out_of_fold_scores(features: Features, settings: BoostSettings) -> npt.NDArray[np.float64]:
    """Each image's score from a classifier fitted without its driver (NaN: unreadable)."""
    x, y, groups = features.x, features.labels, features.groups
    readable = ~np.isnan(x).any(axis=1)
    scores = np.full(len(y), np.nan)
    drivers = sorted(set(groups[readable]))
    if len(drivers) < 2:
        raise DatasetError("leaving drivers out needs a subject column with two drivers or more")
    for driver in drivers:
        held = readable & (groups == driver)
        train = readable & (groups != driver)
        scores[held] = predict(fit(x[train], y[train], settings), x[held])
    return scores


def threshold_at_fpr(
    scores: npt.NDArray[np.float64], labels: npt.NDArray[np.int_], fpr: float = TARGET_FPR
) -> float:
    """The lowest threshold whose false-positive rate over the negatives is at most `fpr`."""
    negatives = np.sort(scores[(labels == 0) & ~np.isnan(scores)])
    if negatives.size == 0:
        return 0.5
    allowed = int(np.floor(fpr * negatives.size))
    return float(np.nextafter(negatives[negatives.size - allowed - 1], np.inf))


@dataclass(frozen=True, slots=True)
class PhoneReport:
    """Recall, false-positive rates per class and per driver at one threshold."""

    threshold: float
    recall: float
    fpr: float
    per_class: dict[str, float]
    """Class -> the fraction judged phone use (recall for phone classes, FPR for the others)."""
    per_driver_recall: dict[str, float]
    per_driver_fpr: dict[str, float]
    images: int
    judged: float
    held_up: int = 0
    """Images judged phone use by the held-up rule (`roadgaze.phone.held_up`)."""
    held_up_negatives: int = 0
    """Of those, images that are not phone use."""
    extra: dict[str, Any] = field(default_factory=dict)


def score_report(
    features: Features, scores: npt.NDArray[np.float64], threshold: float
) -> PhoneReport:
    """The figures of `scores` at `threshold`; an image that cannot be judged counts as not
    phone use (what the service says for it is 'unknown')."""
    y, classes, groups = features.labels, features.classes, features.groups
    held = held_up_rows(features.x)
    positive = (np.nan_to_num(scores, nan=-1.0) >= threshold) | held
    positive &= features.judged

    def rate(mask: npt.NDArray[np.bool_]) -> float:
        return float(positive[mask].mean()) if mask.any() else float("nan")

    return PhoneReport(
        threshold=threshold,
        recall=rate(y == 1),
        fpr=rate(y == 0),
        per_class={c: rate(classes == c) for c in sorted(set(classes)) if c},
        per_driver_recall={d: rate((groups == d) & (y == 1)) for d in sorted(set(groups)) if d},
        per_driver_fpr={d: rate((groups == d) & (y == 0)) for d in sorted(set(groups)) if d},
        images=len(y),
        judged=float(features.judged.mean()),
        held_up=int(held.sum()),
        held_up_negatives=int((held & (y == 0)).sum()),
    )


def format_report(title: str, report: PhoneReport) -> str:
    """The report as aligned text lines."""
    lines = [
        f"{title}: {report.images} images, judged {report.judged:.1%}, threshold "
        f"{report.threshold:.3f}",
        f"  phone use recall {report.recall:.3f}, false-positive rate {report.fpr:.3f}",
        f"  held up in front (roadgaze's rule): {report.held_up} images, "
        f"{report.held_up_negatives} of them not phone use",
    ]
    for label, value in report.per_class.items():
        kind = "recall" if label in {"c1", "c2", "c3", "c4"} else "FPR"
        name = CLASS_NAMES.get(label, "")
        lines.append(f"  {label:<4} {name:<18} {kind:<6} {value:.3f}")
    recalls = [v for v in report.per_driver_recall.values() if v == v]
    fprs = [v for v in report.per_driver_fpr.values() if v == v]
    if recalls:
        lines.append(
            f"  per driver: recall min {min(recalls):.3f} median {np.median(recalls):.3f} "
            f"max {max(recalls):.3f}; FPR min {min(fprs):.3f} median {np.median(fprs):.3f} "
            f"max {max(fprs):.3f}"
        )
    return "\n".join(lines)


def report_json(report: PhoneReport) -> dict[str, Any]:
    """The report as a JSON-ready dict."""
    return {
        "threshold": report.threshold,
        "recall": report.recall,
        "fpr": report.fpr,
        "per_class": report.per_class,
        "per_driver_recall": report.per_driver_recall,
        "per_driver_fpr": report.per_driver_fpr,
        "images": report.images,
        "judged": report.judged,
        "held_up": report.held_up,
        "held_up_negatives": report.held_up_negatives,
    }
