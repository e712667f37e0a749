"""The landmark stage: pure geometry on synthetic landmarks, then the real MediaPipe model on real
photos (scikit-image's astronaut, shipped by a PyPI package, and Pointing'04 when present)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt
import pytest
from skimage import data as skimage_data

from repo_paths import POINTING04, VIDEOS
from roadgaze.config import LandmarksConfig, load_config
from roadgaze.landmarks import (
    DEFAULT_CHOICE,
    LEFT_EYE_OUTER,
    MOUTH_CORNERS,
    NOSE_TIP,
    NUM_LANDMARKS,
    RIGHT_EYE_OUTER,
    LandmarkChoice,
    MediaPipeLandmarker,
    angles_from_matrix_deg,
    choose_driver,
    features_from_landmarks,
    merge_mirrored,
    roll_from_eyes_deg,
    unmirror,
)
from roadgaze.landmarks.model_store import resolve_model
from roadgaze.pose.geometry import center_ce
from roadgaze.types import FaceFeatures

needs_pointing04 = pytest.mark.skipif(
    not POINTING04.is_dir(), reason=f"evaluation data not found at {POINTING04}"
)


# ---------------------------------------------------------------- pure geometry, no MediaPipe


def synthetic_face(
    center: tuple[float, float] = (200.0, 150.0), nose_offset_px: float = 0.0
) -> npt.NDArray[np.float32]:
    """478 landmarks of an upright face: an oval of points, eyes, mouth, nose."""
    rng = np.random.default_rng(3)
    cx, cy = center
    angles = rng.uniform(0, 2 * np.pi, NUM_LANDMARKS)
    radii = np.sqrt(rng.uniform(0, 1, NUM_LANDMARKS))
    points = np.zeros((NUM_LANDMARKS, 3), np.float32)
    points[:, 0] = cx + 50 * radii * np.cos(angles)
    points[:, 1] = cy + 65 * radii * np.sin(angles)
    points[RIGHT_EYE_OUTER, :2] = (cx - 35, cy - 15)
    points[LEFT_EYE_OUTER, :2] = (cx + 35, cy - 15)
    points[MOUTH_CORNERS[0], :2] = (cx - 20, cy + 35)
    points[MOUTH_CORNERS[1], :2] = (cx + 20, cy + 35)
    # Two far-out points at cheek height fix the boundaries exactly.
    points[234, :2] = (cx - 60, cy)
    points[454, :2] = (cx + 60, cy)
    points[NOSE_TIP, :2] = (cx + nose_offset_px, cy + 10)
    points[4, :2] = (cx + nose_offset_px, cy + 8)
    return points


def rotate(points: npt.NDArray[np.float32], angle_deg: float, pivot: tuple[float, float]) -> Any:
    """Rotate landmarks counter-clockwise as seen on screen (y down) about `pivot`."""
    matrix = cv2.getRotationMatrix2D(pivot, angle_deg, 1.0)
    rotated = points.copy()
    rotated[:, :2] = points[:, :2] @ matrix[:, :2].T + matrix[:, 2]
    return rotated


def test_upright_face_features() -> None:
    features = features_from_landmarks(synthetic_face(nose_offset_px=12.0), (400, 300))
    assert features.roll_deg == pytest.approx(0.0, abs=1e-9)
    assert features.x_left_px == pytest.approx(140.0, abs=1e-4)
    assert features.x_right_px == pytest.approx(260.0, abs=1e-4)
    assert features.x_center_px == pytest.approx(212.0, abs=1e-4)
    assert features.quality == pytest.approx(1.0)
    assert features.landmarks_px.shape == (NUM_LANDMARKS, 3)
    assert features.landmarks_px.dtype == np.float32
    assert features.mediapipe_yaw_deg is None


@pytest.mark.parametrize("angle_deg", [-30.0, -15.0, 7.5, 15.0, 40.0])
def test_roll_is_measured_and_removed(angle_deg: float) -> None:
    upright = features_from_landmarks(synthetic_face(nose_offset_px=9.0))
    tilted_points = rotate(synthetic_face(nose_offset_px=9.0), angle_deg, (321.0, 87.0))
    tilted = features_from_landmarks(tilted_points)
    assert tilted.roll_deg == pytest.approx(angle_deg, abs=1e-4)
    # Translation of all three x by the same amount does not change any yaw.
    shift = tilted.x_left_px - upright.x_left_px
    assert tilted.x_right_px - upright.x_right_px == pytest.approx(shift, abs=1e-3)
    assert tilted.x_center_px - upright.x_center_px == pytest.approx(shift, abs=1e-3)


def test_roll_sign_counter_clockwise_positive() -> None:
    points = synthetic_face()
    points[LEFT_EYE_OUTER, 1] -= 20.0  # person's left eye (image right) higher: CCW on screen
    assert roll_from_eyes_deg(points) > 0


def test_nose_right_of_middle_gives_positive_yaw() -> None:
    features = features_from_landmarks(synthetic_face(nose_offset_px=20.0))
    yaw = center_ce(features.x_left_px, features.x_right_px, features.x_center_px)
    assert yaw > 10.0
    mirrored = features_from_landmarks(synthetic_face(nose_offset_px=-20.0))
    assert center_ce(mirrored.x_left_px, mirrored.x_right_px, mirrored.x_center_px) == (
        pytest.approx(-yaw, abs=1e-6)
    )


def test_band_keeps_only_cheek_height() -> None:
    points = synthetic_face()
    points[10, :2] = (50.0, 60.0)  # far left but above the eyes: outside the band
    band = features_from_landmarks(points)
    assert band.x_left_px == pytest.approx(140.0, abs=1e-4)
    whole = features_from_landmarks(points, choice=LandmarkChoice("all", (NOSE_TIP,)))
    assert whole.x_left_px == pytest.approx(50.0, abs=1e-4)
    pair = features_from_landmarks(points, choice=LandmarkChoice("pair", (NOSE_TIP,), (454, 234)))
    assert (pair.x_left_px, pair.x_right_px) == pytest.approx((140.0, 260.0), abs=1e-4)


def test_default_choice_is_documented_candidate() -> None:
    assert DEFAULT_CHOICE.center_landmarks == (1, 4)
    assert DEFAULT_CHOICE.boundary_landmarks is None
    assert DEFAULT_CHOICE.boundary_band == (0.1, 0.5)


def test_quality_drops_when_cut_by_edge_or_small() -> None:
    cut = features_from_landmarks(synthetic_face(center=(10.0, 150.0)), (400, 300))
    assert 0.2 < cut.quality < 0.8
    small = features_from_landmarks(synthetic_face() * np.float32(0.2), (400, 300))
    assert small.quality == pytest.approx(24.0 / 80.0, abs=0.02)


@pytest.mark.parametrize(
    ("landmarks", "message"),
    [
        (np.zeros((468, 3)), "expected \\(478, 3\\)"),
        (np.zeros((478, 4)), "expected \\(478, 3\\)"),
        (np.full((478, 3), np.nan), "NaN"),
    ],
)
def test_bad_landmarks_raise(landmarks: npt.NDArray[np.float64], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        features_from_landmarks(landmarks)


def _rotation_y(angle_deg: float) -> npt.NDArray[np.float64]:
    a = math.radians(angle_deg)
    matrix = np.eye(4)
    matrix[:3, :3] = [[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]]
    return matrix


def _rotation_x(angle_deg: float) -> npt.NDArray[np.float64]:
    a = math.radians(angle_deg)
    matrix = np.eye(4)
    matrix[:3, :3] = [[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]]
    return matrix


@pytest.mark.parametrize("angle_deg", [-50.0, -10.0, 0.0, 25.0, 70.0])
def test_matrix_angles_closed_form(angle_deg: float) -> None:
    yaw, pitch = angles_from_matrix_deg(_rotation_y(angle_deg))
    assert (yaw, pitch) == pytest.approx((angle_deg, 0.0), abs=1e-9)
    yaw, pitch = angles_from_matrix_deg(_rotation_x(angle_deg))
    assert (yaw, pitch) == pytest.approx((0.0, -angle_deg), abs=1e-9)


def _face_at(x_min: float, width: float) -> FaceFeatures:
    points = np.zeros((NUM_LANDMARKS, 3), np.float32)
    return FaceFeatures(0, 1, 0.5, 0.0, (x_min, 0.0, x_min + width, width), 1.0, points)


@pytest.mark.parametrize(("rule", "expected"), [("largest", 1), ("left", 2), ("right", 0)])
def test_choose_driver(rule: str, expected: int) -> None:
    faces = [_face_at(500, 60), _face_at(250, 120), _face_at(20, 80)]
    assert choose_driver(faces, rule) == expected
    assert choose_driver([], rule) is None


def test_choose_driver_unknown_rule() -> None:
    with pytest.raises(ValueError, match="unknown driver rule"):
        choose_driver([_face_at(0, 10)], "middle")


# ---------------------------------------------------------------- the real MediaPipe model


@pytest.fixture(scope="module")
def model_path() -> Path:
    return resolve_model(load_config(environ={}).model)


@pytest.fixture(scope="module")
def landmarker(model_path: Path) -> Iterator[MediaPipeLandmarker]:
    with MediaPipeLandmarker(LandmarksConfig(), model_path) as detector:
        yield detector


@pytest.fixture(scope="module")
def astronaut() -> npt.NDArray[np.uint8]:
    return np.ascontiguousarray(cv2.cvtColor(skimage_data.astronaut(), cv2.COLOR_RGB2BGR))


def center_ce_of(features: FaceFeatures | None) -> float:
    assert features is not None, "no face found"
    return float(center_ce(features.x_left_px, features.x_right_px, features.x_center_px))


def test_astronaut_face_found(
    landmarker: MediaPipeLandmarker, astronaut: npt.NDArray[np.uint8]
) -> None:
    detection = landmarker.detect(astronaut)
    assert len(detection.faces) == 1
    face = detection.driver
    assert face is not None
    x_min, y_min, x_max, y_max = face.box_px
    # The face is in the upper middle of the 512x512 portrait.
    assert 150 < x_min < 200 and 250 < x_max < 300 and 50 < y_min < 100 and 150 < y_max < 200
    assert face.landmarks_px.shape == (478, 3) and face.landmarks_px.dtype == np.float32
    assert face.quality > 0.9
    assert abs(center_ce_of(face)) < 10.0
    assert face.mediapipe_yaw_deg is not None and abs(face.mediapipe_yaw_deg) < 10.0
    assert abs(face.roll_deg) < 10.0
    # z is in the same pixel scale as x: the face's depth extent is tens of pixels, not < 1.
    assert 20.0 < float(np.ptp(face.landmarks_px[:, 2])) < 200.0


def test_mirrored_image_negates_yaw(
    landmarker: MediaPipeLandmarker, astronaut: npt.NDArray[np.uint8]
) -> None:
    yaw = center_ce_of(landmarker.detect(astronaut).driver)
    mirrored = center_ce_of(landmarker.detect(np.ascontiguousarray(astronaut[:, ::-1])).driver)
    assert mirrored == pytest.approx(-yaw, abs=1.0)


@pytest.mark.parametrize("angle_deg", [15.0, -15.0])
def test_in_plane_rotation_barely_changes_yaw(
    landmarker: MediaPipeLandmarker, astronaut: npt.NDArray[np.uint8], angle_deg: float
) -> None:
    face = landmarker.detect(astronaut).driver
    assert face is not None
    center = (0.5 * (face.box_px[0] + face.box_px[2]), 0.5 * (face.box_px[1] + face.box_px[3]))
    matrix = cv2.getRotationMatrix2D(center, angle_deg, 1.0)
    rotated = cv2.warpAffine(astronaut, matrix, (512, 512), borderMode=cv2.BORDER_REPLICATE)
    turned = landmarker.detect(rotated).driver
    assert turned is not None
    assert abs(center_ce_of(turned) - center_ce_of(face)) < 2.0
    assert turned.roll_deg - face.roll_deg == pytest.approx(angle_deg, abs=3.0)


@pytest.mark.parametrize(
    "convert",
    [
        pytest.param(lambda bgr: cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY), id="grayscale"),
        pytest.param(lambda bgr: cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)[:, :, None], id="gray-hw1"),
        pytest.param(lambda bgr: cv2.cvtColor(bgr, cv2.COLOR_BGR2BGRA), id="4-channel"),
    ],
)
def test_grayscale_and_four_channel_are_converted(
    landmarker: MediaPipeLandmarker, astronaut: npt.NDArray[np.uint8], convert: Any
) -> None:
    reference = center_ce_of(landmarker.detect(astronaut).driver)
    assert center_ce_of(landmarker.detect(convert(astronaut)).driver) == pytest.approx(
        reference, abs=2.0
    )


@pytest.mark.parametrize(
    "image",
    [
        pytest.param(np.full((480, 640, 3), 128, np.uint8), id="blank"),
        pytest.param(np.zeros((8, 8, 3), np.uint8), id="tiny"),
        pytest.param(np.zeros((1, 1), np.uint8), id="one-pixel-gray"),
    ],
)
def test_images_without_a_face(landmarker: MediaPipeLandmarker, image: Any) -> None:
    detection = landmarker.detect(image)
    assert detection.faces == () and detection.driver_index is None and detection.driver is None


@pytest.mark.parametrize(
    ("image", "message"),
    [
        (np.zeros((32, 32, 3), np.float32), "uint8"),
        (np.zeros((32, 32, 5), np.uint8), "grayscale, BGR or BGRA"),
        (np.zeros((32,), np.uint8), "grayscale, BGR or BGRA"),
        (np.zeros((0, 32, 3), np.uint8), "empty image"),
    ],
)
def test_unusable_arrays_raise_value_error(
    landmarker: MediaPipeLandmarker, image: Any, message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        landmarker.detect(image)


def test_image_mode_rejects_timestamps(
    landmarker: MediaPipeLandmarker, astronaut: npt.NDArray[np.uint8]
) -> None:
    with pytest.raises(ValueError, match="IMAGE mode"):
        landmarker.detect(astronaut, 0.0)


def test_video_mode_tracks_with_increasing_timestamps(
    model_path: Path, astronaut: npt.NDArray[np.uint8]
) -> None:
    with MediaPipeLandmarker(LandmarksConfig(), model_path, video=True) as detector:
        yaws = []
        # 0.1 ms apart: distinct t_s that round to the same millisecond must still work.
        for t_s in (0.0, 0.0001, 0.0332, 0.0666):
            yaws.append(center_ce_of(detector.detect(astronaut, t_s).driver))
        assert np.ptp(yaws) < 2.0
        with pytest.raises(ValueError, match="strictly increase"):
            detector.detect(astronaut, 0.0666)
        with pytest.raises(ValueError, match="needs a timestamp"):
            detector.detect(astronaut)
    with pytest.raises(ValueError, match="closed"):
        detector.detect(astronaut, 1.0)


@pytest.mark.parametrize(
    ("rule", "expected_side"), [("largest", "left"), ("left", "left"), ("right", "right")]
)
def test_driver_rule_with_two_faces(
    model_path: Path, astronaut: npt.NDArray[np.uint8], rule: str, expected_side: str
) -> None:
    crop = astronaut[20:260, 120:340]
    canvas = np.full((260, 420, 3), 255, np.uint8)
    canvas[10:250, 0:220] = crop  # larger face on the image's left
    canvas[40:220, 240:405] = cv2.resize(crop, (165, 180))
    with MediaPipeLandmarker(LandmarksConfig(driver=rule), model_path) as detector:  # type: ignore[arg-type]
        detection = detector.detect(canvas)
    assert len(detection.faces) == 2
    driver = detection.driver
    assert driver is not None
    center_x = 0.5 * (driver.box_px[0] + driver.box_px[2])
    assert (center_x < 210) == (expected_side == "left")


def test_from_config_uses_resolver(tmp_path: Path, astronaut: npt.NDArray[np.uint8]) -> None:
    config = load_config(environ={})
    with MediaPipeLandmarker.from_config(config) as detector:
        assert detector.detect(astronaut).driver is not None


# ---------------------------------------------------------------- Pointing'04 (when present)


def _pointing04(name: str) -> npt.NDArray[np.uint8]:
    image = cv2.imread(str(POINTING04 / "images" / "Person01" / name))
    assert image is not None, name
    return np.asarray(image, np.uint8)


@needs_pointing04
def test_frontal_pointing04_image(landmarker: MediaPipeLandmarker) -> None:
    face = landmarker.detect(_pointing04("person01146+0+0.jpg")).driver
    assert face is not None
    assert abs(center_ce_of(face)) < 10.0
    assert face.mediapipe_yaw_deg is not None and abs(face.mediapipe_yaw_deg) < 10.0


@needs_pointing04
@pytest.mark.parametrize(
    ("name", "true_yaw_deg"),
    [("person01144+0-30.jpg", 30.0), ("person01148+0+30.jpg", -30.0)],
)
def test_sign_convention_on_pointing04(
    landmarker: MediaPipeLandmarker, name: str, true_yaw_deg: float
) -> None:
    """File name <tilt><pan>, yaw = -pan: both our yaw and MediaPipe's have the truth's sign."""
    face = landmarker.detect(_pointing04(name)).driver
    assert face is not None and face.mediapipe_yaw_deg is not None
    assert center_ce_of(face) == pytest.approx(true_yaw_deg, abs=12.0)
    assert math.copysign(1.0, face.mediapipe_yaw_deg) == math.copysign(1.0, true_yaw_deg)


@needs_pointing04
@pytest.mark.parametrize(
    ("name", "sign"), [("person01172+30+0.jpg", 1), ("person01120-30+0.jpg", -1)]
)
def test_pitch_sign_on_pointing04(landmarker: MediaPipeLandmarker, name: str, sign: int) -> None:
    face = landmarker.detect(_pointing04(name)).driver
    assert face is not None and face.mediapipe_pitch_deg is not None
    assert face.mediapipe_pitch_deg * sign > 5.0


@needs_pointing04
def test_mirrored_turned_faces_roughly_negate_yaw(landmarker: MediaPipeLandmarker) -> None:
    """On turned faces MediaPipe itself is not exactly mirror-symmetric: over Person01's
    pitch-0 pan series |yaw + yaw(mirrored)| has a median near 1 deg (docs/landmarks.md)."""
    sums = []
    for path in sorted((POINTING04 / "images" / "Person01").glob("person01*+0[+-]*.jpg")):
        image = _pointing04(path.name)
        original = landmarker.detect(image).driver
        mirrored = landmarker.detect(np.ascontiguousarray(image[:, ::-1])).driver
        if original is None or mirrored is None:
            continue
        sums.append(abs(center_ce_of(original) + center_ce_of(mirrored)))
    assert len(sums) >= 20
    assert float(np.median(sums)) < 1.5
    assert max(sums) < 10.0


def test_unmirror_is_an_involution_that_negates_yaw() -> None:
    face = features_from_landmarks(synthetic_face(nose_offset_px=15.0), (400, 300))
    flipped = unmirror(face, 400)
    assert (flipped.x_left_px, flipped.x_right_px) == pytest.approx(
        (400 - face.x_right_px, 400 - face.x_left_px)
    )
    yaw = center_ce(face.x_left_px, face.x_right_px, face.x_center_px)
    assert center_ce(flipped.x_left_px, flipped.x_right_px, flipped.x_center_px) == pytest.approx(
        -yaw, abs=1e-9
    )
    back = unmirror(flipped, 400)
    assert back.box_px == pytest.approx(face.box_px)
    assert back.x_center_px == pytest.approx(face.x_center_px)


def test_merge_mirrored_averages_matched_faces_and_keeps_the_rest() -> None:
    face = features_from_landmarks(synthetic_face(nose_offset_px=10.0), (400, 300))
    # The same face measured in the flipped image with a nose 4 px further out.
    flipped_measurement = unmirror(
        features_from_landmarks(synthetic_face(nose_offset_px=14.0), (400, 300)), 400
    )
    far_away = features_from_landmarks(synthetic_face(center=(60.0, 60.0)), (400, 300))
    merged = merge_mirrored([face], [flipped_measurement, far_away], 400)
    assert len(merged) == 2
    assert merged[0].x_center_px == pytest.approx(212.0, abs=1e-4)
    assert merged[1].box_px == pytest.approx(unmirror(far_away, 400).box_px)
    assert merge_mirrored([face], [], 400) == [face]


def test_mirror_average_is_exactly_symmetric(
    model_path: Path, astronaut: npt.NDArray[np.uint8]
) -> None:
    with MediaPipeLandmarker(LandmarksConfig(mirror_average=True), model_path) as detector:
        yaw = center_ce_of(detector.detect(astronaut).driver)
        mirrored = center_ce_of(detector.detect(np.ascontiguousarray(astronaut[:, ::-1])).driver)
    assert mirrored == pytest.approx(-yaw, abs=1e-6)


def test_largest_rule_keeps_the_previous_driver_among_similar_faces() -> None:
    faces = [_face_at(500, 100), _face_at(100, 104)]
    assert choose_driver(faces, "largest") == 1
    assert choose_driver(faces, "largest", previous_box_px=faces[0].box_px) == 0
    # A clearly larger face (>= 1.25 x the area) takes over.
    bigger = [_face_at(500, 100), _face_at(100, 115)]
    assert choose_driver(bigger, "largest", previous_box_px=bigger[0].box_px) == 1
    # The previous driver is gone: the largest face is chosen afresh.
    assert choose_driver(faces, "largest", previous_box_px=(0.0, 0.0, 20.0, 20.0)) == 1


@pytest.mark.skipif(not VIDEOS.is_dir(), reason=f"evaluation data not found at {VIDEOS}")
def test_driver_stays_the_same_person_in_a_two_person_video(model_path: Path) -> None:
    capture = cv2.VideoCapture(str(VIDEOS / "head-pose-face-detection-female-and-male.gif"))
    sides = []
    with MediaPipeLandmarker(LandmarksConfig(), model_path, video=True) as detector:
        for index in range(56):
            ok, frame = capture.read()
            if not ok:
                break
            detection = detector.detect(frame, index / 12.0)
            assert len(detection.faces) == 2
            driver = detection.driver
            assert driver is not None
            sides.append(0.5 * (driver.box_px[0] + driver.box_px[2]) < frame.shape[1] / 2)
    capture.release()
    assert len(sides) == 56
    assert len(set(sides)) == 1


@pytest.mark.skipif(not VIDEOS.is_dir(), reason=f"evaluation data not found at {VIDEOS}")
def test_video_mode_follows_a_head_sweep(model_path: Path) -> None:
    """The female clip turns from her right (about -55 deg) to her left (about +35 deg)."""
    capture = cv2.VideoCapture(str(VIDEOS / "head-pose-face-detection-female.gif"))
    yaws = []
    with MediaPipeLandmarker(LandmarksConfig(), model_path, video=True) as detector:
        for index in range(23):
            ok, frame = capture.read()
            if not ok:
                break
            yaws.append(center_ce_of(detector.detect(frame, index / 12.0).driver))
    capture.release()
    assert len(yaws) == 23
    assert min(yaws) < -45.0 and max(yaws) > 25.0
    assert int(np.argmin(yaws)) < int(np.argmax(yaws))
