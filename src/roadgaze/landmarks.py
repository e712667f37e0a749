"""MediaPipe FaceLandmarker adapter: faces -> left/right boundary and centre with roll removed.

`features_from_landmarks` is pure numpy and turns MediaPipe's 478 landmarks of one face into the
three inputs of the yaw models (see PAPER.md): the eye line (outer corners 33 and 263) gives the
roll; the landmarks are rotated about the eye midpoint so that the eye line is horizontal; then

- the left and right boundaries are the extreme x of all mesh landmarks (the silhouette of the
  projected mesh) in a horizontal band from 0.1 to 0.5 of the eye-to-mouth distance below the eye
  line (cheek height, below the eyes and above the mouth), and
- the centre is the mean x of the nose tip (1) and the point just above it on the ridge (4),

a choice measured on Pointing'04 subjects 1-10 against the alternatives (docs/landmarks.md).
`MediaPipeLandmarker` runs the model (IMAGE mode for stills, VIDEO mode for streams) and chooses
the driver among several faces by `LandmarksConfig.driver`.

Sign conventions: image x grows right, y down. `roll_deg` > 0 is a counter-clockwise head tilt as
seen in the image. Yaw > 0 is the head turned to the person's own left (ISO 8855), which an
unmirrored camera sees as the nose pointing to the image right.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.config import Config, LandmarksConfig
from roadgaze.types import ClosesOnExit, Detection, FaceFeatures

NUM_LANDMARKS = 478
RIGHT_EYE_OUTER = 33
"""The person's right eye, outer corner (image left for an unmirrored camera)."""
LEFT_EYE_OUTER = 263
"""The person's left eye, outer corner (image right for an unmirrored camera)."""
NOSE_TIP = 1
MOUTH_CORNERS = (61, 291)

FACE_OVAL = (
    10, 338, 297, 332, 284, 251, 389, 356, 454, 323, 361, 288, 397, 365, 379, 378, 400, 377,
    152, 148, 176, 149, 150, 136, 172, 58, 132, 93, 234, 127, 162, 21, 54, 103, 67, 109,
)  # fmt: skip
"""MediaPipe's face-oval landmarks (FaceLandmarksConnections.FACE_LANDMARKS_FACE_OVAL)."""


@dataclass(frozen=True, slots=True)
class LandmarkChoice:
    """Which landmarks give the face boundaries and the centre.

    Boundaries: the extreme (min and max) roll-removed x of `boundary_landmarks` (None: all 478
    landmarks, i.e. the silhouette of the projected mesh), keeping only those whose roll-removed
    height lies in `boundary_band`, measured in units of the eye-to-mouth distance below the eye
    line (0 = eye height, 1 = mouth-corner height; None = no height limit).
    Centre: the mean roll-removed x of `center_landmarks`.
    """

    name: str
    center_landmarks: tuple[int, ...]
    boundary_landmarks: tuple[int, ...] | None = None
    boundary_band: tuple[float, float] | None = None


DEFAULT_CHOICE = LandmarkChoice(
    name="mesh silhouette in band [0.1, 0.5] / nose 1+4",
    center_landmarks=(NOSE_TIP, 4),
    boundary_landmarks=None,
    boundary_band=(0.1, 0.5),
)
"""The measured best choice on Pointing'04 subjects 1-10 together (docs/landmarks.md)."""


_MIDLINE = (168, 6, 197, 195, 5, 4, 1)
CANDIDATE_CHOICES: tuple[LandmarkChoice, ...] = (
    LandmarkChoice("face oval, extreme x / nose tip 1", (NOSE_TIP,), FACE_OVAL),
    LandmarkChoice("face oval, extreme x / nose bridge 168", (168,), FACE_OVAL),
    LandmarkChoice("face oval, extreme x / nose bridge 6", (6,), FACE_OVAL),
    LandmarkChoice("face oval, extreme x / midline mean", _MIDLINE, FACE_OVAL),
    LandmarkChoice("cheeks 234/454 / nose tip 1", (NOSE_TIP,), (234, 454)),
    LandmarkChoice("cheeks 234/454 / nose bridge 168", (168,), (234, 454)),
    LandmarkChoice("temples 127/356 / nose tip 1", (NOSE_TIP,), (127, 356)),
    LandmarkChoice("temples 127/356 / nose bridge 6", (6,), (127, 356)),
    LandmarkChoice("cheeks 93/323 / nose tip 1", (NOSE_TIP,), (93, 323)),
    LandmarkChoice("face oval in band [0, 1] / nose 1+4", (NOSE_TIP, 4), FACE_OVAL, (0.0, 1.0)),
    LandmarkChoice("mesh silhouette, whole face / nose tip 1", (NOSE_TIP,)),
    LandmarkChoice("mesh silhouette in band [0, 1] / nose 1+4", (NOSE_TIP, 4), None, (0.0, 1.0)),
    LandmarkChoice(
        "mesh silhouette in band [0.1, 0.5] / nose tip 1", (NOSE_TIP,), None, (0.1, 0.5)
    ),
    LandmarkChoice(
        "mesh silhouette in band [0.1, 0.5] / nose bridge 168", (168,), None, (0.1, 0.5)
    ),
    LandmarkChoice("mesh silhouette in band [0.1, 0.5] / midline mean", _MIDLINE, None, (0.1, 0.5)),
    DEFAULT_CHOICE,
)
"""The alternatives compared in docs/landmarks.md (`roadgaze eval --compare-landmarks`)."""


def roll_from_eyes_deg(landmarks_px: npt.NDArray[np.floating[Any]]) -> float:
    """Counter-clockwise (as seen in the image) angle of the eye line 33 -> 263, degrees."""
    dx = float(landmarks_px[LEFT_EYE_OUTER, 0] - landmarks_px[RIGHT_EYE_OUTER, 0])
    dy = float(landmarks_px[LEFT_EYE_OUTER, 1] - landmarks_px[RIGHT_EYE_OUTER, 1])
    return math.degrees(math.atan2(-dy, dx))


def remove_roll(
    landmarks_px: npt.NDArray[np.floating[Any]], roll_deg: float
) -> npt.NDArray[np.float64]:
    """(N, 2) x, y rotated about the eye midpoint so that the eye line becomes horizontal."""
    points = np.asarray(landmarks_px[:, :2], dtype=np.float64)
    pivot = 0.5 * (points[RIGHT_EYE_OUTER] + points[LEFT_EYE_OUTER])
    # In y-down image coordinates a counter-clockwise (on screen) roll of r is undone by the
    # matrix [[cos r, -sin r], [sin r, cos r]] applied to (x, y).
    angle = math.radians(roll_deg)
    cos_a, sin_a = math.cos(angle), math.sin(angle)
    rotation = np.array([[cos_a, -sin_a], [sin_a, cos_a]])
    return np.asarray((points - pivot) @ rotation.T + pivot, dtype=np.float64)


def boundaries_and_center(
    upright_px: npt.NDArray[np.float64], choice: LandmarkChoice = DEFAULT_CHOICE
) -> tuple[float, float, float]:
    """x_left, x_right, x_center from roll-removed (N, 2) landmarks under `choice`.

    When fewer than two landmarks fall in the height band (a degenerate face), the band is
    ignored rather than failing.
    """
    x_center = float(np.mean(upright_px[list(choice.center_landmarks), 0]))
    candidates = (
        upright_px
        if choice.boundary_landmarks is None
        else upright_px[list(choice.boundary_landmarks)]
    )
    if choice.boundary_band is not None:
        eye_y = 0.5 * (upright_px[RIGHT_EYE_OUTER, 1] + upright_px[LEFT_EYE_OUTER, 1])
        mouth_y = 0.5 * (upright_px[MOUTH_CORNERS[0], 1] + upright_px[MOUTH_CORNERS[1], 1])
        span = mouth_y - eye_y
        if span > 0:
            low, high = choice.boundary_band
            level = (candidates[:, 1] - eye_y) / span
            in_band = (level >= low) & (level <= high)
            if np.count_nonzero(in_band) >= 2:
                candidates = candidates[in_band]
    return float(candidates[:, 0].min()), float(candidates[:, 0].max()), x_center


def angles_from_matrix_deg(matrix: npt.ArrayLike) -> tuple[float, float]:
    """Yaw and pitch (degrees, project convention) from MediaPipe's facial transformation matrix.

    The matrix maps MediaPipe's canonical face model into camera space; its third column is the
    face's forward (nose) direction in the camera frame, from which yaw (about the vertical axis)
    and pitch (about the horizontal one) follow. Signs verified on Pointing'04 subjects 1-10
    (docs/landmarks.md): a nose pointing to the image right gives yaw > 0, a face looking up
    gives pitch > 0.
    """
    rotation = np.asarray(matrix, dtype=np.float64)[:3, :3]
    yaw_deg = math.degrees(math.atan2(float(rotation[0, 2]), float(rotation[2, 2])))
    pitch_deg = math.degrees(
        math.atan2(float(rotation[1, 2]), math.hypot(float(rotation[0, 2]), float(rotation[2, 2])))
    )
    return yaw_deg, pitch_deg


def _quality(
    landmarks_px: npt.NDArray[np.floating[Any]],
    box_px: tuple[float, float, float, float],
    image_size_px: tuple[int, int] | None,
) -> float:
    """0..1: face width relative to 80 px, times the fraction of landmarks inside the image."""
    width_px = box_px[2] - box_px[0]
    size_score = min(1.0, max(0.0, width_px / 80.0))
    if image_size_px is None:
        return size_score
    width, height = image_size_px
    xy = landmarks_px[:, :2]
    inside = (xy[:, 0] >= 0) & (xy[:, 0] < width) & (xy[:, 1] >= 0) & (xy[:, 1] < height)
    return size_score * float(np.mean(inside))


def features_from_landmarks(
    landmarks_px: npt.ArrayLike,
    image_size_px: tuple[int, int] | None = None,
    transformation_matrix: npt.ArrayLike | None = None,
    choice: LandmarkChoice = DEFAULT_CHOICE,
) -> FaceFeatures:
    """The yaw models' inputs for one face from its (478, 3) landmarks in pixels (numpy only).

    `image_size_px` (width, height) enables the edge term of `quality`; `transformation_matrix`
    (MediaPipe's 4x4) fills `mediapipe_yaw_deg` / `mediapipe_pitch_deg`. Raises ValueError for a
    wrong shape or non-finite landmarks.
    """
    points = np.asarray(landmarks_px, dtype=np.float32)
    if points.ndim != 2 or points.shape[0] != NUM_LANDMARKS or points.shape[1] not in (2, 3):
        raise ValueError(f"expected ({NUM_LANDMARKS}, 3) landmarks, found shape {points.shape}")
    if points.shape[1] == 2:
        points = np.concatenate([points, np.zeros((NUM_LANDMARKS, 1), np.float32)], axis=1)
    if not np.all(np.isfinite(points)):
        raise ValueError("landmarks contain NaN or infinite values")
    roll_deg = roll_from_eyes_deg(points)
    upright = remove_roll(points, roll_deg)
    x_left, x_right, x_center = boundaries_and_center(upright, choice)
    box = (
        float(points[:, 0].min()),
        float(points[:, 1].min()),
        float(points[:, 0].max()),
        float(points[:, 1].max()),
    )
    yaw_mp: float | None = None
    pitch_mp: float | None = None
    if transformation_matrix is not None:
        yaw_mp, pitch_mp = angles_from_matrix_deg(transformation_matrix)
    return FaceFeatures(
        x_left_px=x_left,
        x_right_px=x_right,
        x_center_px=x_center,
        roll_deg=roll_deg,
        box_px=box,
        quality=_quality(points, box, image_size_px),
        landmarks_px=points,
        mediapipe_yaw_deg=yaw_mp,
        mediapipe_pitch_deg=pitch_mp,
    )


DRIVER_SWITCH_AREA_RATIO = 1.25
"""In a stream, the "largest" rule moves to another face only when that face's box is this much
larger than the current driver's; faces of similar size would otherwise swap from frame to frame."""
DRIVER_MATCH_IOU = 0.3
"""Box overlap above which a face in a new frame is taken to be the previous frame's driver."""


def _area(face: FaceFeatures) -> float:
    return (face.box_px[2] - face.box_px[0]) * (face.box_px[3] - face.box_px[1])


def choose_driver(
    faces: Sequence[FaceFeatures],
    rule: str,
    previous_box_px: tuple[float, float, float, float] | None = None,
) -> int | None:
    """Index of the driver among `faces` under `rule`, None when there is no face.

    "largest": the face with the largest bounding-box area (default; the driver sits nearest the
    camera). "left" / "right": the face whose box centre is furthest to the image's left / right,
    i.e. the driver sits on that side of the picture as the camera sees it (for a camera facing a
    left-hand-drive driver from the dashboard centre, the driver appears on the image's right).
    `previous_box_px` (streams): the previous frame's driver box; under "largest" that face stays
    the driver unless another is `DRIVER_SWITCH_AREA_RATIO` times larger.
    """
    if not faces:
        return None
    if rule == "largest":
        areas = [_area(f) for f in faces]
        best = int(np.argmax(areas))
        if previous_box_px is not None:
            overlaps = [_box_iou(f.box_px, previous_box_px) for f in faces]
            kept = int(np.argmax(overlaps))
            if (
                overlaps[kept] >= DRIVER_MATCH_IOU
                and areas[best] < DRIVER_SWITCH_AREA_RATIO * areas[kept]
            ):
                return kept
        return best
    centers = [0.5 * (f.box_px[0] + f.box_px[2]) for f in faces]
    if rule == "left":
        return int(np.argmin(centers))
    if rule == "right":
        return int(np.argmax(centers))
    raise ValueError(f"unknown driver rule '{rule}'; choose largest, left or right")


def _box_iou(a: tuple[float, float, float, float], b: tuple[float, float, float, float]) -> float:
    width = min(a[2], b[2]) - max(a[0], b[0])
    height = min(a[3], b[3]) - max(a[1], b[1])
    if width <= 0 or height <= 0:
        return 0.0
    inter = width * height
    area_a = (a[2] - a[0]) * (a[3] - a[1])
    area_b = (b[2] - b[0]) * (b[3] - b[1])
    return inter / (area_a + area_b - inter)


def unmirror(face: FaceFeatures, image_width_px: int) -> FaceFeatures:
    """A face measured in the horizontally flipped image, expressed in the original image.

    x becomes width - x (so left and right boundaries swap), roll and yaw change sign. The
    landmark array is flipped in x but keeps MediaPipe's indices of the flipped face.
    """
    width = float(image_width_px)
    points = face.landmarks_px.copy()
    points[:, 0] = width - points[:, 0]
    x_min, y_min, x_max, y_max = face.box_px
    return FaceFeatures(
        x_left_px=width - face.x_right_px,
        x_right_px=width - face.x_left_px,
        x_center_px=width - face.x_center_px,
        roll_deg=-face.roll_deg,
        box_px=(width - x_max, y_min, width - x_min, y_max),
        quality=face.quality,
        landmarks_px=points,
        mediapipe_yaw_deg=None if face.mediapipe_yaw_deg is None else -face.mediapipe_yaw_deg,
        mediapipe_pitch_deg=face.mediapipe_pitch_deg,
    )


def _mean(a: float | None, b: float | None) -> float | None:
    return None if a is None or b is None else 0.5 * (a + b)


def merge_mirrored(
    faces: Sequence[FaceFeatures], mirrored_faces: Sequence[FaceFeatures], image_width_px: int
) -> list[FaceFeatures]:
    """Average each face with its measurement in the flipped image (matched by box overlap).

    The result is exactly mirror-symmetric: flipping the input negates every yaw. A face found in
    only one of the two images is kept as found there.
    """
    candidates = [unmirror(face, image_width_px) for face in mirrored_faces]
    merged: list[FaceFeatures] = []
    for face in faces:
        overlaps = [_box_iou(face.box_px, other.box_px) for other in candidates]
        best = int(np.argmax(overlaps)) if overlaps else -1
        if best < 0 or overlaps[best] < 0.3:
            merged.append(face)
            continue
        other = candidates.pop(best)
        merged.append(
            FaceFeatures(
                x_left_px=0.5 * (face.x_left_px + other.x_left_px),
                x_right_px=0.5 * (face.x_right_px + other.x_right_px),
                x_center_px=0.5 * (face.x_center_px + other.x_center_px),
                roll_deg=0.5 * (face.roll_deg + other.roll_deg),
                box_px=tuple(0.5 * (p + q) for p, q in zip(face.box_px, other.box_px, strict=True)),  # type: ignore[arg-type]
                quality=0.5 * (face.quality + other.quality),
                landmarks_px=face.landmarks_px,
                mediapipe_yaw_deg=_mean(face.mediapipe_yaw_deg, other.mediapipe_yaw_deg),
                mediapipe_pitch_deg=_mean(face.mediapipe_pitch_deg, other.mediapipe_pitch_deg),
            )
        )
    return merged + candidates


def to_rgb(image: npt.NDArray[Any]) -> npt.NDArray[np.uint8]:
    """A contiguous RGB uint8 copy of a BGR, BGRA or grayscale image; ValueError otherwise."""
    import cv2

    array = np.asarray(image)
    if array.dtype != np.uint8:
        raise ValueError(f"expected a uint8 image, found dtype {array.dtype}")
    if array.ndim == 3 and array.shape[2] == 1:
        array = array[:, :, 0]
    if array.ndim in (2, 3) and (array.shape[0] < 1 or array.shape[1] < 1):
        raise ValueError(f"empty image of shape {array.shape}")
    if array.ndim == 2:
        rgb = cv2.cvtColor(array, cv2.COLOR_GRAY2RGB)
    elif array.ndim == 3 and array.shape[2] == 3:
        rgb = cv2.cvtColor(array, cv2.COLOR_BGR2RGB)
    elif array.ndim == 3 and array.shape[2] == 4:
        rgb = cv2.cvtColor(array, cv2.COLOR_BGRA2RGB)
    else:
        raise ValueError(f"expected a grayscale, BGR or BGRA image, found shape {array.shape}")
    return np.ascontiguousarray(rgb)


_NATIVE_NOISE = (
    "WARNING: Logging before InitGoogle()",
    "INFO: Created TensorFlow Lite",
    "W0000 ",
    "I0000 ",
)


@contextlib.contextmanager
def _filtered_native_stderr() -> Iterator[None]:
    """Drop MediaPipe's start-up log lines (written by C++ to fd 2); pass every other line on."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):
        yield
        return
    with tempfile.TemporaryFile(mode="w+b") as capture:
        os.dup2(capture.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            capture.seek(0)
            kept = [
                line
                for line in capture.read().decode("utf-8", "replace").splitlines(keepends=True)
                if not line.startswith(_NATIVE_NOISE)
            ]
            if kept:
                sys.stderr.write("".join(kept))
                sys.stderr.flush()


class MediaPipeLandmarker(ClosesOnExit):
    """MediaPipe FaceLandmarker as a `roadgaze.types.LandmarkDetector`; a context manager.

    `video=False`: IMAGE mode, each call independent (`t_s` must be None).
    `video=True`: VIDEO mode, tracking across calls; `t_s` must be given and strictly increase.
    """

    def __init__(
        self,
        landmarks_config: LandmarksConfig,
        model_path: Path,
        video: bool = False,
        choice: LandmarkChoice = DEFAULT_CHOICE,
    ) -> None:
        import mediapipe as mp
        from mediapipe.tasks.python import vision
        from mediapipe.tasks.python.core.base_options import BaseOptions

        from roadgaze.errors import ModelError

        self._mp = mp
        self._config = landmarks_config
        self._video = video
        self._choice = choice
        self._last_ms = -1
        self._last_t_s = -math.inf
        self._driver_box_px: tuple[float, float, float, float] | None = None
        mode = vision.RunningMode.VIDEO if video else vision.RunningMode.IMAGE
        options = vision.FaceLandmarkerOptions(
            base_options=BaseOptions(model_asset_path=str(model_path)),
            running_mode=mode,
            num_faces=landmarks_config.max_faces,
            min_face_detection_confidence=landmarks_config.min_detection_confidence,
            min_face_presence_confidence=landmarks_config.min_presence_confidence,
            min_tracking_confidence=landmarks_config.min_tracking_confidence,
            output_facial_transformation_matrixes=True,
        )
        self._landmarker: Any = None
        self._mirror_landmarker: Any = None
        try:
            with _filtered_native_stderr():
                self._landmarker = vision.FaceLandmarker.create_from_options(options)
                if landmarks_config.mirror_average:
                    self._mirror_landmarker = vision.FaceLandmarker.create_from_options(options)
        except (RuntimeError, ValueError, OSError) as exc:
            raise ModelError(f"cannot load face landmarker model {model_path}: {exc}") from None

    @classmethod
    def from_config(cls, config: Config, video: bool = False) -> MediaPipeLandmarker:
        """A landmarker with the model from `resolve_model` (fetched on first use if allowed)."""
        from roadgaze.model_store import resolve_model

        return cls(config.landmarks, resolve_model(config.model), video=video)

    @property
    def video(self) -> bool:
        return self._video

    def detect(self, image: npt.NDArray[np.uint8], t_s: float | None = None) -> Detection:
        """All faces in one BGR (or grayscale / BGRA) uint8 image and which one is the driver.

        Raises ValueError for an image that is not uint8 2-D/3-D, for `t_s` None in VIDEO mode or
        a float in IMAGE mode, and for a `t_s` earlier than the previous one.
        """
        if self._landmarker is None:
            raise ValueError("landmarker is closed")
        rgb = to_rgb(image)
        timestamp_ms: int | None = None
        if self._video:
            if t_s is None:
                raise ValueError("VIDEO mode needs a timestamp t_s for every frame")
            if not math.isfinite(t_s) or t_s <= self._last_t_s:
                raise ValueError(
                    f"timestamps must strictly increase: {t_s} s after {self._last_t_s} s"
                )
            # MediaPipe needs strictly increasing integer milliseconds.
            timestamp_ms = max(round(t_s * 1000.0), self._last_ms + 1)
            self._last_t_s, self._last_ms = t_s, timestamp_ms
        elif t_s is not None:
            raise ValueError("IMAGE mode takes no timestamp; construct with video=True")
        faces = self._run(self._landmarker, rgb, timestamp_ms)
        if self._mirror_landmarker is not None:
            mirrored = self._run(
                self._mirror_landmarker, np.ascontiguousarray(rgb[:, ::-1]), timestamp_ms
            )
            faces = merge_mirrored(faces, mirrored, rgb.shape[1])
        if not self._video:
            return Detection(tuple(faces), choose_driver(faces, self._config.driver))
        driver_index = choose_driver(faces, self._config.driver, self._driver_box_px)
        self._driver_box_px = None if driver_index is None else faces[driver_index].box_px
        return Detection(faces=tuple(faces), driver_index=driver_index)

    def _run(
        self, landmarker: Any, rgb: npt.NDArray[np.uint8], timestamp_ms: int | None
    ) -> list[FaceFeatures]:
        height, width = rgb.shape[:2]
        mp_image = self._mp.Image(image_format=self._mp.ImageFormat.SRGB, data=rgb)
        if timestamp_ms is None:
            result = landmarker.detect(mp_image)
        else:
            result = landmarker.detect_for_video(mp_image, timestamp_ms)
        faces: list[FaceFeatures] = []
        matrices = result.facial_transformation_matrixes or []
        for index, face in enumerate(result.face_landmarks):
            points = np.array(
                [(p.x * width, p.y * height, p.z * width) for p in face], dtype=np.float32
            )
            matrix = matrices[index] if index < len(matrices) else None
            try:
                faces.append(features_from_landmarks(points, (width, height), matrix, self._choice))
            except ValueError:
                continue
        return faces

    def close(self) -> None:
        if self._landmarker is not None:
            self._landmarker.close()
            self._landmarker = None
        if self._mirror_landmarker is not None:
            self._mirror_landmarker.close()
            self._mirror_landmarker = None
