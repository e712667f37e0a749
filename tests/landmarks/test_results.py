"""FaceLandmarker results read straight from MediaPipe's C result equal the public API's."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import mediapipe as mp
import numpy as np
import pytest
from mediapipe.tasks.python import vision
from mediapipe.tasks.python.core.base_options import BaseOptions
from skimage import data as skimage_data

from roadgaze.config import load_config
from roadgaze.landmarks.model_store import resolve_model
from roadgaze.landmarks.results import run_landmarker, uses_c_results


@pytest.fixture(scope="module")
def model_path() -> Path:
    return resolve_model(load_config(environ={}).model)


def landmarker(model_path: Path, video: bool, faces: int = 2) -> object:
    mode = vision.RunningMode.VIDEO if video else vision.RunningMode.IMAGE
    options = vision.FaceLandmarkerOptions(
        base_options=BaseOptions(model_asset_path=str(model_path)),
        running_mode=mode,
        num_faces=faces,
        output_facial_transformation_matrixes=True,
        output_face_blendshapes=True,
    )
    return vision.FaceLandmarker.create_from_options(options)


def two_faces() -> np.ndarray:
    face = skimage_data.astronaut()[20:260, 120:340]
    canvas = np.full((260, 420, 3), 255, np.uint8)
    canvas[10:250, 0:220] = face
    canvas[40:220, 240:405] = cv2.resize(face, (165, 180))
    return np.ascontiguousarray(canvas)


@pytest.mark.parametrize("video", [False, True], ids=["image", "video"])
def test_direct_and_public_results_are_identical(model_path: Path, video: bool) -> None:
    image = mp.Image(image_format=mp.ImageFormat.SRGB, data=two_faces())
    direct, public = landmarker(model_path, video), landmarker(model_path, video)
    try:
        assert uses_c_results(direct), "this MediaPipe has no ctypes result to read"
        for step in range(3):
            timestamp = 33 * step if video else None
            fast = run_landmarker(direct, image, timestamp)
            slow = run_landmarker(public, image, timestamp, direct=False)
            assert len(fast) == len(slow) == 2
            for (points, matrix, scores), (points_ref, matrix_ref, scores_ref) in zip(
                fast, slow, strict=True
            ):
                assert points.shape == (478, 3) and points.dtype == np.float32
                np.testing.assert_array_equal(points, points_ref)
                assert matrix is not None and matrix_ref is not None
                np.testing.assert_array_equal(matrix, matrix_ref)
                assert scores is not None and len(scores) == 52 and scores == scores_ref
                assert 0.0 <= scores["eyeBlinkLeft"] <= 1.0
            if not video:
                break
    finally:
        direct.close()  # type: ignore[attr-defined]
        public.close()  # type: ignore[attr-defined]


def test_no_face_gives_an_empty_list(model_path: Path) -> None:
    blank = mp.Image(image_format=mp.ImageFormat.SRGB, data=np.full((240, 320, 3), 90, np.uint8))
    detector = landmarker(model_path, video=False)
    try:
        assert run_landmarker(detector, blank, None) == []
        assert run_landmarker(detector, blank, None, direct=False) == []
    finally:
        detector.close()  # type: ignore[attr-defined]


def test_objects_without_the_c_interface_use_the_public_api() -> None:
    class Landmark:
        x, y, z = 0.5, 0.25, -0.125

    class Result:
        def __init__(self) -> None:
            self.face_landmarks = [[Landmark()] * 3]
            self.facial_transformation_matrixes: list[np.ndarray] = []
            self.face_blendshapes: list[object] = []

    class Public:
        def detect(self, image: object) -> Result:
            return Result()

    assert not uses_c_results(Public())
    [(points, matrix, scores)] = run_landmarker(Public(), object(), None)
    np.testing.assert_array_equal(points, np.tile([0.5, 0.25, -0.125], (3, 1)).astype(np.float32))
    assert matrix is None and scores is None


def test_the_c_call_runs_on_the_callers_thread_with_mediapipes_status_check(
    model_path: Path,
) -> None:
    """MediaPipe's own wrapper hands every C call to a thread of its own; `run_landmarker` calls
    the same function on the caller's thread (no hand-over), and a failed status still raises."""
    image = mp.Image(image_format=mp.ImageFormat.SRGB, data=two_faces())
    detector: Any = landmarker(model_path, video=True)
    executor = detector._lib._executor
    submit = executor.submit

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("the call went through MediaPipe's dispatcher thread")

    executor.submit = refuse
    try:
        assert len(run_landmarker(detector, image, 100)) == 2
        with pytest.raises(ValueError, match=r"(?i)timestamp"):
            run_landmarker(detector, image, 100)  # not after the previous timestamp
        assert len(run_landmarker(detector, image, 133)) == 2
    finally:
        executor.submit = submit
        detector.close()
