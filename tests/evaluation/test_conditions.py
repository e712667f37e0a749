"""The condition suite's transforms: seeded, documented effects, on a synthetic face-sized scene."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from roadgaze.evaluation.conditions import (
    CLEAN,
    CONDITIONS,
    NOSE_RIDGE,
    SEED,
    apply_condition,
    bright_glare,
    condition_names,
    condition_parameters,
    dark_cabin,
    face_mask,
    ir_grey,
    jpeg_compression,
    low_resolution,
    motion_blur,
    parse_condition,
    sunglasses,
)
from roadgaze.landmarks.eye_landmarks import LEFT_EYE, RIGHT_EYE
from roadgaze.landmarks.features import FACE_OVAL, NOSE_TIP


@pytest.fixture(scope="module")
def scene() -> np.ndarray:
    """A 288x384 BGR image with texture and a spread of levels."""
    rng = np.random.default_rng(5)
    ramp = np.linspace(30, 220, 384)[None, :, None] * np.ones((288, 1, 3))
    return np.clip(ramp + rng.normal(0, 20, (288, 384, 3)), 0, 255).astype(np.uint8)


@pytest.fixture(scope="module")
def landmarks() -> np.ndarray:
    """A face oval from x 140 to 260, y 60 to 240, eyes at y 120 (corner distance 30 px), the
    nose ridge at y 140 and its tip at y 160."""
    points = np.zeros((478, 3), np.float32)
    points[:, :2] = (200, 150)
    angles = np.linspace(0, 2 * np.pi, len(FACE_OVAL), endpoint=False)
    points[list(FACE_OVAL), 0] = 200 + 60 * np.sin(angles)
    points[list(FACE_OVAL), 1] = 150 - 90 * np.cos(angles)
    points[NOSE_RIDGE, :2], points[NOSE_TIP, :2] = (200, 140), (200, 160)
    points[RIGHT_EYE.outer, :2], points[RIGHT_EYE.inner, :2] = (160, 120), (190, 120)
    points[LEFT_EYE.inner, :2], points[LEFT_EYE.outer, :2] = (210, 120), (240, 120)
    return points


def test_every_condition_is_seeded_by_file_and_leaves_its_input(
    scene: np.ndarray, landmarks: np.ndarray
) -> None:
    before = scene.copy()
    for name in CONDITIONS:
        first = apply_condition(name, scene, landmarks, "a.jpg")
        assert first.dtype == np.uint8
        np.testing.assert_array_equal(first, apply_condition(name, scene, landmarks, "a.jpg"))
        assert not np.array_equal(first, scene)
    np.testing.assert_array_equal(scene, before)
    noisy = ("ir_grey", "dark", "sunglasses", "mask")
    for name in noisy:  # another file, other noise
        assert not np.array_equal(
            apply_condition(name, scene, landmarks, "a.jpg"),
            apply_condition(name, scene, landmarks, "b.jpg"),
        )
    assert apply_condition(CLEAN, scene, None, "a.jpg") is scene


def test_ir_grey_is_single_channel_flat_and_noisy(scene: np.ndarray) -> None:
    out = ir_grey(scene, np.random.default_rng(0), noise_std=0.0)
    grey = scene.mean(axis=2)
    assert out.ndim == 2 and out.shape == scene.shape[:2]
    assert out.mean() == pytest.approx(120.0, abs=1.0)
    assert out.std() == pytest.approx(0.4 * grey.std(), rel=0.05)
    noisy = ir_grey(scene, np.random.default_rng(0)).astype(float)
    assert (noisy - out).std() == pytest.approx(6.0, rel=0.1)


def test_dark_and_glare_move_the_levels(scene: np.ndarray) -> None:
    dark = dark_cabin(scene, np.random.default_rng(0), noise_std=0.0)
    assert dark.shape == scene.shape
    assert dark.mean() == pytest.approx(0.15 * scene.mean(), abs=0.6)
    bright = bright_glare(scene, np.random.default_rng(0), spot_level=0.0)
    expected = np.clip(scene * 1.3 + 40.0, 0, 255)
    assert np.abs(bright - expected).max() <= 1.0
    assert bright_glare(scene, np.random.default_rng(0)).mean() > bright.mean()


def test_blur_compression_and_resolution(scene: np.ndarray, landmarks: np.ndarray) -> None:
    blurred = motion_blur(scene, np.random.default_rng(0))
    assert blurred.shape == scene.shape
    assert np.abs(np.diff(blurred.astype(float), axis=1)).mean() < (
        0.5 * np.abs(np.diff(scene.astype(float), axis=1)).mean()
    )
    compressed = jpeg_compression(scene, np.random.default_rng(0))
    assert compressed.shape == scene.shape and not np.array_equal(compressed, scene)
    small = low_resolution(scene, np.random.default_rng(0), landmarks)
    assert small.shape == (144, 192, 3)  # a 120 px face scaled to 60 px: half size
    fixed = low_resolution(scene, np.random.default_rng(0), None)  # box 128 px wide
    assert fixed.shape[1] == round(384 * 60 / 128)
    grey = ir_grey(scene, np.random.default_rng(0))
    assert low_resolution(grey, np.random.default_rng(0), landmarks).shape == (144, 192)


def test_sunglasses_cover_the_eyes_only(scene: np.ndarray, landmarks: np.ndarray) -> None:
    out = sunglasses(scene, np.random.default_rng(0), landmarks).astype(float)
    changed = np.abs(out - scene).max(axis=2) > 0
    ys, xs = np.nonzero(changed)
    assert ys.min() >= 100 and ys.max() <= 140
    assert xs.min() >= 130 and xs.max() <= 270
    assert out[120, 175].mean() < 40 and out[120, 225].mean() < 40  # the lens centres
    no_face = sunglasses(scene, np.random.default_rng(0), None)
    assert no_face[int(0.2 * 288 + 0.4 * 0.55 * 288), int(384 / 3 + 0.3 * 128)].mean() < 40


def test_mask_covers_the_lower_face(scene: np.ndarray, landmarks: np.ndarray) -> None:
    out = face_mask(scene, np.random.default_rng(0), landmarks).astype(float)
    changed = np.abs(out - scene).max(axis=2) > 0
    ys, _ = np.nonzero(changed)
    assert ys.min() >= 140 - 2 and ys.max() <= 241
    assert out[200, 200].mean() == pytest.approx(215.0, abs=20.0)
    assert not changed[:100].any()


def test_condition_names() -> None:
    assert condition_names([]) == ["clean"]
    assert condition_names(["mask", "dark"]) == ["clean", "dark", "mask"]
    assert condition_names(["all"]) == ["clean", *CONDITIONS]
    with pytest.raises(ValueError, match=r"unknown condition 'fog'.*ir_grey"):
        condition_names(["fog"])


def test_a_condition_takes_other_values_for_its_parameters(scene: np.ndarray) -> None:
    """`ir_grey:noise_std=9,contrast=0.3` is `ir_grey` with those keyword values and the same
    noise seed; the suite's values are the functions' defaults."""
    assert parse_condition("ir_grey") == ("ir_grey", {})
    name, parameters = parse_condition("ir_grey:noise_std=9,contrast=0.3")
    assert (name, parameters) == ("ir_grey", {"noise_std": 9.0, "contrast": 0.3})
    assert parse_condition("motion_blur:length_px=21") == ("motion_blur", {"length_px": 21})
    assert condition_parameters("dark") == {"gain": 0.15, "noise_std": 3.0}
    harder = apply_condition("ir_grey:noise_std=9,contrast=0.3", scene, None, "a.jpg")
    key = zlib.crc32(b"ir_grey\0a.jpg")
    expected = ir_grey(scene, np.random.default_rng([SEED, key]), noise_std=9.0, contrast=0.3)
    np.testing.assert_array_equal(harder, expected)
    np.testing.assert_array_equal(
        apply_condition("dark:gain=0.15", scene, None, "a.jpg"),
        apply_condition("dark", scene, None, "a.jpg"),
    )
    assert condition_names(["dark:gain=0.1", "ir_grey", "dark"]) == [
        "clean",
        "ir_grey",
        "dark",
        "dark:gain=0.1",
    ]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("fog:level=3", "unknown condition 'fog'"),
        ("dark:gamma=2", "parameter among gain, noise_std, found 'gamma=2'"),
        ("dark:gain", "expected PARAMETER=VALUE"),
        ("dark:gain=dim", "gain must be a number, found 'dim'"),
        ("jpeg:quality=7.5", "quality must be a whole number, found '7.5'"),
    ],
)
def test_bad_condition_parameters_are_named(text: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        condition_names([text])


def test_the_suite_counts_faces_per_subject() -> None:
    from roadgaze.evaluation.condition_suite import format_subject_table, score_condition
    from roadgaze.evaluation.ground_truth import GroundTruth
    from roadgaze.evaluation.images import ImageEstimate

    truths = [GroundTruth(f"{i}.jpg", 0.0, 0.0, subject) for i, subject in enumerate("aabbb")]
    found = [True, False, True, True, False]
    estimates = [ImageEstimate(file=t.file, face=f) for t, f in zip(truths, found, strict=True)]
    row = score_condition("dark", truths, estimates)
    assert row.faces_by_subject == (("a", 1, 2), ("b", 2, 3))
    assert row.to_json_dict()["subjects"][1] == {"subject": "b", "faces": 2, "images": 3}
    assert format_subject_table([row]) == (
        "| faces found % by subject | a | b |\n|---|---|---|\n| dark | 50.0 | 66.7 |"
    )
    anonymous = [GroundTruth(t.file, 0.0) for t in truths]
    assert format_subject_table([score_condition("dark", anonymous, estimates)]) is None
