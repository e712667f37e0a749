"""The paper's yaw models against its closed forms (Experiment 1) and their symmetry properties."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from roadgaze.pose.geometry import (
    PAPER_CONSTANTS,
    YAW_MODELS,
    FaceModelConstants,
    center_ce,
    cylindrical,
    ellipsoidal,
    expected_error_deg,
    forward_model,
)

SWEEP_DEG = np.arange(-90.0, 91.0, 1.0)
MODEL_NAMES = list(YAW_MODELS)


def test_public_api_names_the_five_models_in_the_papers_order() -> None:
    assert MODEL_NAMES == ["cylindrical", "ellipsoidal", "ce", "center_ce", "boundary_ce"]


def test_ce_recovers_the_forward_model_exactly() -> None:
    face = forward_model(SWEEP_DEG, half_width_px=150.0, pivot_x_px=320.0)
    estimate = YAW_MODELS["ce"](face.x_left, face.x_right, face.x_center)
    assert np.max(np.abs(estimate - SWEEP_DEG)) < 1e-9


@pytest.mark.parametrize("model", ["cylindrical", "ellipsoidal", "center_ce", "boundary_ce"])
def test_model_errors_equal_the_papers_error_functions(model: str) -> None:
    face = forward_model(SWEEP_DEG)
    error = YAW_MODELS[model](face.x_left, face.x_right, face.x_center) - SWEEP_DEG
    np.testing.assert_allclose(error, expected_error_deg(model, SWEEP_DEG), rtol=0, atol=1e-9)


@pytest.mark.parametrize(
    ("model", "true_deg", "expected_deg"),
    [
        # eq. 49 at 90 deg: asin(beta / beta) = 90, the cylinder is exact at the ends.
        ("cylindrical", 90.0, 90.0),
        # eq. 42: sin(yaw_e) = (1 + alpha) / (alpha + beta) sin(yaw_c) = 0.8333 at 90 deg.
        ("ellipsoidal", 90.0, np.degrees(np.arcsin(1.25 / 1.5))),
        # The angle rule: Center-CE and Boundary-CE map a true 90 deg to 60 deg.
        ("center_ce", 90.0, 60.0),
        ("boundary_ce", 90.0, 60.0),
        ("center_ce", -90.0, -60.0),
        ("ce", 37.0, 37.0),
    ],
)
def test_values_at_known_points(model: str, true_deg: float, expected_deg: float) -> None:
    face = forward_model(true_deg)
    estimate = YAW_MODELS[model](face.x_left, face.x_right, face.x_center)
    assert estimate == pytest.approx(expected_deg, abs=0.01)


def test_ellipsoidal_is_the_cylinder_scaled_as_eq_42() -> None:
    rng = np.random.default_rng(0)
    x_left = rng.uniform(0, 100, 50)
    x_right = x_left + rng.uniform(50, 200, 50)
    x_center = x_left + (x_right - x_left) * rng.uniform(0, 1, 50)
    sin_e = np.sin(np.radians(ellipsoidal(x_left, x_right, x_center)))
    sin_c = np.sin(np.radians(cylindrical(x_left, x_right, x_center)))
    np.testing.assert_allclose(sin_e, 0.8333333 * sin_c, atol=1e-6)


def test_constants_can_be_overridden() -> None:
    stiff = FaceModelConstants(alpha=0.25, beta=1.25, gamma_c=0.0, gamma_b=0.5774)
    face = forward_model(np.array([20.0, 45.0]))
    # With gamma_c = 0, Center-CE is exactly CE and so recovers the truth.
    estimate = center_ce(face.x_left, face.x_right, face.x_center, stiff)
    np.testing.assert_allclose(estimate, [20.0, 45.0], atol=1e-9)
    assert center_ce(0.0, 100.0, 80.0) != center_ce(0.0, 100.0, 80.0, stiff)


def test_scalars_give_floats_and_arrays_give_arrays() -> None:
    for model in YAW_MODELS.values():
        assert isinstance(model(0.0, 100.0, 60.0), float)
        result = model(np.zeros((2, 3)), np.full((2, 3), 100.0), np.full((2, 3), 60.0))
        assert isinstance(result, np.ndarray)
        assert result.shape == (2, 3)


def test_unequal_shapes_are_rejected() -> None:
    with pytest.raises(ValueError, match="equal shapes"):
        center_ce(np.zeros(3), np.ones(2), np.ones(3))


@pytest.mark.parametrize("model", MODEL_NAMES)
@pytest.mark.parametrize(
    ("x_left", "x_right", "x_center"),
    [
        (100.0, 100.0, 100.0),  # zero width
        (200.0, 100.0, 150.0),  # boundaries swapped
        (np.nan, 100.0, 50.0),
        (0.0, np.nan, 50.0),
        (0.0, 100.0, np.nan),
        (0.0, np.inf, 50.0),
        (0.0, 100.0, 1000.0),  # centre far outside the face: no head turn explains it
        (0.0, 100.0, -1000.0),
    ],
)
def test_impossible_geometry_gives_nan_without_warnings(
    model: str, x_left: float, x_right: float, x_center: float
) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.isnan(YAW_MODELS[model](x_left, x_right, x_center))


def test_nan_is_per_element_in_arrays() -> None:
    yaw = center_ce(np.array([0.0, 0.0]), np.array([100.0, -5.0]), np.array([60.0, 0.0]))
    assert np.isfinite(yaw[0])
    assert np.isnan(yaw[1])


def test_centre_slightly_outside_the_boundaries_is_explained_by_center_ce() -> None:
    # Center-CE admits |2d| <= (beta + gamma_c) / beta * W: the nose may stick out past the cheek.
    beta, gamma_c = PAPER_CONSTANTS.beta, PAPER_CONSTANTS.gamma_c
    d = 104.0 - 50.0
    r = 0.5 * np.sqrt(100.0**2 - (beta**2 - 1) / (beta + gamma_c) ** 2 * (2 * d) ** 2)  # eq. 35
    expected = np.degrees(np.arcsin(d / ((beta + gamma_c) * r)))  # eq. 36
    assert center_ce(0.0, 100.0, 104.0) == pytest.approx(expected, abs=1e-9)
    assert np.isnan(center_ce(0.0, 100.0, 106.0))


def test_expected_error_rejects_unknown_model() -> None:
    with pytest.raises(KeyError, match="unknown yaw model"):
        expected_error_deg("sphere", 10.0)


# --- Properties -------------------------------------------------------------------------------

coordinate = st.floats(min_value=-2000, max_value=2000, allow_nan=False)
width = st.floats(min_value=5, max_value=1000, allow_nan=False)
relative_offset = st.floats(min_value=-0.99, max_value=0.99, allow_nan=False)


def _face(x_left: float, face_width: float, offset: float) -> tuple[float, float, float]:
    """A face with boundaries x_left, x_left + width and centre at `offset` half-widths."""
    return x_left, x_left + face_width, x_left + face_width / 2 * (1 + offset)


@settings(max_examples=200, deadline=None)
@given(x_left=coordinate, face_width=width, offset=relative_offset, mirror_x=coordinate)
def test_mirroring_about_any_vertical_line_negates_yaw(
    x_left: float, face_width: float, offset: float, mirror_x: float
) -> None:
    left, right, center = _face(x_left, face_width, offset)
    for model in YAW_MODELS.values():
        original = model(left, right, center)
        mirrored = model(2 * mirror_x - right, 2 * mirror_x - left, 2 * mirror_x - center)
        assert mirrored == pytest.approx(-original, abs=1e-6)


@settings(max_examples=200, deadline=None)
@given(
    x_left=coordinate,
    face_width=width,
    offset=relative_offset,
    shift=coordinate,
    scale=st.floats(min_value=0.05, max_value=20),
)
def test_translation_and_positive_scaling_do_not_change_yaw(
    x_left: float, face_width: float, offset: float, shift: float, scale: float
) -> None:
    left, right, center = _face(x_left, face_width, offset)
    for model in YAW_MODELS.values():
        original = model(left, right, center)
        moved = model(left * scale + shift, right * scale + shift, center * scale + shift)
        assert moved == pytest.approx(original, abs=1e-6)


@settings(max_examples=200, deadline=None)
@given(
    x_left=coordinate,
    face_width=width,
    offsets=st.lists(relative_offset, min_size=2, max_size=10, unique=True),
)
def test_yaw_increases_with_x_center(
    x_left: float, face_width: float, offsets: list[float]
) -> None:
    offsets = sorted(offsets)
    centers = np.array([_face(x_left, face_width, u)[2] for u in offsets])
    lefts = np.full_like(centers, x_left)
    rights = np.full_like(centers, x_left + face_width)
    for model in YAW_MODELS.values():
        yaws = model(lefts, rights, centers)
        assert np.all(np.isfinite(yaws))
        # Strictly increasing up to rounding where two centres coincide in float.
        assert np.all(np.diff(yaws) >= -1e-9)
        assert yaws[-1] > yaws[0] or centers[-1] == centers[0]


def test_paper_constants_are_the_papers() -> None:
    assert (PAPER_CONSTANTS.alpha, PAPER_CONSTANTS.beta) == (0.25, 1.25)
    assert (PAPER_CONSTANTS.gamma_c, PAPER_CONSTANTS.gamma_b) == (0.1269, 0.5774)


EDGE_VALUES = [0.0, 1.0, -1.0, 99.5, 100.0, 1e-300, 1e300, np.inf, -np.inf, np.nan]


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_the_scalar_path_agrees_with_the_array_path(model: str) -> None:
    """A face's floats take the per-frame path (plain `math`); arrays take numpy's. Both give
    the same yaw, to 1e-12 deg, and NaN in the same places, over random faces and edge values."""
    rng = np.random.default_rng(7)
    left = rng.uniform(-200.0, 200.0, 2000)
    right = left + rng.uniform(-20.0, 300.0, 2000)
    center = left + (right - left) * rng.uniform(-0.3, 1.3, 2000)
    edges = np.array(np.meshgrid(EDGE_VALUES, EDGE_VALUES, EDGE_VALUES)).reshape(3, -1)
    left, right, center = (
        np.concatenate([a, b]) for a, b in zip((left, right, center), edges, strict=True)
    )
    function = YAW_MODELS[model]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        by_array = function(left, right, center)
        by_float = np.array(
            [function(*map(float, face)) for face in zip(left, right, center, strict=True)]
        )
    assert np.array_equal(np.isnan(by_array), np.isnan(by_float))
    assert np.isfinite(by_array).sum() > 1000  # the centre inside the face for most
    np.testing.assert_allclose(by_float, by_array, rtol=0.0, atol=1e-12, equal_nan=True)
