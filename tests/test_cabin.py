"""The gaze locations' geometry and the head's place from the face box (roadgaze.cabin)."""

from __future__ import annotations

import math

import pytest

from roadgaze.cabin import (
    FACE_HEIGHT_M,
    FACE_WIDTH_M,
    LOCATION_NAMES,
    LOCATIONS,
    PIVOT_BEHIND_FACE_M,
    FacePlace,
    direction_deg,
    face_seen,
    face_size_px_per_m,
    head_place_m,
    location,
    locations_for,
)
from roadgaze.mounting import FRONT, MOUNTING_PRESETS, mounting_for

REFERENCE = FacePlace(320.0, 240.0, 1000.0)
"""A face at the image centre, 1000 px per metre (a 15 cm face 150 px wide)."""


def test_every_sheet_location_is_named_once_with_a_source() -> None:
    assert LOCATION_NAMES == (
        "driver_side_window",
        "infotainment",
        "passenger_footwell",
        "passenger_face",
        "passenger_side_window",
        "glovebox",
        "rear_passenger",
        "driver_side_mirror",
        "rear_view_mirror",
        "passenger_side_mirror",
        "instrument_cluster",
        # where the phone-use rows put the phone
        "phone_dashboard_outboard",
        "driver_knee_outboard",
        "driver_lap",
        "driver_inboard",
        "phone_dedicated_mount",
        "phone_wheel_centre",
    )
    assert all(loc.source for loc in LOCATIONS)
    driving = {loc.name for loc in LOCATIONS if loc.driving_task}
    assert driving == {
        "driver_side_mirror",
        "rear_view_mirror",
        "passenger_side_mirror",
        "instrument_cluster",
    }


def test_directions_from_the_driving_place() -> None:
    # Closed form: yaw = atan2(y, x), pitch = atan2(z, hypot(x, y)).
    assert direction_deg((1.0, 1.0, 0.0)) == pytest.approx((45.0, 0.0))
    assert direction_deg((0.0, 0.0, -1.0))[1] == pytest.approx(-90.0)
    footwell = location("passenger_footwell").direction_deg()
    assert footwell == pytest.approx(
        (
            math.degrees(math.atan2(-0.75, 0.55)),
            math.degrees(math.atan2(-0.85, math.hypot(0.55, 0.75))),
        )
    )
    # From a head leaned 0.25 m right and 0.2 m down it lies at (0.55, -0.5, -0.65) from it.
    leaned = location("passenger_footwell").direction_deg((0.0, -0.25, -0.2))
    assert leaned == pytest.approx(direction_deg((0.55, -0.5, -0.65)))
    assert leaned[0] == pytest.approx(math.degrees(math.atan2(-0.5, 0.55)))
    assert location("passenger_face").direction_deg()[0] == pytest.approx(-90.0)
    assert location("driver_side_window").direction_deg()[0] > 55.0


def test_right_hand_drive_mirrors_every_location() -> None:
    for lhd, rhd in zip(locations_for("lhd"), locations_for("rhd"), strict=True):
        assert rhd.name == lhd.name
        yaw, pitch = lhd.direction_deg()
        assert rhd.direction_deg() == pytest.approx((-yaw, pitch))
    with pytest.raises(ValueError, match="unknown gaze location 'sunroof'"):
        location("sunroof")


def test_face_size_reads_the_larger_of_width_and_height() -> None:
    assert face_size_px_per_m(150.0, 190.0) == pytest.approx(1000.0)
    assert face_size_px_per_m(75.0, 190.0) == pytest.approx(190.0 / FACE_HEIGHT_M)  # turned
    assert face_size_px_per_m(150.0, 120.0) == pytest.approx(150.0 / FACE_WIDTH_M)  # nodded


def test_a_head_moved_toward_a_front_camera_grows_and_moves_across() -> None:
    # Front camera 0.7 m ahead: the head 0.2 m to the driver's right, 0.1 m down, 0.1 m ahead
    # sits at depth 0.6 m: k = 1000 * 0.7 / 0.6; the driver's right is the image left.
    seen = face_seen(FRONT, 0.7, REFERENCE, (0.1, -0.2, -0.1))
    k = 1000.0 * 0.7 / 0.6
    assert seen.k_px_per_m == pytest.approx(k)
    assert seen.u_px == pytest.approx(320.0 - 0.2 * k)
    assert seen.v_px == pytest.approx(240.0 + 0.1 * k)
    assert head_place_m(FRONT, 0.7, REFERENCE, seen) == pytest.approx((0.1, -0.2, -0.1))


def test_a_turn_alone_leaves_the_head_in_place() -> None:
    # Turned 60 deg left about the neck, the face's centre swings 0.105 sin 60 to the left and
    # 0.105 (1 - cos 60) back; the head's place reads 0.
    seen = face_seen(FRONT, 0.7, REFERENCE, (0.0, 0.0, 0.0), 60.0, 0.0)
    depth = 0.7 + PIVOT_BEHIND_FACE_M * (1.0 - math.cos(math.radians(60.0)))
    assert seen.k_px_per_m == pytest.approx(1000.0 * 0.7 / depth)
    swing = PIVOT_BEHIND_FACE_M * math.sin(math.radians(60.0))
    assert seen.u_px == pytest.approx(320.0 + swing * seen.k_px_per_m)
    assert head_place_m(FRONT, 0.7, REFERENCE, seen, 60.0, 0.0) == pytest.approx(
        (0.0, 0.0, 0.0), abs=1e-12
    )


@pytest.mark.parametrize("preset", sorted(MOUNTING_PRESETS))
@pytest.mark.parametrize("cabin", ["lhd", "rhd"])
def test_a_placed_head_is_read_back_from_every_mounting(preset: str, cabin: str) -> None:
    mounting = mounting_for(preset, cabin)  # type: ignore[arg-type]
    for head in ((0.0, -0.25, -0.2), (-0.15, -0.3, 0.0), (0.05, 0.1, 0.05)):
        for yaw, pitch in ((0.0, 0.0), (-40.0, -30.0), (-75.0, 5.0)):
            seen = face_seen(mounting, 0.8, REFERENCE, head, yaw, pitch)
            assert head_place_m(mounting, 0.8, REFERENCE, seen, yaw, pitch) == pytest.approx(head)


def test_a_face_of_no_size_is_refused() -> None:
    with pytest.raises(ValueError, match="positive size"):
        head_place_m(FRONT, 0.7, REFERENCE, FacePlace(320.0, 240.0, 0.0))
