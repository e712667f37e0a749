"""The LiteRT hand engine: the graph's rules against closed forms, and the whole engine against
MediaPipe 0.10.14's own hand graph on real drivers (State Farm development images)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mediapipe_reference import reference_on_drivers
from repo_paths import STATEFARM
from roadgaze.config import load_config
from roadgaze.errors import ModelError
from roadgaze.landmarks.engines.graph import FaceDetection, Rect
from roadgaze.landmarks.hands import graph

SIZE = (640, 480)


def test_transform_rect_shifts_along_the_regions_own_up_axis() -> None:
    upright = graph.transform_rect(Rect(0.5, 0.5, 0.1, 0.2, 0.0), SIZE, 2.0, -0.5)
    assert upright.y_center == pytest.approx(0.4)
    assert upright.width * SIZE[0] == pytest.approx(0.2 * 480 * 2)  # long side squared
    assert upright.height * SIZE[1] == pytest.approx(0.2 * 480 * 2)
    # Turned a quarter clockwise: "up" in the region is +x on the image.
    turned = graph.transform_rect(Rect(0.5, 0.5, 0.1, 0.2, math.pi / 2), SIZE, 1.0, -0.5)
    assert turned.x_center == pytest.approx(0.5 + 0.5 * 0.2 * 480 / 640)
    assert turned.y_center == pytest.approx(0.5, abs=1e-12)


def _upright_hand(x_px: float, y_px: float, scale_px: float) -> np.ndarray:
    """21 points of an open hand, fingers up (y down on the image), in image fractions."""
    points = np.zeros((21, 3))
    points[0] = (0, 0, 0)
    for finger, x in enumerate((-1.2, -0.6, 0.0, 0.6, 1.2)):
        for joint in range(4):
            points[1 + 4 * finger + joint, :2] = (x * (1 + 0.1 * joint), -1 - joint * 0.6)
    points[:, :2] = points[:, :2] * scale_px + (x_px, y_px)
    points[:, 0] /= SIZE[0]
    points[:, 1] /= SIZE[1]
    return points.astype(np.float32)


def test_landmarks_rect_of_an_upright_hand_has_no_rotation_and_turns_with_it() -> None:
    hand = _upright_hand(320, 300, 20)
    rect = graph.landmarks_rect(hand, SIZE)
    assert rect.rotation == pytest.approx(0.0, abs=1e-9)
    assert rect.width * SIZE[0] == pytest.approx(rect.height * SIZE[1])
    sideways = hand.copy()  # the fingers pointing to the image right: a quarter turn clockwise
    px = (hand[:, :2] * SIZE) - (320, 300)
    sideways[:, 0] = (320 - px[:, 1]) / SIZE[0]
    sideways[:, 1] = (300 + px[:, 0]) / SIZE[1]
    assert graph.landmarks_rect(sideways, SIZE).rotation == pytest.approx(math.pi / 2, abs=1e-6)


def test_palm_rect_points_from_wrist_to_fingers() -> None:
    keypoints = np.zeros((7, 2))
    keypoints[0] = (0.5, 0.6)  # wrist below
    keypoints[2] = (0.5, 0.5)  # middle-finger base above: upright, no rotation
    rect = graph.palm_rect(FaceDetection((0.45, 0.5, 0.55, 0.6), keypoints, 0.9), SIZE)
    assert rect.rotation == pytest.approx(0.0, abs=1e-12)
    assert rect.y_center == pytest.approx(0.55 - 0.5 * 0.1)
    assert rect.width * SIZE[0] == pytest.approx(2.6 * max(0.1 * 640, 0.1 * 480))


def test_duplicates_removes_a_repeated_hand_and_keeps_a_distinct_one() -> None:
    one = _upright_hand(200, 300, 20)
    same = one + np.float32(0.002)
    other = _upright_hand(450, 300, 20)
    assert graph.duplicates([one, same, other], SIZE) == {1}
    assert graph.add_detections(
        [Rect(0.5, 0.5, 0.2, 0.2)], [Rect(0.51, 0.5, 0.2, 0.2), Rect(0.1, 0.1, 0.1, 0.1)], 0.5
    ) == [Rect(0.5, 0.5, 0.2, 0.2), Rect(0.1, 0.1, 0.1, 0.1)]


def test_a_corrupt_model_is_one_line_naming_it(tmp_path: Path) -> None:
    from roadgaze.landmarks.hands.engine import HandLandmarker, HandSettings

    bad = tmp_path / "palm_detection_full.tflite"
    bad.write_bytes(b"not a model")
    with pytest.raises(ModelError, match=r"palm_detection_full\.tflite") as caught:
        HandLandmarker(bad, tmp_path / "hand_landmark_full.tflite", HandSettings())
    assert "\n" not in str(caught.value)


def test_a_cache_that_cannot_take_the_models_is_one_line_before_any_download(
    tmp_path: Path,
) -> None:
    """A model cache that cannot be written (here: under a file; in the container image: the
    read-only model folder) is refused before anything is downloaded, so the demo run there
    does not fetch 35 MB to throw away."""
    from roadgaze.config.settings import ModelConfig
    from roadgaze.landmarks.hands.models import fetch_hand_models

    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    config = ModelConfig(cache_dir=blocker / "cache", download_timeout_s=0.001)
    with pytest.raises(ModelError, match=r"the model cache .*cache cannot be made") as caught:
        fetch_hand_models(config)
    assert "\n" not in str(caught.value)


# --- MediaPipe 0.10.14 on real drivers ---------------------------------------------------------


@pytest.fixture(scope="module")
def reference_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, dict, Path]:
    if not (STATEFARM / "ground_truth.csv").is_file():
        pytest.skip(f"no State Farm development images at {STATEFARM}")

    from roadgaze.landmarks.hands.models import fetch_hand_models, model_names
    from roadgaze.landmarks.model_store import default_cache_dir

    config = load_config(environ={}).model
    try:
        fetch_hand_models(config, model_names("full", "full"))
    except ModelError as exc:
        pytest.skip(f"hand models unavailable: {exc}")
    folder = tmp_path_factory.mktemp("hands-reference")
    cache = default_cache_dir(config)
    # 21 images: every class and most drivers
    images, reference = reference_on_drivers(cache, "hands-reference.py", 80, folder)
    return images, reference, cache


def test_litert_hands_equal_mediapipe_0_10_14_on_real_drivers(reference_run: tuple) -> None:
    from roadgaze.landmarks.hands.engine import HandLandmarker, HandSettings

    images, reference, cache = reference_run
    engine = HandLandmarker(
        cache / "palm_detection_full.tflite", cache / "hand_landmark_full.tflite", HandSettings()
    )
    scale = np.array(SIZE, np.float64)
    worst_px, worst_handedness, hands = 0.0, 0.0, 0
    for name, rgb in images.items():
        ours = engine.run(rgb, None)
        theirs = reference[name]
        assert len(ours) == len(theirs["hands"]), name
        for hand, points, handedness in zip(
            ours, theirs["hands"], theirs["handedness"], strict=True
        ):
            error = np.abs((hand.points[:, :2] - np.array(points)[:, :2]) * scale).max()
            worst_px = max(worst_px, float(error))
            worst_handedness = max(worst_handedness, abs(hand.handedness - handedness))
            hands += 1
    assert hands >= 15
    assert worst_px < 0.25  # measured: 0.05 px at most on 44 hands
    assert worst_handedness < 1e-3
