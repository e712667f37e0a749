"""Yaw estimation on still images and its evaluation against ground truth.

`estimate_images` runs the landmark stage and all five yaw models on image files (optionally in
worker processes, each with its own landmarker) and yields one `ImageEstimate` per file, in
order; a file that cannot be read gives an estimate with `error` set, and the others still run.
`evaluate` scores estimates against a data set's `ground_truth.csv` (columns `file,yaw_deg` and
optionally `pitch_deg`; rows with |pitch_deg| = 90 are skipped) per model and for MediaPipe's own
yaw (the peer), over |yaw| <= 60 deg, over all rows and per 15 deg bin.

Scoring: detection rate = images with a face / images; a model's errors (estimate minus truth)
are taken over the images where a face was found and the model could explain the geometry
(`valid`); MAE, RMSE and median are of those errors.
"""

from __future__ import annotations

import csv
import json
import logging
import math
import multiprocessing
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.config import LandmarksConfig
from roadgaze.errors import DatasetError, SourceError
from roadgaze.geometry import PAPER_CONSTANTS, YAW_MODELS, FaceModelConstants, FloatArray
from roadgaze.landmarks import DEFAULT_CHOICE, LandmarkChoice, boundaries_and_center, remove_roll
from roadgaze.types import Detection, LandmarkDetector

log = logging.getLogger(__name__)

MODEL_NAMES: tuple[str, ...] = tuple(YAW_MODELS)
"""The paper's five models, in the paper's order."""
PEER = "mediapipe"
"""MediaPipe's own yaw from its facial transformation matrix, the peer we compare against."""
METHODS: tuple[str, ...] = (*MODEL_NAMES, PEER)
METHOD_LABELS: Mapping[str, str] = {
    "cylindrical": "Cylindrical",
    "ellipsoidal": "Ellipsoidal",
    "ce": "CE",
    "center_ce": "Center-CE",
    "boundary_ce": "Boundary-CE",
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
)


@dataclass(frozen=True, slots=True)
class ImageEstimate:
    """The driver's yaw in one image by every model, or why there is none.

    `face` is False when no face was found or the file could not be used (`error` then says
    why). Yaw values are degrees in the project convention; None where a model cannot explain
    the measured geometry.
    """

    file: str
    face: bool
    n_faces: int = 0
    yaw_deg_by_model: Mapping[str, float | None] = field(default_factory=dict)
    mediapipe_yaw_deg: float | None = None
    mediapipe_pitch_deg: float | None = None
    x_left_px: float | None = None
    x_right_px: float | None = None
    x_center_px: float | None = None
    roll_deg: float | None = None
    quality: float | None = None
    error: str | None = None
    landmarks_px: npt.NDArray[np.float32] | None = None
    """The driver's (478, 3) landmarks, kept for re-scoring other landmark choices."""

    @property
    def yaw_deg(self) -> float | None:
        """Center-CE, the paper's best model."""
        return self.yaw_deg_by_model.get("center_ce")

    def to_json_dict(self) -> dict[str, Any]:
        """The fields `roadgaze estimate` prints (no landmarks)."""
        result: dict[str, Any] = {
            "file": self.file,
            "face": self.face,
            "n_faces": self.n_faces,
            "yaw_deg": self.yaw_deg,
            "models": {name: self.yaw_deg_by_model.get(name) for name in MODEL_NAMES},
            "mediapipe_yaw_deg": self.mediapipe_yaw_deg,
            "mediapipe_pitch_deg": self.mediapipe_pitch_deg,
            "x_left": self.x_left_px,
            "x_right": self.x_right_px,
            "x_center": self.x_center_px,
            "roll_deg": self.roll_deg,
            "quality": self.quality,
        }
        if self.error is not None:
            result["error"] = self.error
        return result


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


def yaw_by_model(
    x_left_px: float,
    x_right_px: float,
    x_center_px: float,
    constants: FaceModelConstants = PAPER_CONSTANTS,
) -> dict[str, float | None]:
    """Every model's yaw in degrees (None where the model cannot explain the geometry)."""
    return {
        name: _finite_or_none(float(model(x_left_px, x_right_px, x_center_px, constants)))
        for name, model in YAW_MODELS.items()
    }


def read_image(path: Path) -> npt.NDArray[np.uint8]:
    """An image file as uint8 grayscale or BGR, EXIF orientation applied; SourceError if unusable.

    16-bit images are scaled to 8 bits; an alpha channel is dropped.
    """
    import cv2

    if not path.exists():
        raise SourceError(f"{path}: file not found")
    if not path.is_file():
        raise SourceError(f"{path}: not a regular file")
    # ANYCOLOR | ANYDEPTH keeps grayscale and 16-bit data and applies the EXIF orientation
    # (IMREAD_UNCHANGED would ignore it and hand MediaPipe a sideways phone photo).
    decoded = cv2.imread(str(path), cv2.IMREAD_ANYCOLOR | cv2.IMREAD_ANYDEPTH)
    if decoded is None or decoded.size == 0:
        raise SourceError(f"{path}: cannot decode as an image (corrupt or unsupported format)")
    image: npt.NDArray[Any] = np.asarray(decoded)
    if image.dtype == np.uint16:
        image = (image // 256).astype(np.uint8)
    elif image.dtype != np.uint8:
        low, high = float(np.nanmin(image)), float(np.nanmax(image))
        image = (255.0 * (image - low) / max(high - low, 1e-12)).astype(np.uint8)
    if image.ndim == 3 and image.shape[2] not in (1, 3, 4):
        raise SourceError(f"{path}: unsupported image with {image.shape[2]} channels")
    return np.asarray(image, dtype=np.uint8)


def estimate_from_detection(
    name: str, detection: Detection, constants: FaceModelConstants = PAPER_CONSTANTS
) -> ImageEstimate:
    """The driver's estimate from one detection result."""
    driver = detection.driver
    if driver is None:
        return ImageEstimate(file=name, face=False, n_faces=len(detection.faces))
    return ImageEstimate(
        file=name,
        face=True,
        n_faces=len(detection.faces),
        yaw_deg_by_model=yaw_by_model(
            driver.x_left_px, driver.x_right_px, driver.x_center_px, constants
        ),
        mediapipe_yaw_deg=driver.mediapipe_yaw_deg,
        mediapipe_pitch_deg=driver.mediapipe_pitch_deg,
        x_left_px=driver.x_left_px,
        x_right_px=driver.x_right_px,
        x_center_px=driver.x_center_px,
        roll_deg=driver.roll_deg,
        quality=driver.quality,
        landmarks_px=driver.landmarks_px,
    )


def estimate_image(
    detector: LandmarkDetector,
    path: Path,
    constants: FaceModelConstants = PAPER_CONSTANTS,
    name: str | None = None,
) -> ImageEstimate:
    """Run the landmark stage and the yaw models on one file; errors become `error`, not raise."""
    label = str(path) if name is None else name
    try:
        image = read_image(path)
        detection = detector.detect(image)
    except (SourceError, ValueError) as exc:
        return ImageEstimate(file=label, face=False, error=str(exc))
    return estimate_from_detection(label, detection, constants)


_worker: dict[str, Any] = {}


def _close_worker() -> None:
    detector = _worker.pop("detector", None)
    if detector is not None:
        detector.close()


def _init_worker(
    landmarks_config: LandmarksConfig, model_path: Path, constants: FaceModelConstants
) -> None:
    from multiprocessing.util import Finalize

    from roadgaze.landmarks import MediaPipeLandmarker

    _worker["detector"] = MediaPipeLandmarker(landmarks_config, model_path, video=False)
    _worker["constants"] = constants
    # Runs when the worker leaves its loop, while MediaPipe's threads are still alive (an atexit
    # hook would run after they are gone and fail).
    Finalize(None, _close_worker, exitpriority=10)


def _worker_estimate(job: tuple[Path, str]) -> ImageEstimate:
    path, name = job
    return estimate_image(_worker["detector"], path, _worker["constants"], name)


def estimate_images(
    jobs: Sequence[tuple[Path, str]],
    landmarks_config: LandmarksConfig,
    model_path: Path,
    constants: FaceModelConstants = PAPER_CONSTANTS,
    workers: int = 1,
    progress: bool = False,
    description: str = "images",
) -> Iterator[ImageEstimate]:
    """One `ImageEstimate` per (path, display name), in input order.

    `workers` > 1 uses that many processes (spawned, each with its own landmarker); the progress
    bar, when asked for, goes to stderr.
    """
    from tqdm import tqdm

    bar = tqdm(total=len(jobs), desc=description, unit="img", disable=not progress, leave=False)
    try:
        if workers <= 1 or len(jobs) <= 1:
            from roadgaze.landmarks import MediaPipeLandmarker

            with MediaPipeLandmarker(landmarks_config, model_path, video=False) as detector:
                for path, name in jobs:
                    yield estimate_image(detector, path, constants, name)
                    bar.update(1)
            return
        context = multiprocessing.get_context("spawn")
        with context.Pool(
            processes=workers,
            initializer=_init_worker,
            initargs=(landmarks_config, model_path, constants),
        ) as pool:
            for estimate in pool.imap(_worker_estimate, jobs, chunksize=8):
                yield estimate
                bar.update(1)
    finally:
        bar.close()


@dataclass(frozen=True, slots=True)
class GroundTruth:
    """One labelled image of a data set."""

    file: str
    yaw_deg: float
    pitch_deg: float | None = None


def load_ground_truth(dataset_dir: Path) -> tuple[list[GroundTruth], int]:
    """Rows of `<dataset_dir>/ground_truth.csv` and how many were skipped for |pitch| = 90.

    Raises `DatasetError` for a missing folder or file, missing columns or non-numeric values.
    """
    csv_path = dataset_dir / "ground_truth.csv"
    if not dataset_dir.is_dir():
        raise DatasetError(f"{dataset_dir}: not a folder; pass a folder with ground_truth.csv")
    if not csv_path.is_file():
        raise DatasetError(f"{csv_path} not found; the folder needs a ground_truth.csv")
    rows: list[GroundTruth] = []
    skipped = 0
    try:
        with csv_path.open(newline="", encoding="utf-8") as stream:
            reader = csv.DictReader(stream)
            columns = set(reader.fieldnames or [])
            if not {"file", "yaw_deg"} <= columns:
                raise DatasetError(
                    f"{csv_path}: needs columns file,yaw_deg; found {','.join(sorted(columns))}"
                )
            for line, row in enumerate(reader, start=2):
                try:
                    yaw_deg = float(row["yaw_deg"])
                    pitch_text = (row.get("pitch_deg") or "").strip()
                    pitch_deg = float(pitch_text) if pitch_text else None
                except ValueError:
                    raise DatasetError(
                        f"{csv_path}:{line}: yaw_deg/pitch_deg must be numbers, found "
                        f"{row.get('yaw_deg')!r}/{row.get('pitch_deg')!r}"
                    ) from None
                if not row["file"]:
                    raise DatasetError(f"{csv_path}:{line}: empty file name")
                if pitch_deg is not None and abs(pitch_deg) == 90.0:
                    skipped += 1
                    continue
                rows.append(GroundTruth(row["file"], yaw_deg, pitch_deg))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise DatasetError(f"cannot read {csv_path}: {exc}") from None
    if not rows:
        raise DatasetError(f"{csv_path}: no usable rows")
    return rows, skipped


@dataclass(frozen=True, slots=True)
class ErrorStats:
    """Errors (estimate minus truth, degrees) of one method over a set of images."""

    n_images: int
    n_faces: int
    n_valid: int
    mae_deg: float
    rmse_deg: float
    median_deg: float
    bias_deg: float

    @property
    def detection_rate(self) -> float:
        return self.n_faces / self.n_images if self.n_images else math.nan

    @property
    def valid_rate(self) -> float:
        return self.n_valid / self.n_images if self.n_images else math.nan

    def to_json_dict(self) -> dict[str, Any]:
        return {
            "n_images": self.n_images,
            "n_faces": self.n_faces,
            "n_valid": self.n_valid,
            "detection_rate": _json_float(self.detection_rate),
            "valid_rate": _json_float(self.valid_rate),
            "mae_deg": _json_float(self.mae_deg),
            "rmse_deg": _json_float(self.rmse_deg),
            "median_abs_error_deg": _json_float(self.median_deg),
            "bias_deg": _json_float(self.bias_deg),
        }


def _json_float(value: float) -> float | None:
    return round(value, 4) if math.isfinite(value) else None


def error_stats(
    true_deg: FloatArray, estimate_deg: FloatArray, face: npt.NDArray[np.bool_]
) -> ErrorStats:
    """Statistics of `estimate - true` where finite; `face` marks images with a face."""
    valid = np.isfinite(estimate_deg) & face
    errors = estimate_deg[valid] - true_deg[valid]
    if errors.size == 0:
        mae = rmse = median = bias = math.nan
    else:
        mae = float(np.mean(np.abs(errors)))
        rmse = float(np.sqrt(np.mean(errors**2)))
        median = float(np.median(np.abs(errors)))
        bias = float(np.mean(errors))
    return ErrorStats(
        n_images=int(true_deg.size),
        n_faces=int(np.count_nonzero(face)),
        n_valid=int(errors.size),
        mae_deg=mae,
        rmse_deg=rmse,
        median_deg=median,
        bias_deg=bias,
    )


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
    )


def _fmt(value: float, digits: int = 2) -> str:
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
                f"{_fmt(100 * s.detection_rate, 1):>6} {_fmt(100 * s.valid_rate, 1):>7} "
                f"{_fmt(s.mae_deg):>6} {_fmt(s.rmse_deg):>6} {_fmt(s.median_deg):>7} "
                f"{_fmt(s.bias_deg):>6}"
            )
        lines.append("")
    lines.append("MAE (deg) per 15 deg bin of true yaw (det% = face found):")
    bin_header = f"{'yaw':>5} {'n':>5} {'det%':>6} " + " ".join(
        f"{METHOD_LABELS[m][:11]:>11}" for m in METHODS
    )
    lines.append(bin_header)
    lines.append("-" * len(bin_header))
    for b in report.bins:
        first = b.stats[MODEL_NAMES[0]]
        lines.append(
            f"{b.center_deg:>5.0f} {first.n_images:>5} {_fmt(100 * first.detection_rate, 1):>6} "
            + " ".join(f"{_fmt(b.stats[m].mae_deg):>11}" for m in METHODS)
        )
    if report.refit is not None:
        lines.append("")
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
                + [cell(e.mediapipe_yaw_deg)]
            )


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
    figure, axes = plt.subplots(2, 3, figsize=(13, 8.5), sharex=True, sharey=True)
    limit = max(90.0, float(np.max(np.abs(scored.true_yaw_deg))))
    for axis, method in zip(axes.ravel(), METHODS, strict=True):
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
        axis.set_title(f"{METHOD_LABELS[method]} (MAE |yaw|<=60: {_fmt(mae)} deg)")
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


def rescore_landmark_choice(
    estimates: Sequence[ImageEstimate], choice: LandmarkChoice, constants: FaceModelConstants
) -> list[ImageEstimate]:
    """The estimates recomputed from the stored driver landmarks under another landmark choice."""
    from dataclasses import replace

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
            f"| {choice.name}{marker} | {_fmt(center.mae_deg)} | "
            f"{_fmt(100 * center.valid_rate, 1)} | "
            + " | ".join(_fmt(stats[m].mae_deg) for m in MODEL_NAMES if m != "center_ce")
            + " |"
        )
    return "\n".join(lines)


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
