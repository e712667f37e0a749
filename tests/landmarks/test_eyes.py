"""Eye features: the iris model against its own forward model, openness and sides on built
landmarks, the usability rules, the image check, and real MediaPipe on the synthetic photo."""

from __future__ import annotations

import math

import numpy as np
import pytest

from repo_paths import POINTING04
from roadgaze.config import EyesConfig
from roadgaze.landmarks.eye_contrast import (
    eye_checks,
    eye_contrast,
    eye_lid_share,
    eye_sharpness,
    polygon_mask,
)
from roadgaze.landmarks.eyes import (
    BLENDSHAPE_PITCH_PER_DEG,
    BLENDSHAPE_YAW_PER_DEG,
    EYE_LANDMARKS,
    EYEBALL,
    EYES,
    LEFT_EYE,
    RIGHT_EYE,
    EyeIndices,
    blendshape_direction_deg,
    driver_eyes,
    eye_features,
    head_rotation,
    iris_direction_deg,
    swap_sides,
    upright_eye_points,
)
from roadgaze.landmarks.features import remove_roll

WIDTH_PX = 30.0


def built_landmarks(
    head_yaw_deg: float = 0.0,
    head_pitch_deg: float = 0.0,
    eye_yaw_deg: float = 0.0,
    eye_pitch_deg: float = 0.0,
    aperture: float = 0.3,
) -> np.ndarray:
    """478 landmarks whose eye corners, lids and iris centres follow the eyeball model exactly
    (orthographic camera, eye midpoints 90 px apart, eye width 30 px, centred at 320, 240)."""
    rotation = head_rotation(head_yaw_deg, head_pitch_deg)
    points = np.zeros((478, 3))
    e, p = math.radians(eye_yaw_deg), math.radians(eye_pitch_deg)
    gaze = np.array([math.sin(e) * math.cos(p), -math.sin(p), math.cos(e) * math.cos(p)])
    k, lam, mu, b = EYEBALL.k, EYEBALL.lam, EYEBALL.mu, EYEBALL.b
    for eye, centre_x in ((RIGHT_EYE, -45.0), (LEFT_EYE, 45.0)):
        middle = np.array([centre_x, 0.0, 0.0])
        half = eye.lateral * WIDTH_PX / 2
        placed = {
            eye.outer: middle + np.array([half, 0.0, -0.2 * WIDTH_PX]),
            eye.inner: middle + np.array([-half, 0.0, 0.2 * WIDTH_PX]),
            eye.iris_center: middle
            + [eye.lateral * lam * WIDTH_PX, -mu * WIDTH_PX, (b - k) * WIDTH_PX]
            + k * WIDTH_PX * gaze,
        }
        # The lid contour from the outer corner: flat over the middle quarter, tapering to the
        # corners, so the three lid pairs (at 3/8, 1/2, 5/8 of the width) see the full gap.
        uppers = eye.contour[1:8]
        lowers = eye.contour[9:16][::-1]
        for step, (upper, lower) in enumerate(zip(uppers, lowers, strict=True), start=1):
            u = step / 8
            half_gap = 0.5 * aperture * WIDTH_PX * min(1.0, math.sin(math.pi * u) / 0.9238795)
            x = half - 2 * half * u
            placed[upper] = middle + np.array([x, -half_gap, 0.1 * WIDTH_PX])
            placed[lower] = middle + np.array([x, half_gap, 0.1 * WIDTH_PX])
        for index, point in placed.items():
            points[index] = rotation @ point
    points[:, :2] += [320.0, 240.0]
    return points


@pytest.mark.parametrize(
    ("head_yaw", "head_pitch", "eye_yaw", "eye_pitch"),
    [(0, 0, 0, 0), (30, 0, 15, 0), (-30, 0, -15, 10), (0, 20, 10, -10), (40, -15, -20, 5)],
)
def test_iris_model_inverts_its_forward_model(
    head_yaw: float, head_pitch: float, eye_yaw: float, eye_pitch: float
) -> None:
    upright = built_landmarks(head_yaw, head_pitch, eye_yaw, eye_pitch)[:, :2]
    for eye in EYES:
        yaw, pitch = iris_direction_deg(upright, eye, WIDTH_PX, head_yaw, head_pitch)
        assert yaw == pytest.approx(eye_yaw, abs=1e-6)
        assert pitch == pytest.approx(eye_pitch, abs=1e-6)


def test_openness_is_the_lid_gap_over_the_wider_eye() -> None:
    features = eye_features(built_landmarks(aperture=0.25), 0.0)
    assert features.right.openness == pytest.approx(0.25, abs=1e-9)
    assert features.left.openness == pytest.approx(0.25, abs=1e-9)
    assert features.openness == pytest.approx(0.25, abs=1e-9)
    # Turned 30 deg the far eye is narrower in the image; both eyes divide by the wider one, so
    # the far eye does not read wider open than the near one.
    turned = eye_features(built_landmarks(30.0, aperture=0.25), 30.0)
    assert turned.left.width_px < 0.7 * turned.right.width_px
    assert turned.scale_px == turned.right.width_px
    gap_px = 0.25 * WIDTH_PX
    assert turned.right.openness == pytest.approx(gap_px / turned.scale_px, abs=1e-9)
    assert turned.left.openness == pytest.approx(turned.right.openness, abs=1e-9)


def scores(**values: float) -> dict[str, float]:
    names = ("Blink", "LookIn", "LookOut", "LookUp", "LookDown")
    table = {f"eye{n}{side}": 0.0 for n in names for side in ("Left", "Right")}
    table.update(values)
    return table


def test_blendshape_sides_and_gains() -> None:
    # Both eyes looking to the person's own left: the left eye looks out, the right eye in.
    left = scores(eyeLookOutLeft=0.229, eyeLookInRight=0.229, eyeLookDownLeft=0.148)
    assert blendshape_direction_deg(left, LEFT_EYE) == pytest.approx((10.0, -10.0))
    assert blendshape_direction_deg(left, RIGHT_EYE) == pytest.approx((10.0, 0.0))
    assert blendshape_direction_deg({}, LEFT_EYE) is None
    assert (BLENDSHAPE_YAW_PER_DEG, BLENDSHAPE_PITCH_PER_DEG) == (0.0229, 0.0148)


def test_mirroring_the_landmarks_and_swapping_sides_negates_the_eye_yaw() -> None:
    points = built_landmarks()
    table = scores(eyeLookOutLeft=0.3, eyeLookInRight=0.2, eyeBlinkLeft=0.1, eyeLookUpLeft=0.05)
    mirrored = points.copy()
    mirrored[:, 0] = 640.0 - mirrored[:, 0]
    # In the flipped image MediaPipe's indices follow the flipped face: swap the eyes' indices.
    swapped_points = mirrored.copy()
    for right, left in zip(_eye_indices(RIGHT_EYE), _eye_indices(LEFT_EYE), strict=True):
        swapped_points[[right, left]] = mirrored[[left, right]]
    a = eye_features(points, 0.0, blendshapes=table)
    b = eye_features(swapped_points, 0.0, blendshapes=swap_sides(table))
    assert a.yaw_deg is not None and b.yaw_deg is not None
    assert b.yaw_deg == pytest.approx(-a.yaw_deg)
    assert b.pitch_deg == pytest.approx(a.pitch_deg)
    assert swap_sides(swap_sides(table)) == table


def _eye_indices(eye: object) -> list[int]:
    assert eye in EYES
    e = RIGHT_EYE if eye is RIGHT_EYE else LEFT_EYE
    pairs = [i for pair in e.lid_pairs for i in pair]
    return [e.outer, e.inner, e.iris_center, *pairs]


@pytest.mark.parametrize(
    ("head_yaw", "kwargs", "right", "left"),
    [
        (0.0, {}, ("", True, True), ("", True, True)),
        (40.0, {}, ("", True, True), ("far eye", False, False)),
        (-40.0, {}, ("far eye", False, False), ("", True, True)),
        (70.0, {}, ("head turned", False, True), ("head turned", False, False)),
        (85.0, {}, ("head turned", False, False), ("head turned", False, False)),
        (0.0, {"quality": 0.1}, ("low landmark quality", False, False), None),
        (None, {}, ("no head yaw", False, True), None),
    ],
)
def test_which_eyes_are_used(
    head_yaw: float | None,
    kwargs: dict[str, float],
    right: tuple[str, bool, bool],
    left: tuple[str, bool, bool] | None,
) -> None:
    features = eye_features(built_landmarks(head_yaw or 0.0), head_yaw, **kwargs)  # type: ignore[arg-type]
    assert (features.right.reason, features.right.gaze_usable, features.right.closure_usable) == (
        right
    )
    if left is not None:
        assert (features.left.reason, features.left.gaze_usable, features.left.closure_usable) == (
            left
        )


def test_small_eyes_give_nothing() -> None:
    features = eye_features(built_landmarks(), 0.0, config=EyesConfig(min_eye_width_px=40.0))
    assert not features.gaze_available and not features.closure_available
    assert features.reason == "eyes too small" and features.openness is None


def test_flat_eye_openings_with_open_lids_are_hidden_eyes() -> None:
    open_points = built_landmarks(aperture=0.3)
    hidden = eye_features(open_points, 0.0, contrast=(0.02, 0.05))
    assert hidden.occluded and not hidden.gaze_available and hidden.reason == "eyes hidden"
    # A closed lid is flat too: that is a closure to judge, not a lens.
    closed = eye_features(built_landmarks(aperture=0.1), 0.0, contrast=(0.02, 0.05))
    assert not closed.occluded and closed.closure_available
    assert not eye_features(open_points, 0.0, contrast=(0.4, 0.02)).occluded
    assert not eye_features(open_points, 0.0, contrast=(math.nan, math.nan)).occluded
    off = EyesConfig(min_contrast=0.0)
    assert not eye_features(open_points, 0.0, contrast=(0.0, 0.0), config=off).occluded


def test_bad_landmarks_are_refused() -> None:
    with pytest.raises(ValueError, match="expected"):
        eye_features(np.zeros((10, 3)), 0.0)
    points = built_landmarks()
    points[33, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        eye_features(points, 0.0)


def test_polygon_mask_of_a_square() -> None:
    square = np.array([[1.0, 1.0], [5.0, 1.0], [5.0, 5.0], [1.0, 5.0]])
    mask = polygon_mask(square, (8, 8))
    assert mask.sum() == 16 and mask[1, 1] and not mask[0, 0] and not mask[5, 5]


def test_eye_contrast_of_a_drawn_eye_and_a_dark_lens() -> None:
    points = built_landmarks(aperture=0.4)
    image = np.full((480, 640), 150, np.uint8)  # skin
    xs, ys = np.meshgrid(np.arange(640) + 0.5, np.arange(480) + 0.5)
    for eye in EYES:
        polygon = points[list(eye.contour), :2]
        inside = polygon_mask(polygon, (480, 640))
        iris = np.hypot(xs - points[eye.iris_center, 0], ys - points[eye.iris_center, 1]) < 6
        image[inside] = 230  # sclera
        image[inside & iris] = 40
    assert eye_contrast(image, points, RIGHT_EYE) == pytest.approx(190 / 150)
    lens = image.copy()
    lens[200:280, 250:390] = 30
    assert eye_contrast(lens, points, LEFT_EYE) == pytest.approx(0.0)
    assert math.isnan(eye_contrast(image[:10, :10], points, LEFT_EYE))


def test_eye_sharpness_of_a_drawn_eye_blurred_and_flat() -> None:
    import cv2

    points = built_landmarks(aperture=0.4)
    image = np.full((480, 640), 150, np.uint8)  # skin
    for eye in EYES:
        image[polygon_mask(points[list(eye.contour), :2], (480, 640))] = 230
    sharp = eye_sharpness(image, points, RIGHT_EYE)
    # A step of 80 grey levels gives a 3x3 Sobel magnitude of 4 x 80 on its edge pixels.
    assert 1.0 < sharp <= 4 * 80 / 150 + 1e-6
    blurred = cv2.GaussianBlur(image, (0, 0), 4.0)
    assert eye_sharpness(blurred, points, RIGHT_EYE) < EyesConfig().min_sharpness < sharp
    assert eye_sharpness(np.full((480, 640), 150, np.uint8), points, LEFT_EYE) == 0.0
    assert math.isnan(eye_sharpness(image[:10, :10], points, LEFT_EYE))


def test_lid_share_reads_lids_along_the_eye_and_strands_across_it() -> None:
    points = built_landmarks(aperture=0.4)
    image = np.full((480, 640), 150, np.uint8)  # skin
    for eye in EYES:
        image[polygon_mask(points[list(eye.contour), :2], (480, 640))] = 230
    seen = eye_lid_share(image, points, RIGHT_EYE)
    strands = image.copy()
    strands[:, ::4] = 60  # dark hair every 4 px, hanging down across the eyes
    assert seen > 0.5 > EyesConfig().min_lid_share > eye_lid_share(strands, points, LEFT_EYE)
    # The share follows the eye's own axis: the same eye and image turned 90 deg read alike.
    turned = np.ascontiguousarray(np.rot90(image))
    points_turned = points.copy()
    points_turned[:, 0], points_turned[:, 1] = points[:, 1], 640 - points[:, 0]
    assert eye_lid_share(turned, points_turned, RIGHT_EYE) == pytest.approx(seen, abs=0.05)
    assert eye_checks(image, points, RIGHT_EYE)[2] == seen
    assert math.isnan(eye_lid_share(np.full((480, 640), 150, np.uint8), points, LEFT_EYE))


def test_edges_across_both_eyes_are_eyes_hidden_by_strands() -> None:
    points = built_landmarks(aperture=0.3)
    hidden = eye_features(points, 0.0, lid_share=(0.1, 0.15))
    assert hidden.occluded and hidden.occluded_by == "strands" and not hidden.gaze_available
    assert not eye_features(points, 0.0, lid_share=(0.1, 0.5)).occluded  # one eye is seen
    assert not eye_features(points, 0.0, lid_share=(math.nan, math.nan)).occluded
    # One eye measured (the other too small): a glasses rim beside it may read as low.
    assert not eye_features(points, 0.0, lid_share=(0.26, math.nan)).occluded
    lens = eye_features(points, 0.0, contrast=(0.02, 0.05), lid_share=(0.1, 0.1))
    assert lens.occluded and lens.occluded_by == ""  # a flat opening: the lens says it first
    off = EyesConfig(min_lid_share=0.0)
    assert not eye_features(points, 0.0, lid_share=(0.0, 0.0), config=off).occluded


def test_eyes_without_sharp_edges_are_blurred() -> None:
    points = built_landmarks(aperture=0.1)
    assert eye_features(points, 0.0, sharpness=(0.3, 0.5)).blurred
    assert eye_features(points, 0.0, sharpness=(0.3, math.nan)).blurred
    assert not eye_features(points, 0.0, sharpness=(0.3, 0.9)).blurred
    assert not eye_features(points, 0.0, sharpness=(math.nan, math.nan)).blurred
    assert not eye_features(points, 0.0).blurred
    off = EyesConfig(min_sharpness=0.0)
    assert not eye_features(points, 0.0, sharpness=(0.0, 0.0), config=off).blurred


@pytest.fixture(scope="module")
def photo_face() -> object:
    from roadgaze.config import Config
    from roadgaze.landmarks import MediaPipeLandmarker
    from roadgaze.synth import load_photo

    with MediaPipeLandmarker.from_config(Config()) as landmarker:
        return landmarker.detect(load_photo()).driver


def test_mediapipe_gives_blendshapes_and_open_visible_eyes(photo_face: object) -> None:
    from roadgaze.types import FaceFeatures

    assert isinstance(photo_face, FaceFeatures)
    assert photo_face.blendshapes is not None and len(photo_face.blendshapes) == 52
    assert photo_face.eye_contrast is not None and min(photo_face.eye_contrast) > 0.3
    assert photo_face.eye_sharpness is not None
    assert min(photo_face.eye_sharpness) > EyesConfig().min_sharpness
    eyes = driver_eyes(photo_face, 0.0)
    assert eyes is not None and eyes.method == "blendshapes" and not eyes.occluded
    assert eyes.openness is not None and 0.25 < eyes.openness < 0.4
    assert eyes.blink is not None and eyes.blink < 0.2
    assert eyes.yaw_deg is not None and abs(eyes.yaw_deg) < 10


def test_mirror_average_keeps_the_eyes_symmetric() -> None:
    from roadgaze.config import Config, LandmarksConfig
    from roadgaze.landmarks import MediaPipeLandmarker
    from roadgaze.landmarks.model_store import resolve_model
    from roadgaze.synth import load_photo

    image = load_photo()
    config = LandmarksConfig(mirror_average=True)
    with MediaPipeLandmarker(config, resolve_model(Config().model)) as landmarker:
        face = landmarker.detect(image).driver
        flipped = landmarker.detect(np.ascontiguousarray(image[:, ::-1])).driver
    assert face is not None and flipped is not None
    assert face.blendshapes is not None and flipped.blendshapes is not None
    for name in ("eyeLookOutLeft", "eyeLookInRight", "eyeBlinkLeft"):
        assert face.blendshapes[name] == pytest.approx(
            swap_sides(flipped.blendshapes)[name], abs=1e-6
        )


@pytest.mark.skipif(not POINTING04.is_dir(), reason="needs the Pointing'04 set ($ROADGAZE_DATA)")
def test_iris_468_is_the_persons_right_eye_on_a_frontal_still() -> None:
    from roadgaze.config import Config
    from roadgaze.evaluation.images import read_image
    from roadgaze.landmarks import MediaPipeLandmarker

    image = read_image(POINTING04 / "images/Person01/person01146+0+0.jpg")
    with MediaPipeLandmarker.from_config(Config()) as landmarker:
        face = landmarker.detect(image).driver
    assert face is not None
    points = face.landmarks_px[:, :2]
    right_middle = 0.5 * (points[33] + points[133])
    left_middle = 0.5 * (points[263] + points[362])
    assert np.linalg.norm(points[468] - right_middle) < 6
    assert np.linalg.norm(points[473] - left_middle) < 6
    assert right_middle[0] < left_middle[0]  # the person's right eye is on the image's left


@pytest.mark.parametrize("shade", [20, 60])
def test_painted_sunglasses_hide_the_eyes(photo_face: object, shade: int) -> None:
    """MediaPipe still reports open eyes behind dark lenses; the contrast check hides them."""
    import cv2

    from roadgaze.config import Config
    from roadgaze.landmarks import MediaPipeLandmarker
    from roadgaze.synth import load_photo
    from roadgaze.types import FaceFeatures

    assert isinstance(photo_face, FaceFeatures)
    image = load_photo().copy()
    for eye in EYES:
        points = photo_face.landmarks_px[list(eye.contour), :2]
        centre = points.mean(axis=0)
        axes = (0.75 * float(np.ptp(points[:, 0])), 1.2 * float(np.ptp(points[:, 1])) + 6)
        cv2.ellipse(
            image,
            (round(centre[0]), round(centre[1])),
            (round(axes[0]), round(axes[1])),
            0,
            0,
            360,
            (shade, shade, shade),
            -1,
        )
    with MediaPipeLandmarker.from_config(Config()) as landmarker:
        face = landmarker.detect(image).driver
    eyes = driver_eyes(face, 0.0)
    assert eyes is not None and face is not None and face.eye_contrast is not None
    assert max(face.eye_contrast) < 0.15
    assert eyes.occluded and not eyes.gaze_available and not eyes.closure_available


def _iris_by_matrices(
    upright: np.ndarray, eye: EyeIndices, scale: float, head_yaw: float, head_pitch: float
) -> tuple[float, float]:
    """The iris model as its docstring states it, with `head_rotation`'s matrix (the reference
    for the per-frame path, which writes the matrix out in floats)."""
    rotation = head_rotation(head_yaw, head_pitch)
    middle = 0.5 * (upright[eye.outer] + upright[eye.inner])
    centre_in_head = np.array([eye.lateral * EYEBALL.lam, -EYEBALL.mu, EYEBALL.b - EYEBALL.k])
    centre = middle + (rotation @ (centre_in_head * scale))[:2]
    dx, dy = (upright[eye.iris_center] - centre) / (EYEBALL.k * scale)
    planar = math.hypot(dx, dy)
    if planar > 1.0:
        dx, dy, planar = dx / planar, dy / planar, 1.0
    x, y, z = rotation.T @ np.array([dx, dy, math.sqrt(max(0.0, 1.0 - planar * planar))])
    return math.degrees(math.atan2(x, z)), math.degrees(math.atan2(-y, math.hypot(x, z)))


def test_the_iris_model_in_floats_equals_its_matrix_form() -> None:
    rng = np.random.default_rng(3)
    for _ in range(500):
        head_yaw, head_pitch = rng.uniform(-60, 60), rng.uniform(-40, 40)
        upright = built_landmarks(head_yaw, head_pitch, rng.uniform(-30, 30), rng.uniform(-20, 20))[
            :, :2
        ] + rng.normal(0.0, 3.0, (478, 2))  # off the model, some beyond the limb
        scale = rng.uniform(10.0, 40.0)
        for eye in EYES:
            expected = _iris_by_matrices(upright, eye, scale, head_yaw, head_pitch)
            assert iris_direction_deg(upright, eye, scale, head_yaw, head_pitch) == pytest.approx(
                expected, abs=1e-9
            )


def test_the_eye_points_are_remove_roll_of_those_landmarks() -> None:
    rng = np.random.default_rng(5)
    points = rng.uniform(0.0, 640.0, (478, 3)).astype(np.float32)
    for roll in (-35.0, -3.0, 0.0, 12.0, 80.0):
        upright = upright_eye_points(points.astype(np.float64), roll)
        reference = remove_roll(points, roll)
        assert set(upright) == set(EYE_LANDMARKS)
        for index, (x, y) in upright.items():
            assert (x, y) == pytest.approx(tuple(reference[index]), abs=1e-9)
