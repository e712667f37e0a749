"""MediaPipe's FaceLandmarker as an engine: the reference, and the fallback when LiteRT is missing.

Its C function is called directly and its results read as arrays (`roadgaze.landmarks.results`);
faces are counted with `roadgaze.landmarks.multi_face.FaceCounter` (MediaPipe's FaceDetector on
the bundle's own detector model).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy.typing as npt

from roadgaze.config import LandmarksConfig
from roadgaze.errors import ModelError
from roadgaze.landmarks.multi_face import FaceCounter, detector_model_bytes
from roadgaze.landmarks.native_log import filtered_native_stderr
from roadgaze.landmarks.results import FaceArrays, run_landmarker


class MediaPipeRunner:
    """One MediaPipe FaceLandmarker with `num_faces` faces."""

    def __init__(self, landmarker: Any) -> None:
        self._landmarker = landmarker
        self._started = False

    def run(self, image: Any, timestamp_ms: int | None) -> list[FaceArrays]:
        """The faces in the `mediapipe.Image` `image`; errors are MediaPipe's."""
        if self._started:
            return run_landmarker(self._landmarker, image, timestamp_ms)
        with filtered_native_stderr():  # its first inference logs its set-up on fd 2
            faces = run_landmarker(self._landmarker, image, timestamp_ms)
        self._started = True
        return faces

    def close(self) -> None:
        if self._landmarker is not None:
            with filtered_native_stderr():
                self._landmarker.close()
            self._landmarker = None


class MediaPipeEngine:
    """MediaPipe FaceLandmarkers for `model_path` (IMAGE or VIDEO mode)."""

    name = "mediapipe"

    def __init__(self, config: LandmarksConfig, model_path: Path, video: bool) -> None:
        import mediapipe as mp

        self._mp = mp
        self._config = config
        self._model_path = model_path
        self._video = video

    def image(self, rgb: npt.NDArray[Any]) -> Any:
        """MediaPipe's own copy of the contiguous RGB array."""
        return self._mp.Image(image_format=self._mp.ImageFormat.SRGB, data=rgb)

    def landmarker(self, num_faces: int) -> MediaPipeRunner:
        from mediapipe.tasks.python import vision
        from mediapipe.tasks.python.core.base_options import BaseOptions

        config = self._config
        options = vision.FaceLandmarkerOptions(
            base_options=BaseOptions(model_asset_path=str(self._model_path)),
            running_mode=vision.RunningMode.VIDEO if self._video else vision.RunningMode.IMAGE,
            num_faces=num_faces,
            min_face_detection_confidence=config.min_detection_confidence,
            min_face_presence_confidence=config.min_presence_confidence,
            min_tracking_confidence=config.min_tracking_confidence,
            output_facial_transformation_matrixes=True,
            output_face_blendshapes=True,
        )
        try:
            with filtered_native_stderr():
                return MediaPipeRunner(vision.FaceLandmarker.create_from_options(options))
        except (RuntimeError, ValueError, OSError) as exc:
            raise ModelError(
                f"cannot load face landmarker model {self._model_path}: {exc}"
            ) from None

    def counter(self) -> FaceCounter | None:
        """None when the bundle has no readable detector (every frame then runs `max_faces`)."""
        model = detector_model_bytes(self._model_path)
        if model is None:
            return None
        with filtered_native_stderr():
            return FaceCounter(model, self._config.min_detection_confidence)
