"""The vertical CE model against its closed forms (like the paper's Experiment 1), its constants
against MediaPipe's canonical face mesh, and the service pitch's down gain."""

from __future__ import annotations

import struct
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from roadgaze.config import load_config
from roadgaze.pose.pitch import (
    CANONICAL_MIDLINE,
    DOWN_GAIN,
    MidlineConstants,
    head_pitch_deg,
    midline_forward_model,
    midline_pitch_deg,
    naive_pitch_error_deg,
)

TRUE_PITCH_DEG = np.arange(-80.0, 80.5, 1.0)
PIVOTS_PX = [(0.0, 0.0), (120.0, 180.0), (250.0, 90.0), (-60.0, 300.0)]
"""(below, behind) of the top/bottom midpoint relative to the neck pivot."""


@pytest.mark.parametrize(("below_px", "behind_px"), PIVOTS_PX)
def test_the_estimator_inverts_the_forward_model_exactly_for_any_pivot(
    below_px: float, behind_px: float
) -> None:
    projected = midline_forward_model(
        TRUE_PITCH_DEG, pivot_below_px=below_px, pivot_behind_px=behind_px
    )
    estimate = midline_pitch_deg(projected.y_top, projected.y_bottom, projected.y_center)
    np.testing.assert_allclose(estimate, TRUE_PITCH_DEG, atol=1e-9)


def test_the_offset_free_estimator_errs_exactly_as_the_closed_form_says() -> None:
    """(P5): drop = lean = 0 in the estimator, the canonical face in the forward model."""
    projected = midline_forward_model(TRUE_PITCH_DEG)
    naive = midline_pitch_deg(
        projected.y_top,
        projected.y_bottom,
        projected.y_center,
        MidlineConstants(depth=CANONICAL_MIDLINE.depth, drop=0.0, lean=0.0),
    )
    expected = naive_pitch_error_deg(TRUE_PITCH_DEG)
    np.testing.assert_allclose(naive - TRUE_PITCH_DEG, expected, atol=1e-9)
    # The neutral offset: -atan(drop / depth) at 0, about -10.2 deg for the canonical face.
    assert float(expected[80]) == pytest.approx(
        -np.degrees(np.arctan(CANONICAL_MIDLINE.drop / CANONICAL_MIDLINE.depth)), abs=1e-12
    )
    np.testing.assert_allclose(
        naive_pitch_error_deg([0.0, -30.0, 30.0]), [-10.16, -7.31, -8.43], atol=0.01
    )


@settings(max_examples=50, deadline=None)
@given(
    pitch=st.floats(-75.0, 75.0),
    half_height=st.floats(10.0, 400.0),
    row=st.floats(-1000.0, 1000.0),
    below=st.floats(-300.0, 300.0),
    behind=st.floats(-300.0, 300.0),
)
def test_size_position_and_pivot_cancel(
    pitch: float, half_height: float, row: float, below: float, behind: float
) -> None:
    projected = midline_forward_model(pitch, half_height, row, below, behind)
    assert float(
        midline_pitch_deg(projected.y_top, projected.y_bottom, projected.y_center)
    ) == pytest.approx(pitch, abs=1e-7)


def test_impossible_geometry_is_nan_and_scalars_stay_scalars() -> None:
    assert np.isnan(midline_pitch_deg(10.0, 5.0, 7.0))  # bottom above top
    assert np.isnan(midline_pitch_deg(float("nan"), 5.0, 7.0))
    value = midline_pitch_deg(0.0, 10.0, 5.0)
    assert isinstance(value, float)
    assert value == pytest.approx(
        np.degrees(np.arctan2(CANONICAL_MIDLINE.drop, CANONICAL_MIDLINE.depth))
    )


def test_the_down_gain_kinks_at_the_neutral() -> None:
    np.testing.assert_allclose(
        head_pitch_deg([-10.0, 2.0, 10.0], 2.0), [2.0 - DOWN_GAIN * 12.0, 2.0, 10.0]
    )
    assert head_pitch_deg(-20.0) == pytest.approx(-20.0 * DOWN_GAIN)
    assert head_pitch_deg(-20.0, 0.0, 1.0) == -20.0
    assert np.isnan(head_pitch_deg(float("nan"), 0.0))
    below = head_pitch_deg(np.array([-1e-9, 0.0, 1e-9]), 0.0)
    assert float(np.max(np.abs(np.diff(below)))) < 1e-8  # continuous at the kink


def test_the_scalar_path_of_the_down_gain_agrees_with_the_array_path() -> None:
    rng = np.random.default_rng(2)
    pitch = np.concatenate([rng.uniform(-60.0, 60.0, 500), [np.nan, np.inf, -np.inf, 0.0]])
    neutral = np.concatenate([rng.uniform(-15.0, 15.0, 500), [0.0, 0.0, 0.0, np.nan]])
    by_array = head_pitch_deg(pitch, neutral, 1.7)
    by_float = [
        head_pitch_deg(float(p), float(n), 1.7) for p, n in zip(pitch, neutral, strict=True)
    ]
    assert all(isinstance(value, float) for value in by_float)
    np.testing.assert_array_equal(by_float, by_array)


# MediaPipe's canonical face mesh: the constants are read off it, nothing is fitted.


def _varint(data: bytes, index: int) -> tuple[int, int]:
    result = shift = 0
    while True:
        byte = data[index]
        index += 1
        result |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            return result, index


def _protobuf_fields(data: bytes) -> dict[tuple[int, int], list[object]]:
    """A minimal protobuf wire-format reader: (field, wire type) -> values."""
    index, fields = 0, {}
    while index < len(data):
        key, index = _varint(data, index)
        number, wire = key >> 3, key & 7
        value: object
        if wire == 0:
            value, index = _varint(data, index)
        elif wire == 5:
            value = struct.unpack("<f", data[index : index + 4])[0]
            index += 4
        elif wire == 1:
            value, index = data[index : index + 8], index + 8
        elif wire == 2:
            length, index = _varint(data, index)
            value, index = data[index : index + length], index + length
        else:
            raise ValueError(f"unexpected wire type {wire}")
        fields.setdefault((number, wire), []).append(value)
    return fields


def canonical_face_cm(model_path: Path) -> np.ndarray:
    """(468, 3) canonical mesh (x, up, toward the camera; cm) from face_landmarker.task."""
    with zipfile.ZipFile(model_path) as bundle:
        metadata = bundle.read("geometry_pipeline_metadata_landmarks.binarypb")
    mesh = _protobuf_fields(_protobuf_fields(metadata)[(1, 2)][0])  # type: ignore[arg-type]
    return np.array(mesh[(3, 5)], dtype=np.float64).reshape(-1, 5)[:, :3]


@pytest.fixture(scope="module")
def canonical_face() -> np.ndarray:
    from roadgaze.landmarks.model_store import resolve_model

    return canonical_face_cm(resolve_model(load_config(environ={}).model))


def test_constants_are_those_of_mediapipes_canonical_face(canonical_face: np.ndarray) -> None:
    up, depth = canonical_face[:, 1], canonical_face[:, 2]
    top, bottom, nose = 10, 152, 1
    half_height = (up[top] - up[bottom]) / 2.0
    assert half_height == pytest.approx(8.833, abs=1e-3)
    middle_up, middle_depth = (up[top] + up[bottom]) / 2, (depth[top] + depth[bottom]) / 2
    assert (depth[nose] - middle_depth) / half_height == pytest.approx(
        CANONICAL_MIDLINE.depth, abs=1e-4
    )
    assert (middle_up - up[nose]) / half_height == pytest.approx(CANONICAL_MIDLINE.drop, abs=1e-4)
    assert (depth[top] - depth[bottom]) / (2 * half_height) == pytest.approx(
        CANONICAL_MIDLINE.lean, abs=1e-4
    )


@pytest.mark.parametrize("pitch_deg", [-40.0, -20.0, 0.0, 20.0, 40.0])
def test_the_canonical_mesh_nodded_rigidly_is_recovered(
    canonical_face: np.ndarray, pitch_deg: float
) -> None:
    angle = np.radians(pitch_deg)
    image_y = -(canonical_face[:, 1] * np.cos(angle) + canonical_face[:, 2] * np.sin(angle))
    estimate = midline_pitch_deg(image_y[10], image_y[152], image_y[1])
    assert estimate == pytest.approx(pitch_deg, abs=0.01)
