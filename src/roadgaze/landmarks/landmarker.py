"""MediaPipe FaceLandmarker as a `LandmarkDetector`: IMAGE mode for stills, VIDEO mode for streams.

It measures every face with `features_from_landmarks` and chooses the driver among several faces
by `LandmarksConfig.driver` (see `roadgaze.landmarks.driver`).
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.config import Config, LandmarksConfig
from roadgaze.landmarks.driver import choose_driver, merge_mirrored
from roadgaze.landmarks.eye_contrast import eye_contrast
from roadgaze.landmarks.eyes import LEFT_EYE, RIGHT_EYE
from roadgaze.landmarks.features import DEFAULT_CHOICE, LandmarkChoice, features_from_landmarks
from roadgaze.types import ClosesOnExit, Detection, FaceFeatures


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


def rgb_to_gray(rgb: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
    """The grey image the eye check measures (OpenCV's luma weights)."""
    import cv2

    return np.asarray(cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY), dtype=np.uint8)


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
            output_face_blendshapes=True,
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
        from roadgaze.landmarks.model_store import resolve_model

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
        blendshape_lists = result.face_blendshapes or []
        gray: npt.NDArray[np.uint8] | None = None
        for index, face in enumerate(result.face_landmarks):
            points = np.array(
                [(p.x * width, p.y * height, p.z * width) for p in face], dtype=np.float32
            )
            matrix = matrices[index] if index < len(matrices) else None
            try:
                features = features_from_landmarks(points, (width, height), matrix, self._choice)
            except ValueError:
                continue
            if gray is None:
                gray = rgb_to_gray(rgb)
            scores = blendshape_lists[index] if index < len(blendshape_lists) else None
            faces.append(
                replace(
                    features,
                    blendshapes=None
                    if scores is None
                    else {str(c.category_name): float(c.score) for c in scores},
                    eye_contrast=(
                        eye_contrast(gray, points, RIGHT_EYE),
                        eye_contrast(gray, points, LEFT_EYE),
                    ),
                )
            )
        return faces

    def close(self) -> None:
        if self._landmarker is not None:
            self._landmarker.close()
            self._landmarker = None
        if self._mirror_landmarker is not None:
            self._mirror_landmarker.close()
            self._mirror_landmarker = None
