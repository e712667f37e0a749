"""The full-range yaw blend: exactly Center-CE below its cue, continuous, antisymmetric."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from roadgaze.pose.fullrange import (
    DEFAULT_FULL_RANGE,
    FullRangeConstants,
    blend_weight,
    clipped_cylinder_deg,
    full_range_yaw_deg,
)
from roadgaze.pose.geometry import center_ce, cylindrical, forward_model

SWEEP_DEG = np.linspace(-90.0, 90.0, 181)
FACE = forward_model(SWEEP_DEG)


def test_below_the_cue_start_it_is_center_ce_exactly() -> None:
    cue = np.full(SWEEP_DEG.shape, DEFAULT_FULL_RANGE.cue_start_deg)
    np.testing.assert_array_equal(
        full_range_yaw_deg(FACE.x_left, FACE.x_right, FACE.x_center, cue),
        center_ce(FACE.x_left, FACE.x_right, FACE.x_center),
    )


@pytest.mark.parametrize("cue", [None, float("nan")])
def test_without_a_matrix_yaw_it_is_center_ce(cue: float | None) -> None:
    assert full_range_yaw_deg(100.0, 200.0, 170.0, cue) == center_ce(100.0, 200.0, 170.0)


def test_at_full_weight_it_is_the_clipped_cylinder() -> None:
    constants = FullRangeConstants(10.0, 40.0)
    cue = np.full(SWEEP_DEG.shape, 45.0)
    np.testing.assert_allclose(
        full_range_yaw_deg(FACE.x_left, FACE.x_right, FACE.x_center, cue, constants),
        cylindrical(FACE.x_left, FACE.x_right, FACE.x_center),
        atol=1e-9,
    )


def test_weight_is_a_smoothstep_of_the_cue() -> None:
    start, end = DEFAULT_FULL_RANGE.cue_start_deg, DEFAULT_FULL_RANGE.cue_end_deg
    middle = 0.5 * (start + end)
    np.testing.assert_allclose(
        blend_weight(np.array([0.0, start, middle, -middle, end, 120.0])),
        [0.0, 0.0, 0.5, 0.5, 1.0, 1.0],
    )
    cue = np.linspace(0.0, 120.0, 12001)
    weight = blend_weight(cue)
    assert float(np.max(np.abs(np.diff(weight)))) < 1e-3  # continuous
    assert np.all(np.diff(weight) >= 0)  # monotonic
    assert blend_weight(None) == 0.0


@settings(max_examples=100, deadline=None)
@given(
    left=st.floats(-500.0, 500.0),
    width=st.floats(20.0, 400.0),
    centre=st.floats(-0.5, 0.5),  # the nose within the boundaries
    cue=st.floats(-80.0, 80.0),
)
def test_mirror_flip_negates_the_yaw(left: float, width: float, centre: float, cue: float) -> None:
    right = left + width
    middle = left + width * (0.5 + centre)
    yaw = full_range_yaw_deg(left, right, middle, cue)
    mirrored = full_range_yaw_deg(-right, -left, -middle, -cue)
    # The inputs round differently once mirrored (1e-16 relative); at the edge (nose on a
    # boundary) asin's slope is infinite and that becomes up to sqrt(2e-16) rad, 1e-6 deg.
    assert mirrored == pytest.approx(-yaw, abs=1e-6)


@pytest.mark.parametrize("cue", [0.0, 40.0, 70.0])
def test_continuous_in_the_landmarks(cue: float) -> None:
    """Steps shrink with the grid (asin is steep but continuous at 2d/W = +-1)."""
    largest = []
    for count in (20_001, 2_000_001):
        centres = np.linspace(100.0, 200.0, count)  # sweeps 2d/W over [-1, 1]
        ones = np.ones(count)
        yaw = full_range_yaw_deg(100.0 * ones, 200.0 * ones, centres, cue)
        assert np.all(np.isfinite(yaw))
        largest.append(float(np.max(np.abs(np.diff(yaw)))))
    assert largest[1] < 0.1 * largest[0] and largest[1] < 0.1


def test_the_clipped_cylinder_is_defined_beyond_the_boundaries() -> None:
    assert clipped_cylinder_deg(100.0, 200.0, 260.0) == 90.0
    assert clipped_cylinder_deg(100.0, 200.0, 40.0) == -90.0
    assert np.isnan(clipped_cylinder_deg(200.0, 100.0, 150.0))


def test_constants_must_be_ordered() -> None:
    with pytest.raises(ValueError, match="cue_start_deg < cue_end_deg"):
        FullRangeConstants(50.0, 40.0)


def test_the_scalar_path_agrees_with_the_array_path() -> None:
    """One face's floats (the per-frame path) and arrays give the same (F1) yaw, to 1e-12 deg,
    with and without a cue, over random faces and edge values."""
    rng = np.random.default_rng(11)
    count = 3000
    left = rng.uniform(-200.0, 200.0, count)
    right = left + rng.uniform(-20.0, 300.0, count)
    center = left + (right - left) * rng.uniform(-0.3, 1.3, count)
    cue = rng.uniform(-100.0, 100.0, count)
    edges = [np.nan, np.inf, -np.inf, 0.0, 1e300]
    left[:5], right[5:10], center[10:15], cue[15:20] = edges, edges, edges, edges
    by_array = full_range_yaw_deg(left, right, center, cue)
    without_cue = full_range_yaw_deg(left, right, center, None)
    for i in range(count):
        face = (float(left[i]), float(right[i]), float(center[i]))
        np.testing.assert_allclose(
            full_range_yaw_deg(*face, float(cue[i])), by_array[i], atol=1e-12, equal_nan=True
        )
        np.testing.assert_allclose(
            full_range_yaw_deg(*face, None), without_cue[i], atol=1e-12, equal_nan=True
        )
    assert np.isfinite(by_array).sum() > 1500
