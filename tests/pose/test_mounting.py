"""Camera mounting maths: round trips, closed forms, presets and cabins."""

from __future__ import annotations

import itertools
import math

import pytest

from roadgaze.pose.mounting import (
    FRONT,
    MOUNTING_PRESETS,
    CameraMounting,
    angles_of,
    gaze_to_camera,
    gaze_to_driver,
    head_to_camera,
    head_to_driver,
    mounting_for,
    rotation,
)

ANGLES = [-70.0, -35.0, 0.0, 20.0, 65.0]
PITCHES = [-40.0, -10.0, 0.0, 25.0]
MOUNTINGS = [*MOUNTING_PRESETS.values(), CameraMounting(-40.0, 12.0, 15.0)]


def test_rotation_and_angles_are_inverse_and_orthonormal() -> None:
    for yaw, pitch, roll in itertools.product(ANGLES, PITCHES, [-30.0, 0.0, 10.0]):
        m = rotation(yaw, pitch, roll)
        assert angles_of(m) == pytest.approx((yaw, pitch, roll), abs=1e-9)
        for i, j in itertools.product(range(3), range(3)):
            dot = sum(m[k][i] * m[k][j] for k in range(3))
            assert dot == pytest.approx(1.0 if i == j else 0.0, abs=1e-12)


def test_first_column_is_the_facing_direction() -> None:
    m = rotation(30.0, 20.0, 40.0)
    c = math.cos(math.radians(20.0))
    assert [m[i][0] for i in range(3)] == pytest.approx(
        [
            c * math.cos(math.radians(30.0)),
            c * math.sin(math.radians(30.0)),
            math.sin(math.radians(20.0)),
        ]
    )


@pytest.mark.parametrize("mounting", MOUNTINGS, ids=lambda m: m.name)
def test_round_trips(mounting: CameraMounting) -> None:
    for yaw, pitch in itertools.product(ANGLES, PITCHES):
        head = head_to_driver(mounting, yaw, pitch, 5.0)
        assert head_to_camera(mounting, *head) == pytest.approx((yaw, pitch, 5.0), abs=1e-9)
        gaze = gaze_to_driver(mounting, yaw, pitch)
        assert gaze_to_camera(mounting, *gaze) == pytest.approx((yaw, pitch), abs=1e-9)
        assert head[:2] == pytest.approx(gaze, abs=1e-9)  # a head's facing direction is a gaze


def test_a_head_facing_the_camera_points_at_the_camera() -> None:
    for mounting in MOUNTINGS:
        yaw, pitch, roll = head_to_driver(mounting, 0.0, 0.0, 0.0)
        assert (yaw, pitch, roll) == pytest.approx(
            (mounting.yaw_deg, mounting.pitch_deg, mounting.roll_deg), abs=1e-9
        )


def test_yaw_only_mounting_adds_yaw_exactly() -> None:
    mounting = CameraMounting(35.0, 0.0, 0.0)
    for yaw, pitch in itertools.product([-60.0, -35.0, 0.0, 30.0], PITCHES):
        assert gaze_to_driver(mounting, yaw, pitch) == pytest.approx((yaw + 35.0, pitch))
    # the road ahead (driver yaw 0) reads -35 in the camera
    assert gaze_to_camera(mounting, 0.0, 0.0) == pytest.approx((-35.0, 0.0))


def test_pitch_mounting_closed_form_for_a_turned_head() -> None:
    """Camera 20 deg below the eyes: pitch does not simply add for a head turned sideways."""
    pm = -20.0
    mounting = CameraMounting(0.0, pm, 0.0)
    for y, p in itertools.product([0.0, 30.0, 60.0, -50.0], [0.0, 15.0, -20.0]):
        yr, pr, pmr = math.radians(y), math.radians(p), math.radians(pm)
        sin_pd = math.sin(pmr) * math.cos(pr) * math.cos(yr) + math.cos(pmr) * math.sin(pr)
        x = math.cos(pmr) * math.cos(pr) * math.cos(yr) - math.sin(pmr) * math.sin(pr)
        yaw_d = math.degrees(math.atan2(math.cos(pr) * math.sin(yr), x))
        assert gaze_to_driver(mounting, y, p) == pytest.approx(
            (yaw_d, math.degrees(math.asin(sin_pd))), abs=1e-9
        )
    # Straight at the camera's level: pitch adds; turned 60 deg: only cos(60) of it.
    assert gaze_to_driver(mounting, 0.0, 20.0) == pytest.approx((0.0, 0.0), abs=1e-9)
    assert gaze_to_driver(mounting, 60.0, 0.0)[1] == pytest.approx(
        math.degrees(math.asin(math.sin(math.radians(pm)) * 0.5))
    )


def test_a_rolled_camera_turns_yaw_into_pitch() -> None:
    mounting = CameraMounting(0.0, 0.0, 30.0)
    yaw, pitch = gaze_to_driver(mounting, 40.0, 0.0)
    assert pitch == pytest.approx(math.degrees(math.asin(math.sin(math.radians(40.0)) * 0.5)))
    assert yaw == pytest.approx(
        math.degrees(
            math.atan2(
                math.sin(math.radians(40.0)) * math.cos(math.radians(30.0)),
                math.cos(math.radians(40.0)),
            )
        )
    )


def test_presets_and_cabins() -> None:
    assert mounting_for("front") == FRONT and FRONT.is_identity
    lhd, rhd = mounting_for("a_pillar", "lhd"), mounting_for("a_pillar", "rhd")
    assert lhd.yaw_deg > 0 > rhd.yaw_deg  # the driver-side pillar: left in LHD, right in RHD
    assert (rhd.yaw_deg, rhd.pitch_deg, rhd.roll_deg) == (
        -lhd.yaw_deg,
        lhd.pitch_deg,
        -lhd.roll_deg,
    )
    assert mounting_for("centre_console", "rhd").yaw_deg > 0
    assert mounting_for("steering_column", "rhd") == mounting_for("steering_column", "lhd")
    custom = mounting_for("a_pillar", "rhd", pitch_deg=12.0)
    assert (custom.yaw_deg, custom.pitch_deg, custom.name) == (-35.0, 12.0, "custom")
    # mirroring a whole cabin mirrors every mapped pose
    for yaw, pitch in itertools.product(ANGLES, PITCHES):
        a = gaze_to_driver(lhd, yaw, pitch)
        b = gaze_to_driver(rhd, -yaw, pitch)
        assert b == pytest.approx((-a[0], a[1]), abs=1e-9)


@pytest.mark.parametrize(
    ("args", "message"),
    [(("roof",), "unknown camera mounting"), (("front", "xhd"), "unknown cabin")],
)
def test_bad_presets(args: tuple[str, ...], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        mounting_for(*args)  # type: ignore[arg-type]


def test_bad_angles() -> None:
    with pytest.raises(ValueError, match="pitch_deg"):
        CameraMounting(0.0, 95.0, 0.0)
    with pytest.raises(ValueError, match="yaw_deg"):
        CameraMounting(math.nan, 0.0, 0.0)
