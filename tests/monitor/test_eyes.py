"""The eye monitor on hand-made samples: the closed/open rule, closures and their ladder, blinks,
PERCLOS against closed forms, gaze with its deadband, unavailable eyes and degraded, speed."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from fakes import eyes_of
from roadgaze.config import MonitorConfig
from roadgaze.monitor.eye_rules import classify_eyes, firm_threshold, gaze_deg, soft_threshold
from roadgaze.monitor.eyes import EyesAlone, clearable_eye_kinds, step_eyes
from roadgaze.types import (
    AlertKind,
    EyeMeasurement,
    EyesFeatures,
    EyeStatus,
    FaceFeatures,
    PoseSample,
)

CONFIG = MonitorConfig()
FPS = 15.0


def face(mp_pitch_deg: float = 0.0) -> FaceFeatures:
    return FaceFeatures(
        x_left_px=0.0,
        x_right_px=1.0,
        x_center_px=0.5,
        roll_deg=0.0,
        box_px=(0.0, 0.0, 1.0, 1.0),
        quality=1.0,
        landmarks_px=np.zeros((0, 3), np.float32),
        mediapipe_pitch_deg=mp_pitch_deg,
    )


def sample(t_s: float, eyes: EyesFeatures | None, mp_pitch_deg: float = 0.0) -> PoseSample:
    has_face = eyes is not None
    return PoseSample(
        t_s=t_s,
        frame=round(t_s * FPS),
        face=has_face,
        yaw_raw_deg=0.0 if has_face else None,
        yaw_deg=0.0 if has_face else None,
        yaw_rate_dps=None,
        yaw_std_deg=None,
        features=face(mp_pitch_deg) if has_face else None,
        eyes=eyes,
    )


def drive(
    segments: list[tuple[float, dict[str, object]]],
    speed_moving: bool = True,
    config: MonitorConfig = CONFIG,
) -> tuple[list[tuple[float, AlertKind, str]], list[EyesAlone]]:
    """Run segments of (seconds, eyes_of kwargs | {'face': False} | {'mp_pitch': deg, ...})."""
    state = EyesAlone()
    events: list[tuple[float, AlertKind, str]] = []
    states: list[EyesAlone] = []
    t = 0.0
    for seconds, kwargs in segments:
        end = t + seconds
        while t < end - 1e-9:
            options = dict(kwargs)
            mp_pitch = float(options.pop("mp_pitch", 0.0))  # type: ignore[arg-type]
            eyes = None if options.pop("face", True) is False else eyes_of(**options)  # type: ignore[arg-type]
            gaze = state.verdict.gaze_yaw_deg
            on_road = gaze is None or abs(gaze) <= 15.0  # the monitor's previous decision
            state, raised = step_eyes(
                config, state, sample(t, eyes, mp_pitch), speed_moving, on_road, 0.0, mp_pitch
            )
            events += [(t, event.kind, event.reason) for event in raised]
            states.append(state)
            t = round(t + 1 / FPS, 9)
    return events, states


@pytest.mark.parametrize(
    ("openness", "blink", "below", "was_closed", "expected"),
    [
        (0.30, 0.05, 0.0, None, (EyeStatus.OPEN, "")),
        (0.09, 0.10, 0.0, None, (EyeStatus.CLOSED, "eyes closed")),  # hard: blink not needed
        (0.12, 0.50, 0.0, None, (EyeStatus.CLOSED, "eyes closed")),  # blink agrees
        (0.12, 0.30, 0.0, None, (EyeStatus.OPEN, "")),  # blink disagrees
        (0.12, None, 0.0, None, (EyeStatus.CLOSED, "eyes closed")),  # no blendshapes
        (0.16, 0.60, 0.0, True, (EyeStatus.CLOSED, "eyes closed")),  # hysteresis
        (0.19, 0.60, 0.0, True, (EyeStatus.OPEN, "")),
        (0.05, 0.70, 12.0, False, (EyeStatus.OPEN, "looking down")),  # head lowered
        (0.05, 0.70, 12.0, True, (EyeStatus.CLOSED, "eyes closed")),  # closed before it dropped
        (0.05, 0.70, 6.0, None, (EyeStatus.OPEN, "looking down")),  # beyond 4 deg
        (0.05, 0.70, 3.0, None, (EyeStatus.CLOSED, "eyes closed")),
    ],
)
def test_closed_or_open(
    openness: float,
    blink: float | None,
    below: float,
    was_closed: bool | None,
    expected: tuple[EyeStatus, str],
) -> None:
    eyes = eyes_of(openness, blink)
    if blink is None:
        eyes = EyesFeatures(
            right=_no_blink(eyes.right), left=_no_blink(eyes.left), method="iris", scale_px=30.0
        )
    assert classify_eyes(CONFIG, eyes, below, was_closed) == expected


def _no_blink(eye: EyeMeasurement) -> EyeMeasurement:
    from dataclasses import replace

    return replace(eye, blink=None)


def test_unavailable_eyes_and_the_baseline_scaling() -> None:
    assert classify_eyes(CONFIG, None, None) == (EyeStatus.UNAVAILABLE, "no eyes measured")
    assert classify_eyes(CONFIG, eyes_of(usable=False), 0.0)[0] is EyeStatus.UNAVAILABLE
    assert classify_eyes(CONFIG, eyes_of(occluded=True), 0.0) == (
        EyeStatus.UNAVAILABLE,
        "eyes hidden",
    )
    # A fist read as shut lids: hidden by a hand, never closed (no microsleep from a hand).
    fist = replace(eyes_of(0.02, 0.9, occluded=True), occluded_by="hand")
    assert classify_eyes(CONFIG, fist, 0.0) == (EyeStatus.UNAVAILABLE, "eyes hidden by a hand")
    fringe = replace(eyes_of(occluded=True), occluded_by="strands")
    assert classify_eyes(CONFIG, fringe, 0.0)[1] == "eyes hidden by strands across them"
    # A driver whose open eyes read 0.39 (x1.3): 0.12 is closed for them even with a low blink.
    assert classify_eyes(CONFIG, eyes_of(0.12, 0.1), 0.0, open_baseline=0.39)[0] is (
        EyeStatus.CLOSED
    )
    assert classify_eyes(CONFIG, eyes_of(0.12, 0.1), 0.0, open_baseline=0.9)[0] is (
        EyeStatus.CLOSED
    )  # the factor is clamped at 1.3


def test_soft_threshold_and_gaze() -> None:
    assert soft_threshold(8.0, 10.0) == 0.0
    assert soft_threshold(-30.0, 10.0) == -20.0
    assert gaze_deg(5.0, -2.0, None, 10.0) == (5.0, -2.0, False)
    assert gaze_deg(5.0, -2.0, eyes_of(eye_yaw=-30.0, eye_pitch=4.0), 10.0) == (-15.0, -2.0, True)
    assert gaze_deg(0.0, 0.0, eyes_of(eye_yaw=-30.0), 10.0, (-25.0, 0.0))[0] == 0.0


@pytest.mark.parametrize(
    ("value", "full_factor", "expected"),
    [
        (8.0, 2.0, 0.0),  # within the deadband: nothing
        (10.0, 2.0, 0.0),  # continuous at the deadband
        (15.0, 2.0, 10.0),  # the ramp: 20 (15 - 10) / 10
        (-18.0, 2.0, -16.0),
        (20.0, 2.0, 20.0),  # continuous at twice the deadband
        (-25.8, 2.0, -25.8),  # beyond: all of it (soft: -15.8)
        (15.0, 3.0, 7.5),  # a longer ramp: 30 (15 - 10) / 20
        (10.5, 1.0, 10.5),  # 1: a hard threshold
        (-25.8, math.inf, -15.8),  # infinite: the soft threshold
    ],
)
def test_firm_threshold_closed_forms(value: float, full_factor: float, expected: float) -> None:
    assert firm_threshold(value, 10.0, full_factor) == pytest.approx(expected)


def test_open_eyes_raise_nothing_and_blinks_are_counted() -> None:
    blinks = [(1.8, {}), (0.2, {"openness": 0.08})] * 10
    events, states = drive([(2.0, {}), *blinks, (2.0, {})])
    assert events == []
    last = states[-1].verdict
    assert last.status is EyeStatus.OPEN and last.blinks == 10 and last.long_blinks == 0
    assert last.last_blink_s == pytest.approx(0.2, abs=1 / FPS)


@pytest.mark.parametrize(
    ("closed_s", "expected"),
    [
        (0.9, []),
        (1.5, [(1.0, AlertKind.MICROSLEEP)]),
        (4.0, [(1.0, AlertKind.MICROSLEEP), (3.0, AlertKind.SLEEP)]),
        (
            7.0,
            [(1.0, AlertKind.MICROSLEEP), (3.0, AlertKind.SLEEP), (6.0, AlertKind.UNRESPONSIVE)],
        ),
    ],
)
def test_closure_ladder_fires_within_one_frame_of_each_threshold(
    closed_s: float, expected: list[tuple[float, AlertKind]]
) -> None:
    events, states = drive([(2.0, {}), (closed_s, {"openness": 0.08}), (1.0, {})])
    assert [kind for _, kind, _ in events] == [kind for _, kind in expected]
    for (t, _, _), (after_s, _) in zip(events, expected, strict=True):
        assert 0.0 <= t - 2.0 - after_s < 1 / FPS + 1e-9
    assert states[-1].eyes.closure_s() == 0.0 and states[-1].verdict.status is EyeStatus.OPEN
    assert AlertKind.MICROSLEEP in clearable_eye_kinds(states[-1], on_road=True)
    assert AlertKind.MICROSLEEP not in clearable_eye_kinds(states[-1], on_road=False)


def test_a_short_loss_of_the_eyes_inside_a_closure_does_not_end_it() -> None:
    events, _ = drive(
        [(2.0, {}), (0.6, {"openness": 0.08}), (0.2, {"usable": False}), (0.6, {"openness": 0.08})]
    )
    assert [kind for _, kind, _ in events] == [AlertKind.MICROSLEEP]
    events, _ = drive(
        [(2.0, {}), (0.6, {"openness": 0.08}), (0.6, {"usable": False}), (0.6, {"openness": 0.08})]
    )
    assert events == []


def test_a_closure_that_starts_with_the_head_up_stays_closed_when_the_head_drops() -> None:
    events, states = drive(
        [(3.0, {}), (0.5, {"openness": 0.08}), (2.0, {"openness": 0.05, "mp_pitch": -20.0})]
    )
    assert [kind for _, kind, _ in events] == [AlertKind.MICROSLEEP]
    # Lowering the head with narrowed lids from open eyes is looking down.
    events, states = drive([(3.0, {}), (3.0, {"openness": 0.05, "mp_pitch": -20.0})])
    assert events == [] and states[-1].verdict.reason == "looking down"


def test_narrowed_lids_with_the_iris_read_aside_are_a_glance_not_a_closure() -> None:
    # Calibrated at rest (yaw 0): lids at 0.08 with the eyes read 25 deg aside are a glance.
    events, states = drive([(4.0, {}), (3.5, {"openness": 0.08, "eye_yaw": 25.0})])
    assert not [kind for _, kind, _ in events if kind is AlertKind.MICROSLEEP]
    assert states[-1].eyes.status is EyeStatus.OPEN and states[-1].verdict.reason == "looking aside"
    # The same lids with the iris read in the middle (a shut lid's reading) are a closure.
    events, _ = drive([(4.0, {}), (3.5, {"openness": 0.08, "eye_yaw": 6.0})])
    assert AlertKind.MICROSLEEP in [kind for _, kind, _ in events]
    # A closure that began centred stays one when the reading then slides aside.
    events, states = drive(
        [(4.0, {}), (0.5, {"openness": 0.08}), (2.0, {"openness": 0.08, "eye_yaw": 25.0})]
    )
    assert AlertKind.MICROSLEEP in [kind for _, kind, _ in events]
    assert states[-1].eyes.status is EyeStatus.CLOSED
    # Before the eyes are calibrated nothing is excused, and the setting turns the rule off.
    events, _ = drive([(0.5, {}), (3.0, {"openness": 0.08, "eye_yaw": 25.0})])
    assert AlertKind.MICROSLEEP in [kind for _, kind, _ in events]
    off = MonitorConfig(closure_needs_centred_iris=False)
    events, _ = drive([(4.0, {}), (3.5, {"openness": 0.08, "eye_yaw": 25.0})], config=off)
    assert AlertKind.MICROSLEEP in [kind for _, kind, _ in events]


def test_perclos_matches_the_closed_share_and_memory_stays_bounded() -> None:
    # 0.8 s open then 0.2 s closed (blinks, each shorter than the microsleep time): 20 %.
    config = MonitorConfig(long_blinks_drowsy=1000)
    events, states = drive([(0.8, {}), (0.2, {"openness": 0.08})] * 120, config=config)
    last = states[-1]
    assert last.verdict.perclos == pytest.approx(0.2, abs=0.02)
    assert len(last.eyes.bins) <= 61 and len(last.eyes.blinks) <= 61
    assert [kind for _, kind, _ in events] == [AlertKind.DROWSY]
    assert 30.0 - 1e-6 <= events[0][0] <= 31.0  # reported once 30 s are judged
    assert states[200].verdict.perclos is None  # 13 s judged: not yet


def test_long_blinks_make_drowsy_and_it_rearms() -> None:
    long_blinks = [(1.4, {}), (0.6, {"openness": 0.08})] * 3
    events, states = drive([(2.0, {}), *long_blinks, (70.0, {})])
    assert [kind for _, kind, _ in events] == [AlertKind.DROWSY]
    assert states[-1].drowsy.armed
    assert AlertKind.DROWSY in clearable_eye_kinds(states[-1], on_road=True)


def test_unavailable_eyes_degrade_after_ten_seconds_and_recover() -> None:
    events, states = drive([(2.0, {}), (12.0, {"usable": False}), (1.0, {})])
    assert [kind for _, kind, _ in events] == [AlertKind.DEGRADED]
    assert 12.0 - 1e-6 <= events[0][0] < 12.0 + 1 / FPS
    assert "head turned" in events[0][2]
    during = states[round(13.0 * FPS)]
    assert during.verdict.degraded and during.verdict.gaze_source == "head"
    assert AlertKind.DEGRADED not in clearable_eye_kinds(during, on_road=True)
    assert not states[-1].verdict.degraded
    events, _ = drive([(2.0, {}), (12.0, {"face": False})])
    assert [kind for _, kind, _ in events] == [AlertKind.DEGRADED]


def test_nothing_is_raised_when_not_moving() -> None:
    events, states = drive(
        [(2.0, {}), (4.0, {"openness": 0.08}), (12.0, {"usable": False})], speed_moving=False
    )
    assert events == [] and states[-1].verdict.unavailable_s == 0.0


def test_the_eye_neutral_is_learned_on_the_road_and_gaze_uses_it() -> None:
    _, states = drive([(30.0, {"eye_yaw": -6.0, "eye_pitch": 3.0})])
    neutral = states[-1].eyes.eye_neutral_deg
    assert neutral == pytest.approx((-6.0, 3.0), abs=0.1)
    _, states = drive([(30.0, {"eye_yaw": -6.0}), (1.0, {"eye_yaw": -36.0})])
    assert states[-1].verdict.gaze_yaw_deg == pytest.approx(-30.0, abs=0.5)  # 3 thresholds: all
    assert states[-1].verdict.gaze_source == "eyes"
    _, states = drive([(2.0, {}), (1.0, {"openness": 0.05})])
    assert states[-1].verdict.gaze_source == "head"  # closed eyes give no direction


def test_samples_out_of_order_are_ignored() -> None:
    state, _ = step_eyes(CONFIG, EyesAlone(), sample(1.0, eyes_of()), True, True, 0.0, 0.0)
    again, events = step_eyes(CONFIG, state, sample(0.5, eyes_of()), True, True, 0.0, 0.0)
    assert again is state and events == ()


def test_lids_that_read_closed_on_blurred_eyes_are_not_judged() -> None:
    blurred = replace(eyes_of(0.06, 0.7), blurred=True)
    assert classify_eyes(CONFIG, blurred, 0.0) == (EyeStatus.UNAVAILABLE, "eyes blurred")
    assert classify_eyes(CONFIG, replace(eyes_of(0.30), blurred=True), 0.0) == (EyeStatus.OPEN, "")
    # once closed (a closure seen sharp), blur does not end it
    assert classify_eyes(CONFIG, blurred, 0.0, was_closed=True)[0] is EyeStatus.CLOSED


@pytest.mark.parametrize(("far_openness", "expected"), [(0.20, "eyes disagree"), (0.08, "")])
def test_one_judged_eye_closes_only_if_the_other_does_not_read_open(
    far_openness: float, expected: str
) -> None:
    both = eyes_of(0.06, 0.7)
    far = replace(both.left, openness=far_openness, closure_usable=False, reason="far eye")
    status, reason = classify_eyes(CONFIG, replace(both, left=far), 0.0)
    if expected:
        assert (status, reason) == (EyeStatus.UNAVAILABLE, expected)
    else:
        assert (status, reason) == (EyeStatus.CLOSED, "eyes closed")
