"""The LiteRT pose engine: the graph's rules against closed forms, and the whole engine against
MediaPipe 0.10.14's own pose graph on real drivers (State Farm development images)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mediapipe_reference import reference_on_drivers
from repo_paths import STATEFARM
from roadgaze.config import load_config
from roadgaze.errors import ModelError
from roadgaze.landmarks.pose import graph

SIZE = (640, 480)


def test_alignment_rect_is_twice_the_span_scaled_and_upright_when_the_body_stands() -> None:
    centre, top = np.array([0.5, 0.6]), np.array([0.5, 0.6 - 100 / 480])
    rect = graph.alignment_rect(centre, top, SIZE)
    assert rect.rotation == pytest.approx(0.0, abs=1e-9)
    assert rect.x_center == pytest.approx(0.5)
    assert rect.y_center == pytest.approx(0.6)
    assert rect.width * SIZE[0] == pytest.approx(2 * 100 * 1.25)
    assert rect.height * SIZE[1] == pytest.approx(2 * 100 * 1.25)


def test_alignment_rect_turns_with_a_body_lying_to_the_right() -> None:
    centre, side = np.array([0.5, 0.5]), np.array([0.5 + 100 / 640, 0.5])
    assert graph.alignment_rect(centre, side, SIZE).rotation == pytest.approx(math.pi / 2)


def test_heatmap_moves_a_point_to_its_peak_and_leaves_a_weak_one() -> None:
    heatmap = np.full((64, 64, 2), -20.0, np.float32)
    heatmap[30, 40, 0] = 20.0  # a sharp peak at column 40, row 30 for point 0
    points = np.array([[41.5 / 64, 31.5 / 64], [10 / 64, 10 / 64]])
    refined = graph.refine_from_heatmap(points, heatmap)
    assert refined[0] == pytest.approx([40 / 64, 30 / 64], abs=1e-6)
    assert refined[1] == pytest.approx(points[1])  # no window reaches 0.5: kept


def test_a_corrupt_pose_model_is_one_line_naming_it(tmp_path: Path) -> None:
    from roadgaze.landmarks.pose.engine import PoseLandmarker, PoseSettings

    bad = tmp_path / "pose_detection.tflite"
    bad.write_bytes(b"not a model")
    with pytest.raises(ModelError, match=r"pose_detection\.tflite") as caught:
        PoseLandmarker(bad, tmp_path / "pose_landmark_full.tflite", PoseSettings())
    assert "\n" not in str(caught.value)


@pytest.fixture(scope="module")
def reference_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, dict, Path]:
    if not (STATEFARM / "ground_truth.csv").is_file():
        pytest.skip(f"no State Farm development images at {STATEFARM}")

    from roadgaze.landmarks.hands.models import fetch_hand_models
    from roadgaze.landmarks.model_store import default_cache_dir
    from roadgaze.landmarks.pose.models import POSE_MODEL_FILES

    config = load_config(environ={}).model
    try:
        fetch_hand_models(config, tuple(POSE_MODEL_FILES))
    except ModelError as exc:
        pytest.skip(f"pose models unavailable: {exc}")
    folder = tmp_path_factory.mktemp("pose-reference")
    cache = default_cache_dir(config)
    # 11 images: most classes and drivers
    images, reference = reference_on_drivers(cache, "pose-reference.py", 160, folder)
    return images, reference, cache


def test_litert_pose_equals_mediapipe_0_10_14_on_real_drivers(reference_run: tuple) -> None:
    from roadgaze.landmarks.pose.engine import PoseLandmarker, PoseSettings
    from roadgaze.landmarks.pose.models import DETECTOR_NAME, LANDMARKS_NAME

    images, reference, cache = reference_run
    engine = PoseLandmarker(cache / DETECTOR_NAME, cache / LANDMARKS_NAME, PoseSettings())
    scale = np.array(SIZE, np.float64)
    worst_px, worst_visibility, bodies = 0.0, 0.0, 0
    for name, rgb in images.items():
        ours = engine.run(rgb, None)
        theirs = reference[name]["landmarks"]
        assert (ours is None) == (theirs is None), name
        if ours is None:
            continue
        theirs = np.array(theirs)
        error = np.abs((ours.points[:, :2] - theirs[:, :2]) * scale).max()
        worst_px = max(worst_px, float(error))
        worst_visibility = max(
            worst_visibility, float(np.abs(ours.visibility - theirs[:, 3]).max())
        )
        bodies += 1
    assert bodies >= 8
    assert worst_px < 1.0  # measured: 0.35 px at most on 8 State Farm images
    assert worst_visibility < 0.01
