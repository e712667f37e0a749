"""Pose on still images: the landmark stage, all five yaw models and the service's yaw, pitch,
roll and zone (neutral 0) per file, in worker processes.

`estimate_images` yields one `ImageEstimate` per file, in order; a file that cannot be read gives
an estimate with `error` set, and the others still run.
"""

from __future__ import annotations

import math
import multiprocessing
from collections.abc import Iterator, Mapping, Sequence
from contextlib import closing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.config import Config, LandmarksConfig
from roadgaze.errors import SourceError
from roadgaze.evaluation.eyes import EyeEstimate, still_eyes
from roadgaze.monitor.zones import ZoneMap
from roadgaze.outputs.records import rounded
from roadgaze.pose.estimator import PoseEstimator
from roadgaze.pose.geometry import PAPER_CONSTANTS, YAW_MODELS, FaceModelConstants
from roadgaze.pose.pitch import midline_pitch_deg
from roadgaze.types import Detection, FaceFeatures, LandmarkDetector

MODEL_NAMES: tuple[str, ...] = tuple(YAW_MODELS)
"""The paper's five models, in the paper's order."""


@dataclass(frozen=True, slots=True)
class ImageEstimate:
    """The driver's pose in one image by every model, or why there is none.

    `face` is False when no face was found or the file could not be used (`error` then says
    why). Angles are degrees in the project convention (yaw > 0 = the person's own left, pitch > 0
    = up); None where a model cannot explain the measured geometry. The service's values take
    neutral 0 (a still has no learned neutral pose).
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
    service_yaw_deg: float | None = None
    """The service's yaw (`geometry.model`, full range by default)."""
    pitch_deg: float | None = None
    """The service's pitch (`pose.pitch_model`; neutral 0)."""
    pitch_geometric_deg: float | None = None
    """The vertical CE model's pitch (P4), for comparison."""
    zone: str | None = None
    """The glance zone of the service's yaw and pitch (neutral 0, no previous zone)."""
    eyes: EyeEstimate | None = None
    """The eyes as the service judges them on a still (roadgaze.evaluation.eyes)."""

    @property
    def yaw_deg(self) -> float | None:
        """The service's yaw; Center-CE where it was not computed."""
        if self.service_yaw_deg is not None or not self.face:
            return self.service_yaw_deg
        return self.yaw_deg_by_model.get("center_ce")

    def to_json_dict(self) -> dict[str, Any]:
        """The fields `roadgaze estimate` prints (no landmarks), rounded as `replay` rounds them:
        angles to 3 decimals, pixels to 2."""
        result: dict[str, Any] = {
            "file": self.file,
            "face": self.face,
            "n_faces": self.n_faces,
            "yaw_deg": rounded(self.yaw_deg, 3),
            "models": {name: rounded(self.yaw_deg_by_model.get(name), 3) for name in MODEL_NAMES},
            "pitch_deg": rounded(self.pitch_deg, 3),
            "pitch_geometric_deg": rounded(self.pitch_geometric_deg, 3),
            "zone": self.zone,
            "mediapipe_yaw_deg": rounded(self.mediapipe_yaw_deg, 3),
            "mediapipe_pitch_deg": rounded(self.mediapipe_pitch_deg, 3),
            "x_left": rounded(self.x_left_px, 2),
            "x_right": rounded(self.x_right_px, 2),
            "x_center": rounded(self.x_center_px, 2),
            "roll_deg": rounded(self.roll_deg, 2),
            "quality": rounded(self.quality, 3),
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


@dataclass(frozen=True, slots=True)
class StillPose:
    """The service's pose models for stills: yaw, pitch (neutral 0) and the zone classifier."""

    pose: PoseEstimator
    zones: ZoneMap
    config: Config = field(default_factory=Config)
    """For the eyes: `[eyes]` and the monitor's eye thresholds."""

    @classmethod
    def from_config(cls, config: Config) -> StillPose:
        return cls(PoseEstimator.from_config(config), ZoneMap.from_config(config.monitor), config)

    def estimate(self, face: FaceFeatures) -> tuple[float | None, float | None, str | None]:
        """Yaw, pitch and zone of one face as a first sample with neutral 0."""
        yaw = self.pose.raw_yaw_deg(face)
        pitch = self.pose.raw_pitch_deg(face, 0.0)
        zone = None if yaw is None else self.zones.classify(yaw, pitch or 0.0, None)
        return yaw, pitch, zone


def _geometric_pitch(face: FaceFeatures) -> float | None:
    if face.y_top_px is None or face.y_bottom_px is None or face.y_center_px is None:
        return None
    return _finite_or_none(
        float(midline_pitch_deg(face.y_top_px, face.y_bottom_px, face.y_center_px))
    )


def estimate_from_detection(
    name: str,
    detection: Detection,
    constants: FaceModelConstants = PAPER_CONSTANTS,
    still: StillPose | None = None,
) -> ImageEstimate:
    """The driver's estimate from one detection result (`still`: the service's models, by
    default those of the default configuration with `constants`)."""
    driver = detection.driver
    if driver is None:
        return ImageEstimate(file=name, face=False, n_faces=len(detection.faces))
    if still is None:
        still = StillPose(PoseEstimator(constants=constants), ZoneMap.from_config(Config().monitor))
    service_yaw, pitch, zone = still.estimate(driver)
    return ImageEstimate(
        eyes=still_eyes(driver, service_yaw, pitch, still.config),
        service_yaw_deg=service_yaw,
        pitch_deg=pitch,
        pitch_geometric_deg=_geometric_pitch(driver),
        zone=zone,
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
    still: StillPose | None = None,
) -> ImageEstimate:
    """Run the landmark stage and the pose models on one file; errors become `error`, not raise."""
    label = str(path) if name is None else name
    try:
        image = read_image(path)
        detection = detector.detect(image)
    except (SourceError, ValueError) as exc:
        return ImageEstimate(file=label, face=False, error=str(exc))
    return estimate_from_detection(label, detection, constants, still)


def still_detector(landmarks_config: LandmarksConfig, model_path: Path) -> LandmarkDetector:
    """The landmarker (`landmarks.engine`) in IMAGE mode behind the front end of
    `landmarks.enhance`, as the service runs."""
    from roadgaze.landmarks.front_end import with_front_end
    from roadgaze.landmarks.landmarker import Landmarker

    landmarker = Landmarker(landmarks_config, model_path, video=False)
    return with_front_end(landmarker, landmarks_config.enhance)


_worker: dict[str, Any] = {}


def _close_worker() -> None:
    detector = _worker.pop("detector", None)
    if detector is not None:
        detector.close()


def _init_worker(
    landmarks_config: LandmarksConfig,
    model_path: Path,
    constants: FaceModelConstants,
    config: Config,
) -> None:
    from multiprocessing.util import Finalize

    _worker["detector"] = still_detector(landmarks_config, model_path)
    _worker["constants"] = constants
    _worker["still"] = StillPose.from_config(config)
    # Runs when the worker leaves its loop, while MediaPipe's threads are still alive (an atexit
    # hook would run after they are gone and fail).
    Finalize(None, _close_worker, exitpriority=10)


def _worker_estimate(job: tuple[Path, str]) -> ImageEstimate:
    path, name = job
    return estimate_image(_worker["detector"], path, _worker["constants"], name, _worker["still"])


def estimate_images(
    jobs: Sequence[tuple[Path, str]],
    landmarks_config: LandmarksConfig,
    model_path: Path,
    constants: FaceModelConstants = PAPER_CONSTANTS,
    workers: int = 1,
    progress: bool = False,
    description: str = "images",
    config: Config | None = None,
) -> Iterator[ImageEstimate]:
    """One `ImageEstimate` per (path, display name), in input order.

    `workers` > 1 uses that many processes (spawned, each with its own landmarker); the progress
    bar, when asked for, goes to stderr. `config` chooses the service's yaw and pitch models and
    zones (default: the built-in configuration).
    """
    from tqdm import tqdm

    config = config if config is not None else Config()
    bar = tqdm(
        total=len(jobs),
        desc=description,
        unit="img",
        disable=None if progress else True,
        leave=False,
    )
    try:
        if workers <= 1 or len(jobs) <= 1:
            still = StillPose.from_config(config)
            with closing(still_detector(landmarks_config, model_path)) as detector:
                for path, name in jobs:
                    yield estimate_image(detector, path, constants, name, still)
                    bar.update(1)
            return
        context = multiprocessing.get_context("spawn")
        with context.Pool(
            processes=workers,
            initializer=_init_worker,
            initargs=(landmarks_config, model_path, constants, config),
        ) as pool:
            for estimate in pool.imap(_worker_estimate, jobs, chunksize=8):
                yield estimate
                bar.update(1)
    finally:
        bar.close()
