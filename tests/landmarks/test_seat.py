"""Where the driver sits in the image: the seat side against a pinhole camera's projection for
any mounting, the presets in both cabins, the first pick and when two faces are ambiguous."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from roadgaze.landmarks.driver import choose_driver
from roadgaze.landmarks.seat import (
    REASON_NEARER_SEAT,
    REASON_SAME_PLACE,
    REASON_SIDE_UNKNOWN,
    REASON_SIMILAR_SIZE,
    ambiguity,
    driver_image_side,
    seat_pick,
)
from roadgaze.pose.mounting import MOUNTING_PRESETS, mounting_for, rotation


class Face:
    def __init__(self, x_min: float, width: float, y_min: float = 100.0) -> None:
        self.box_px = (x_min, y_min, x_min + width, y_min + 1.2 * width)


def passenger_image_x(
    yaw_deg: float, pitch_deg: float, roll_deg: float, distance_m: float, passenger_y_m: float
) -> float | None:
    """The passenger's image x (the driver's is 0) for a pinhole camera of this mounting at
    `distance_m` from the driver's head, aimed at it; None when the passenger is behind it."""
    m = np.array(rotation(yaw_deg, pitch_deg, roll_deg))
    x_cam, y_cam = m[:, 0], m[:, 1]
    camera = distance_m * x_cam
    ray = np.array([0.0, passenger_y_m, 0.0]) - camera
    depth = float(ray @ -x_cam)
    if depth <= 0.05:
        return None
    # The camera looks along -x_cam with z_cam up: its right (the image's +x) is
    # (-x_cam) x z_cam = y_cam.
    right = np.cross(-x_cam, m[:, 2])
    np.testing.assert_allclose(right, y_cam, atol=1e-12)
    return float(ray @ right) / depth


@settings(max_examples=300, deadline=None)
@given(
    yaw=st.floats(-89.0, 89.0),
    pitch=st.floats(-60.0, 60.0),
    roll=st.floats(-180.0, 180.0),
    distance=st.floats(0.3, 1.5),
    width=st.floats(0.4, 1.0),
    cabin=st.sampled_from(["lhd", "rhd"]),
)
def test_the_seat_side_is_where_a_pinhole_camera_sees_the_driver(
    yaw: float, pitch: float, roll: float, distance: float, width: float, cabin: str
) -> None:
    passenger_y = -width if cabin == "lhd" else width  # beside the driver, on the other side
    x = passenger_image_x(yaw, pitch, roll, distance, passenger_y)
    assume(x is not None and abs(x) > 1e-6)
    side = driver_image_side(cabin, yaw, pitch, roll)
    if side != 0:
        assert side == -math.copysign(1, x)  # the driver on the other side of the passenger


@pytest.mark.parametrize("preset", sorted(MOUNTING_PRESETS))
@pytest.mark.parametrize(("cabin", "side"), [("lhd", 1), ("rhd", -1)])
def test_every_preset_sees_the_driver_right_in_lhd_and_left_in_rhd(
    preset: str, cabin: str, side: int
) -> None:
    mounting = mounting_for(preset, cabin)  # type: ignore[arg-type]
    angles = (mounting.yaw_deg, mounting.pitch_deg, mounting.roll_deg)
    assert driver_image_side(cabin, *angles) == side


def test_a_camera_beside_the_heads_or_on_its_side_does_not_know_the_side() -> None:
    assert driver_image_side("lhd", 85.0) == 0
    assert driver_image_side("lhd", 0.0, 0.0, 90.0) == 0
    assert driver_image_side("lhd", 0.0, 0.0, 180.0) == -1  # upside down: the sides swap
    with pytest.raises(ValueError, match="unknown cabin"):
        driver_image_side("middle")


def test_the_seat_picks_by_side_not_by_size() -> None:
    passenger, driver = Face(40, 110), Face(300, 100)  # the passenger 1.2 times larger
    faces = [passenger, driver]
    assert choose_driver(faces, "largest") == 0
    assert choose_driver(faces, "seat", side=1) == 1 == seat_pick(faces, 1)
    assert choose_driver(faces, "seat", side=-1) == 0
    assert seat_pick(faces, 0) == 0  # side unknown: the larger
    assert seat_pick([], 1) is None


def test_a_face_too_small_to_be_the_driver_is_not_picked() -> None:
    rear = Face(420, 50)  # furthest right, a quarter of the area: a rear passenger
    faces = [Face(40, 100), Face(260, 100), rear]
    assert seat_pick(faces, 1) == 1


def test_two_faces_at_one_place_take_the_larger() -> None:
    faces = [Face(300, 80, 40), Face(310, 100, 200)]  # one above the other, centres 20 px apart
    assert seat_pick(faces, 1) == 1


@pytest.mark.parametrize(
    ("faces", "driver", "rule", "side", "reason"),
    [
        ([Face(40, 100), Face(300, 100)], 1, "seat", 1, ""),
        ([Face(300, 100)], 0, "seat", 1, ""),
        ([Face(40, 100), Face(300, 100)], None, "seat", 1, ""),
        ([Face(40, 100), Face(300, 40)], 0, "seat", 1, ""),  # the other too small
        ([Face(40, 100), Face(300, 100)], 1, "seat", 0, REASON_SIDE_UNKNOWN),
        ([Face(300, 80, 40), Face(310, 100, 200)], 1, "seat", 1, REASON_SAME_PLACE),
        ([Face(40, 100), Face(300, 100)], 0, "seat", 1, REASON_NEARER_SEAT),
        ([Face(40, 100), Face(300, 100)], 0, "left", -1, ""),
        ([Face(40, 100), Face(300, 105)], 1, "largest", 0, REASON_SIMILAR_SIZE),
        ([Face(40, 80), Face(300, 100)], 1, "largest", 0, ""),
    ],
)
def test_when_the_driver_cannot_be_told_from_another_face(
    faces: list[Face], driver: int | None, rule: str, side: int, reason: str
) -> None:
    assert ambiguity(faces, driver, rule, side) == reason
