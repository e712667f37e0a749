"""The inattention monitor on synthetic timelines with known event times."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable

import pytest

from fakes import open_eyes
from repo_paths import child_env
from roadgaze.config import MonitorConfig
from roadgaze.monitor import (
    Alert,
    AlertKind,
    AlertLevel,
    Gaze,
    Monitor,
    initial_state,
    step,
)
from roadgaze.types import PoseSample

FPS = 30.0
FRAME_S = 1.0 / FPS
FIXED = MonitorConfig(neutral_yaw_deg=0.0)
"""Neutral fixed at 0 so event times do not depend on learning."""

YawAt = Callable[[float], float | None]
"""Yaw at time t, None for no face."""


def sample(
    t_s: float, yaw_deg: float | None, frame: int = 0, pitch_deg: float | None = None
) -> PoseSample:
    face = yaw_deg is not None
    return PoseSample(
        t_s=t_s,
        frame=frame,
        face=face,
        yaw_raw_deg=yaw_deg,
        yaw_deg=yaw_deg,
        yaw_rate_dps=0.0 if face else None,
        yaw_std_deg=1.0 if face else None,
        n_faces=int(face),
        pitch_raw_deg=pitch_deg if face else None,
        pitch_deg=pitch_deg if face else None,
        eyes=open_eyes() if face else None,
    )


def run(
    yaw_at: YawAt,
    duration_s: float,
    config: MonitorConfig = FIXED,
    speed_at: Callable[[float], float | None] = lambda t: None,
) -> tuple[Monitor, list[Alert]]:
    monitor = Monitor(config)
    alerts: list[Alert] = []
    for frame in range(round(duration_s * FPS)):
        t_s = frame / FPS
        alerts.extend(monitor.update(sample(t_s, yaw_at(t_s), frame), speed_at(t_s)))
    return monitor, alerts


AWAY_YAW_DEG = -27.0
"""A glance to the driver's right, short of the right mirror: zone `away` (not driving-related).
(Before zones the timing tests glanced to +45 deg, which the default zones call `left_mirror`;
before ADDW's mirror bounds to -30, which is now the right mirror's edge.)"""


def glances(
    starts_s: list[float], length_s: float, yaw_deg: float = AWAY_YAW_DEG, base_deg: float = 0.0
) -> YawAt:
    def yaw_at(t_s: float) -> float:
        inside = any(start <= t_s + 1e-9 < start + length_s for start in starts_s)
        return yaw_deg if inside else base_deg

    return yaw_at


def kinds(alerts: list[Alert]) -> list[tuple[str, str]]:
    return [(a.kind.value, a.level.value) for a in alerts]


def assert_within_one_frame(actual_s: float, expected_s: float) -> None:
    assert expected_s - 1e-9 <= actual_s < expected_s + FRAME_S + 1e-9, (actual_s, expected_s)


def test_long_distraction_fires_three_seconds_into_a_glance_then_clears() -> None:
    _, alerts = run(glances([4.0], 4.0), 12.0)
    assert kinds(alerts) == [("long_distraction", "warning"), ("cleared", "info")]
    assert_within_one_frame(alerts[0].t_s, 7.0)
    assert alerts[0].off_road_s == pytest.approx(3.0, abs=FRAME_S)
    assert alerts[0].yaw_deg == AWAY_YAW_DEG
    assert alerts[0].reason == "head in away"
    assert_within_one_frame(alerts[1].t_s, 8.0)
    assert alerts[1].clears == (AlertKind.LONG_DISTRACTION,)
    assert alerts[1].off_road_s == pytest.approx(4.0, abs=FRAME_S)


def test_long_distraction_is_raised_to_critical_at_six_seconds() -> None:
    _, alerts = run(glances([1.0], 8.0), 12.0)
    assert kinds(alerts) == [
        ("long_distraction", "warning"),
        ("long_distraction", "critical"),
        ("unresponsive", "critical"),  # away 6 s, i.e. not back 3 s after the warning
        ("cleared", "info"),
    ]
    assert_within_one_frame(alerts[0].t_s, 4.0)
    assert_within_one_frame(alerts[1].t_s, 7.0)
    assert_within_one_frame(alerts[2].t_s, 7.0)
    assert alerts[2].reason == "away 6.0 s"
    assert_within_one_frame(alerts[3].t_s, 9.0)
    assert alerts[3].clears == (
        AlertKind.LONG_DISTRACTION,
        AlertKind.UNRESPONSIVE,
    )


def test_a_glance_shorter_than_three_seconds_raises_nothing() -> None:
    _, alerts = run(glances([1.0], 2.9), 6.0)
    assert alerts == []


@pytest.mark.parametrize(
    ("yaw_sequence", "expected_on_road"),
    [
        ([0, 24, 25, 0], [True, True, True, True]),  # <= 25 is road ahead
        ([0, 26, 0], [True, False, True]),
        ([0, 26, 22, 20.5, 20, 24], [True, False, False, False, True, True]),  # back at <= 20
        ([0, -26, -21, -19], [True, False, False, True]),  # symmetric
        ([0, 26, 24, 26, 24, 26], [True, False, False, False, False, False]),  # no flicker
    ],
)
def test_hysteresis_leaves_at_25_and_returns_at_20(
    yaw_sequence: list[float], expected_on_road: list[bool]
) -> None:
    monitor = Monitor(FIXED)
    on_road = []
    for index, yaw in enumerate(yaw_sequence):
        monitor.update(sample(index * FRAME_S, yaw))
        on_road.append(monitor.state.on_road)
    assert on_road == expected_on_road


def test_yaw_flickering_around_the_limit_does_not_restart_the_episode() -> None:
    def yaw_at(t_s: float) -> float:
        if t_s < 1.0:
            return 0.0
        return -26.0 if int(t_s * FPS) % 2 else -23.0  # inside the hysteresis band once off road

    _, alerts = run(yaw_at, 4.5)
    assert kinds(alerts) == [("long_distraction", "warning")]
    assert_within_one_frame(alerts[0].t_s, 1.0 + FRAME_S + 3.0)


def test_five_short_glances_raise_one_vats_and_no_long_distraction() -> None:
    starts = [1.0 + 3.5 * k for k in range(5)]  # 2.5 s glances, 1 s between
    _, alerts = run(glances(starts, 2.5), 20.0)
    assert kinds(alerts) == [("vats", "warning"), ("cleared", "info")]
    # 10 s off road is reached at the end of the fourth glance (4 x 2.5 s); the alert raised on
    # the sample that ends the glance is cleared on the next one.
    assert_within_one_frame(alerts[0].t_s, starts[3] + 2.5)
    assert alerts[0].window_off_road_s == pytest.approx(10.0, abs=1e-6)
    assert_within_one_frame(alerts[1].t_s, starts[3] + 2.5 + FRAME_S)


@pytest.mark.parametrize(
    ("second_start_s", "expected_t_s"),
    [
        (26.0, 30.0),  # 6 s + 4 s of the second glance, the first still fully in the window
        (26.5, None),  # the first glance starts leaving the window before 10 s are reached
        (24.0, 28.0),
    ],
)
def test_vats_window_edges(second_start_s: float, expected_t_s: float | None) -> None:
    config = FIXED.model_copy(update={"long_distraction_s": 100.0, "critical_distraction_s": 200.0})
    _, alerts = run(glances([0.0, second_start_s], 6.0), 34.0, config)
    vats = [a for a in alerts if a.kind is AlertKind.VATS]
    if expected_t_s is None:
        assert vats == []
    else:
        assert len(vats) == 1
        assert_within_one_frame(vats[0].t_s, expected_t_s)


@pytest.mark.parametrize(("gap_s", "expected_vats"), [(1.9, 1), (2.1, 2)])
def test_vats_rearms_only_after_two_seconds_on_road(gap_s: float, expected_vats: int) -> None:
    first = [0.5 + 3.5 * k for k in range(4)]  # fires at the end of the fourth glance
    second_start = first[-1] + 2.5 + gap_s
    _, alerts = run(glances([*first, second_start], 2.5), second_start + 4.0)
    vats = [a for a in alerts if a.kind is AlertKind.VATS]
    assert len(vats) == expected_vats
    if expected_vats == 2:  # the window still holds >= 10 s: fires on the first off-road sample
        assert_within_one_frame(vats[1].t_s, second_start)


@pytest.mark.parametrize(
    ("speed_kmh", "min_speed_kmh", "expect_alerts"),
    [
        (None, 20.0, True),  # no speed known: taken as moving
        (50.0, 20.0, True),
        (20.0, 20.0, False),  # alerts only above the limit
        (10.0, 20.0, False),
        (10.0, 5.0, True),  # configurable
        (0.0, 0.0, False),
    ],
)
def test_speed_gating(speed_kmh: float | None, min_speed_kmh: float, expect_alerts: bool) -> None:
    config = FIXED.model_copy(update={"min_speed_kmh": min_speed_kmh})
    _, alerts = run(glances([1.0], 4.0), 6.0, config, speed_at=lambda t: speed_kmh)
    assert kinds(alerts) == (
        [("long_distraction", "warning"), ("cleared", "info")] if expect_alerts else []
    )


def test_no_vats_when_the_window_fills_as_the_vehicle_stops() -> None:
    starts = [1.0 + 3.5 * k for k in range(4)]  # 10 s off road exactly at t = 14.0 s
    speed = lambda t: 50.0 if t < starts[3] + 2.5 else 5.0  # noqa: E731
    _, alerts = run(glances(starts, 2.5), 16.0, speed_at=speed)
    assert alerts == []


def test_off_road_time_counts_only_from_when_the_vehicle_moves() -> None:
    speed = lambda t: 10.0 if t < 3.0 else 40.0  # noqa: E731
    _, alerts = run(glances([1.0], 7.0), 9.0, speed_at=speed)
    assert kinds(alerts)[0] == ("long_distraction", "warning")
    assert_within_one_frame(alerts[0].t_s, 6.0)


def test_face_lost_after_a_turn_is_off_road_not_unavailable() -> None:
    def yaw_at(t_s: float) -> float | None:
        if t_s < 1.0:
            return 0.0
        if t_s < 1.5:
            return 70.0 * (t_s - 1.0) / 0.5  # turning: passes 25 deg at about t = 1.18 s
        if t_s < 6.0:
            return None  # profile: the landmarker loses the face
        return 0.0

    no_mirrors = FIXED.model_copy(update={"driving_related_zones": []})  # the turn crosses one
    monitor, alerts = run(yaw_at, 8.0, no_mirrors)
    assert kinds(alerts) == [("long_distraction", "warning"), ("cleared", "info")]
    first_off = next(k / FPS for k in range(300) if (yaw_at(k / FPS) or 0.0) > 25.0)
    assert_within_one_frame(alerts[0].t_s, first_off + 3.0)
    assert_within_one_frame(alerts[1].t_s, 6.0)
    assert monitor.state.look.gaze is Gaze.ON_ROAD


@pytest.mark.parametrize(("lost_s", "expected"), [(1.9, []), (2.5, ["driver_unavailable"])])
def test_face_lost_looking_ahead_is_unavailable_after_two_seconds(
    lost_s: float, expected: list[str]
) -> None:
    def yaw_at(t_s: float) -> float | None:
        return None if 1.0 <= t_s < 1.0 + lost_s else 5.0

    _, alerts = run(yaw_at, 6.0)
    assert [a.kind.value for a in alerts] == ([*expected, "cleared"] if expected else [])
    if expected:
        assert_within_one_frame(alerts[0].t_s, 3.0)
        assert alerts[0].unavailable_s == pytest.approx(2.0, abs=FRAME_S)
        assert alerts[1].clears == (AlertKind.DRIVER_UNAVAILABLE,)


def test_no_face_from_the_start_is_unavailable() -> None:
    _, alerts = run(lambda t: None, 3.0)
    assert kinds(alerts) == [("driver_unavailable", "warning")]
    assert_within_one_frame(alerts[0].t_s, 2.0)


def test_explicit_turn_away_angle() -> None:
    config = FIXED.model_copy(update={"turn_away_deg": 50.0})

    def yaw_at(t_s: float) -> float | None:
        return 0.0 if t_s < 1.0 else (40.0 if t_s < 1.5 else None)

    _, alerts = run(yaw_at, 4.0, config)
    # Lost at 40 deg < 50 deg: unexplained, so unavailable 2 s after the loss.
    assert [a.kind for a in alerts] == [AlertKind.DRIVER_UNAVAILABLE]
    assert_within_one_frame(alerts[0].t_s, 3.5)


def test_neutral_settles_on_the_road_pose_then_follows_it_slowly() -> None:
    """A running mean at first (the road pose within a second), then the 60 s filter.

    (Before pitch, the neutral followed the 60 s filter from the start: 15.6 deg after 120 s at
    18 deg; a neutral that takes minutes to settle put the matrix pitch's down gain and the
    lap limit at the camera's axis instead of the driver's road pose for the whole first minute.)
    """
    config = MonitorConfig()  # learning on, time constant 60 s
    monitor, alerts = run(lambda t: 18.0, 1.0, config)
    assert alerts == []
    assert monitor.state.neutral.yaw_deg == pytest.approx(18.0)
    for frame in range(30, round(120 * FPS)):
        monitor.update(sample(frame / FPS, 18.0))
    for frame in range(round(120 * FPS), round(180 * FPS)):
        monitor.update(sample(frame / FPS, 8.0))  # the road pose moves by 10 deg
    # 120 s learned: the running mean's gain is below the filter's, which moves 1 - e^-1 in 60 s.
    assert monitor.state.neutral.yaw_deg == pytest.approx(8.0 + 10.0 * 2.718281828**-1, abs=0.1)
    neutral = monitor.state.neutral.yaw_deg
    monitor.update(sample(180.0, neutral + 26.0))  # 26 deg from the neutral: off road
    assert monitor.state.on_road is False
    monitor.update(sample(181.0, neutral + 21.4))
    assert monitor.state.on_road is False  # inside the hysteresis band
    monitor.update(sample(182.0, neutral + 19.4))
    assert monitor.state.on_road is True  # back within 20


def test_neutral_is_clamped_and_fixed_neutral_is_used_as_is() -> None:
    config = MonitorConfig(neutral_limit_deg=10.0)
    monitor, _ = run(lambda t: 20.0, 600.0, config)
    assert monitor.state.neutral.yaw_deg == pytest.approx(10.0)
    fixed = MonitorConfig(neutral_yaw_deg=30.0)
    monitor, _ = run(lambda t: 30.0, 10.0, fixed)
    assert monitor.state.neutral.yaw_deg == 30.0
    assert monitor.state.on_road is True
    monitor.update(sample(10.0, 0.0))
    assert monitor.state.on_road is False


def test_step_is_pure_and_ignores_time_going_backwards() -> None:
    state0 = initial_state(FIXED)
    state1, alerts = step(FIXED, state0, sample(1.0, 40.0), None)
    assert state0.t_s is None and state1.t_s == 1.0 and alerts == ()
    assert step(FIXED, state0, sample(1.0, 40.0), None) == (state1, ())
    assert step(FIXED, state1, sample(0.5, 0.0), None) == (state1, ())
    assert step(FIXED, state1, sample(1.0, 0.0), None) == (state1, ())


def test_counters_and_levels() -> None:
    monitor, alerts = run(glances([0.5], 7.0), 9.0)
    assert [a.level for a in alerts] == [
        AlertLevel.WARNING,
        AlertLevel.CRITICAL,
        AlertLevel.CRITICAL,
        AlertLevel.INFO,
    ]
    assert dict(monitor.state.alert_counts) == {
        "long_distraction:warning": 1,
        "long_distraction:critical": 1,
        "unresponsive:critical": 1,
        "cleared:info": 1,
    }
    assert monitor.state.samples == 270


def test_monitor_imports_no_heavy_modules() -> None:
    code = (
        "import sys, roadgaze.monitor; "
        "bad = {'cv2', 'mediapipe', 'zenoh'} & set(sys.modules); "
        "sys.exit(1 if bad else 0)"
    )
    env = child_env()
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, timeout=60, env=env, check=False
    )
    assert result.returncode == 0, result.stderr


# Zones: mirrors are driving-related (off road, counted for VATS, no long distraction alone).

Pose = tuple[float, float] | None
"""(yaw, pitch) at a time; None for no face."""


def run_poses(
    pose_at: Callable[[float], Pose], duration_s: float, config: MonitorConfig = FIXED
) -> tuple[Monitor, list[Alert], list[str | None]]:
    monitor = Monitor(config)
    alerts: list[Alert] = []
    zones: list[str | None] = []
    for frame in range(round(duration_s * FPS)):
        t_s = frame / FPS
        pose = pose_at(t_s)
        yaw, pitch = (None, None) if pose is None else pose
        alerts.extend(monitor.update(sample(t_s, yaw, frame, pitch)))
        zones.append(monitor.verdict.zone)
    return monitor, alerts, zones


def segments(*parts: tuple[float, Pose]) -> Callable[[float], Pose]:
    """Consecutive (seconds, pose) parts; the last pose holds afterwards."""

    def pose_at(t_s: float) -> Pose:
        start = 0.0
        for length_s, pose in parts:
            if t_s + 1e-9 < start + length_s:
                return pose
            start += length_s
        return parts[-1][1]

    return pose_at


ROAD_POSE = (0.0, 0.0)
LEFT_MIRROR = (45.0, 0.0)
RIGHT_MIRROR = (-45.0, 0.0)  # -60 before ADDW's area 1 (beyond 55 deg: always distraction)
AWAY_POSE = (AWAY_YAW_DEG, 0.0)
LAP = (0.0, -35.0)


def test_a_mirror_glance_is_off_road_but_raises_no_long_distraction() -> None:
    """(A glance of 3.5 s before the default `driving_glance_max_s` went from 4 s to 2 s.)"""
    _, alerts, zones = run_poses(
        segments((1.0, ROAD_POSE), (1.9, LEFT_MIRROR), (1.5, AWAY_POSE), (2.0, ROAD_POSE)), 6.4
    )
    assert alerts == []
    assert zones[40] == "left_mirror" and zones[-1] == "road"
    inside = Monitor(FIXED)
    for frame in range(round(2.9 * FPS)):
        inside.update(sample(frame / FPS, 0.0 if frame < 30 else 45.0, frame, 0.0))
    verdict = inside.verdict
    assert (verdict.zone, verdict.on_road, verdict.gaze) == ("left_mirror", False, Gaze.OFF_ROAD)
    assert verdict.off_road_s == pytest.approx(1.9 - FRAME_S, abs=1e-6)
    assert verdict.window_off_road_s == pytest.approx(1.9 - FRAME_S, abs=1e-6)
    assert verdict.distraction_s == 0.0


def test_a_mirror_stare_of_the_default_limit_is_a_long_distraction() -> None:
    """Fail-safe default: 2 s in a mirror zone is a stare (or a look out of the side window read
    short: a real 60 deg look reads 47-52 deg on 4 of 10 Pointing'04 subjects); it counts from
    its start, so the warning comes when a look elsewhere would (before: 4 s, at 5 s)."""
    _, alerts, _ = run_poses(segments((1.0, ROAD_POSE), (8.0, LEFT_MIRROR), (2.0, ROAD_POSE)), 11.0)
    assert kinds(alerts)[0] == ("long_distraction", "warning")
    assert_within_one_frame(alerts[0].t_s, 1.0 + 3.0)
    excused = FIXED.model_copy(update={"driving_glance_max_s": None})
    _, none_raised, _ = run_poses(
        segments((1.0, ROAD_POSE), (8.0, LEFT_MIRROR), (2.0, ROAD_POSE)), 11.0, excused
    )
    assert none_raised == []


def test_mirror_glances_count_for_vats() -> None:
    parts: list[tuple[float, Pose]] = [(1.0, ROAD_POSE)]
    for mirror in (LEFT_MIRROR, RIGHT_MIRROR) * 3:
        parts += [(2.5, mirror), (1.0, ROAD_POSE)]
    _, alerts, _ = run_poses(segments(*parts), 22.0)
    assert kinds(alerts) == [("vats", "warning"), ("cleared", "info")]
    assert_within_one_frame(alerts[0].t_s, 1.0 + 3 * 3.5 + 2.5)  # the fourth glance ends at 10 s


@pytest.mark.parametrize(
    ("parts", "expected_s"),
    [
        # mirror 1 s, then away: the timer starts with the away part and fires 3 s into it
        (((1.0, ROAD_POSE), (1.0, LEFT_MIRROR), (5.0, AWAY_POSE)), 1.0 + 1.0 + 3.0),
        # away 0.4 s (a turn passing the road's edge), mirror 1.5 s (pauses, does not reset),
        # away again: 2.6 s more
        (((1.0, ROAD_POSE), (0.4, AWAY_POSE), (1.5, LEFT_MIRROR), (3.0, AWAY_POSE)), 1.0 + 4.5),
        # away 2 s, then a mirror reading: after a look elsewhere (driving_glance_entry_s,
        # 0.5 s) a mirror stay no longer pauses the timer, which fires 1 s into it
        (((1.0, ROAD_POSE), (2.0, AWAY_POSE), (1.5, LEFT_MIRROR), (3.0, AWAY_POSE)), 1.0 + 3.0),
        # mirror 1.5 s then away 2 s: 2 s of distraction, no alert
        (((1.0, ROAD_POSE), (1.5, LEFT_MIRROR), (2.0, AWAY_POSE), (2.0, ROAD_POSE)), None),
        # the lap is not driving-related
        (((1.0, ROAD_POSE), (4.0, LAP), (1.0, ROAD_POSE)), 1.0 + 3.0),
    ],
)
def test_mirror_time_pauses_the_long_distraction_timer(
    parts: tuple[tuple[float, Pose], ...], expected_s: float | None
) -> None:
    total_s = sum(length for length, _ in parts) + 1.0
    _, alerts, _ = run_poses(segments(*parts), total_s)
    long_alerts = [a for a in alerts if a.label == "long_distraction:warning"]
    if expected_s is None:
        assert long_alerts == []
    else:
        assert len(long_alerts) == 1
        assert_within_one_frame(long_alerts[0].t_s, expected_s)
        assert long_alerts[0].off_road_s == pytest.approx(expected_s - 1.0, abs=FRAME_S)


def test_a_mirror_stay_longer_than_the_limit_counts_from_its_start() -> None:
    config = FIXED.model_copy(update={"driving_glance_max_s": 2.0})
    _, alerts, _ = run_poses(
        segments((1.0, ROAD_POSE), (5.0, LEFT_MIRROR), (1.0, ROAD_POSE)), 7.0, config
    )
    assert kinds(alerts) == [("long_distraction", "warning"), ("cleared", "info")]
    assert_within_one_frame(alerts[0].t_s, 1.0 + 3.0)
    _, short, _ = run_poses(
        segments((1.0, ROAD_POSE), (1.9, LEFT_MIRROR), (2.0, AWAY_POSE), (1.0, ROAD_POSE)),
        6.0,
        config,
    )
    assert short == []  # 1.9 s of mirror is a glance; 2 s away is not yet a long distraction


def test_a_face_lost_in_a_mirror_glance_counts_as_away() -> None:
    _, alerts, zones = run_poses(
        segments((1.0, ROAD_POSE), (1.0, LEFT_MIRROR), (4.0, None), (1.0, ROAD_POSE)), 7.0
    )
    assert zones[45] == "left_mirror" and zones[75] == "away"
    assert kinds(alerts) == [("long_distraction", "warning"), ("cleared", "info")]
    assert_within_one_frame(alerts[0].t_s, 2.0 + 3.0)  # from the loss: out of view is not a mirror


def test_pitch_neutral_is_learned_and_looking_down_is_the_lap() -> None:
    config = MonitorConfig(neutral_yaw_deg=0.0)  # pitch neutral learned
    camera_low = 12.0  # the road-ahead pose seen from a camera below the line of sight
    monitor, alerts, zones = run_poses(lambda t: (0.0, camera_low), 3.0, config)
    assert alerts == [] and set(zones) == {"road"}
    assert monitor.state.neutral.pitch_deg == pytest.approx(camera_low)
    neutral = monitor.state.neutral.pitch_deg
    monitor.update(sample(3.0, 0.0, 0, neutral - 19.0))
    assert monitor.verdict.zone == "lap"  # 19 deg below the neutral, 7 deg below the camera axis
    fixed = MonitorConfig(neutral_yaw_deg=0.0, neutral_pitch_deg=-5.0)
    monitor, _, zones = run_poses(lambda t: (0.0, -25.0), 2.0, fixed)
    assert monitor.state.neutral.pitch_deg == -5.0 and zones[-1] == "lap"


def test_a_sample_without_pitch_is_judged_at_level_pitch() -> None:
    _, _, zones = run_poses(lambda t: None if t < 0 else (0.0, float("nan")), 1.0)
    assert zones[-1] == "road"


def test_a_road_pose_outside_the_road_zone_at_first_is_still_learned() -> None:
    """A camera 16 deg above the line of sight: the road pose reads pitch -16 (below the road
    zone while the neutral is 0); it is learned within a second and never raises an alert."""
    config = MonitorConfig(neutral_yaw_deg=0.0)
    monitor, alerts, zones = run_poses(lambda t: (0.0, -16.0), 10.0, config)
    assert alerts == []
    assert zones[0] == "cluster" and zones[-1] == "road"
    assert zones.index("road") <= FPS  # within a second
    assert monitor.state.neutral.pitch_deg == pytest.approx(-16.0)
    lap_glance, _, _ = run_poses(lambda t: (0.0, -16.0 if t < 2.0 else -45.0), 6.0, config)
    assert lap_glance.state.neutral.pitch_deg == pytest.approx(-16.0)  # a lap glance does not teach
    assert lap_glance.verdict.zone == "lap"


def test_a_turn_held_just_past_the_road_edge_early_in_a_drive_is_not_learned_as_ahead() -> None:
    """3 s ahead, an eased half-second turn to about -27 deg held 5 s (how the one-face landmarker
    reads `roadgaze synth --timeline '0:3,-30:5,0:3'`): the turn must raise long_distraction.

    Before, samples within 25 deg of the neutral taught it: the transition moved the running
    mean to about -2 deg, which brought the held turn within 25 deg, and the turn itself walked
    the neutral to -8.5 deg here (-14.3 on the real clip, where the turn then read as road after
    2.3 s and no alert fired). Now only samples within the road's entry bound (20 deg) teach.
    """

    def yaw_at(t: float) -> float:
        if t < 3.0:
            return -0.8
        if t < 3.5:
            u = (t - 3.0) / 0.5
            return -0.8 - 27.0 * (3 * u * u - 2 * u**3)
        return -27.8 + 0.15 * (t - 3.5) if t < 8.5 else -0.8  # as read: -27.8 drifting to -27.1

    monitor, alerts = run(yaw_at, 11.0, MonitorConfig())
    assert monitor.state.neutral.yaw_deg > -3.0, monitor.state.neutral.yaw_deg
    kinds = [a.kind for a in alerts]
    assert AlertKind.LONG_DISTRACTION in kinds


def test_a_mirror_reading_after_a_look_elsewhere_goes_on_counting() -> None:
    """`driving_glance_entry_s`: a 70 deg look right read, under a hat's brim, partly as 50 deg
    (the right mirror's zone) with the face lost between, used to pause at every mirror reading
    and warned only after the look; the readings after the look began no longer pause it. None
    keeps every mirror stay paused (before)."""
    parts = ((1.0, ROAD_POSE), (1.0, AWAY_POSE), (0.6, None), (1.2, RIGHT_MIRROR), (1.2, None))
    _, alerts, _ = run_poses(segments(*parts, (1.0, ROAD_POSE)), 6.4)
    assert kinds(alerts)[0] == ("long_distraction", "warning")
    assert_within_one_frame(alerts[0].t_s, 1.0 + 3.0)
    every = FIXED.model_copy(update={"driving_glance_entry_s": None})
    _, before, _ = run_poses(segments(*parts, (1.0, ROAD_POSE)), 6.4, every)
    assert [a for a in before if a.label == "long_distraction:warning"] == []
