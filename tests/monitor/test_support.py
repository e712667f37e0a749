"""Forward and lane support on scripted tracks: raised at the first sample the driver stops
watching the road (any zone, driving-task glances included), held until the clear time on the
road, held to the end of the trip after an impairment alert, heightened whenever the service
cannot tell. Times are closed forms at 15 fps (`support_raise_s` 0, `support_clear_s` 2)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import pytest

from fakes import eyes_of, face_sample
from roadgaze.config import MonitorConfig
from roadgaze.monitor import Monitor
from roadgaze.monitor.behaviours.support import support_output
from roadgaze.monitor.context import Context
from roadgaze.monitor.events import Event, Raise, Rule
from roadgaze.monitor.protocols import behaviours
from roadgaze.types import (
    Alert,
    AlertKind,
    AlertLevel,
    EyesFeatures,
    HandSide,
    Output,
    PhoneJudgement,
    PhonePose,
)

FPS = 15.0
CONFIG = MonitorConfig(neutral_yaw_deg=0.0, neutral_pitch_deg=0.0)


@dataclass(frozen=True)
class Pose:
    """What the script shows at one time: head yaw/pitch, the eyes (None: no face), speed."""

    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    eyes: EyesFeatures | None = None
    face: bool = True
    ambiguous: str = ""
    speed_kmh: float | None = 70.0
    phone: PhoneJudgement | None = None


Script = Callable[[float], Pose]
AHEAD = Pose(eyes=eyes_of())


def drive(
    script: Script,
    duration_s: float,
    config: MonitorConfig = CONFIG,
    monitor: Monitor | None = None,
) -> tuple[list[tuple[float, Output, Output]], list[Alert]]:
    """(t, forward, lane) at every frame, and every alert."""
    monitor = monitor or Monitor(config)
    seen: list[tuple[float, Output, Output]] = []
    alerts: list[Alert] = []
    for frame in range(round(duration_s * FPS)):
        t_s = frame / FPS
        pose = script(t_s)
        face = pose.face
        sample = face_sample(
            t_s,
            frame,
            pose.yaw_deg,
            pose.pitch_deg,
            pose.eyes,
            face,
            n_faces=2 if pose.ambiguous else int(face),
            driver_ambiguous=pose.ambiguous,
            phone=pose.phone,
        )
        alerts.extend(monitor.update(sample, pose.speed_kmh))
        forward = support_output(monitor.verdict, "forward")
        lane = support_output(monitor.verdict, "lane")
        assert forward is not None and lane is not None
        seen.append((t_s, forward, lane))
    return seen, alerts


def glance(start_s: float, end_s: float, during: Pose, outside: Pose = AHEAD) -> Script:
    return lambda t_s: during if start_s <= t_s + 1e-9 < end_s else outside


def first(seen: list[tuple[float, Output, Output]], value: str, after_s: float) -> float:
    """The first frame at or after `after_s` where forward support is `value`."""
    return next(t for t, forward, _ in seen if t >= after_s - 1e-9 and forward.value == value)


def at(seen: list[tuple[float, Output, Output]], t_s: float) -> Output:
    return next(forward for t, forward, _ in seen if abs(t - t_s) < 1e-6)


def test_support_starts_heightened_until_the_driver_has_watched_the_road_the_clear_time() -> None:
    seen, _ = drive(lambda t: AHEAD, 3.0)
    assert seen[0][1].value == "heightened" and seen[0][1].since_s == 0.0
    assert first(seen, "normal", 0.0) == pytest.approx(2.0)  # support_clear_s
    normal = at(seen, 2.0)
    assert (normal.rule, normal.reason, normal.since_s) == (
        "roadgaze.support.forward.clear",
        "watching the road 2 s",
        2.0,
    )
    assert "roadgaze's choice" in normal.source


def test_a_4_s_mirror_look_raises_support_at_its_first_sample_held_until_the_clear_time() -> None:
    mirror = Pose(yaw_deg=35.0, eyes=eyes_of())  # left_mirror: a driving-task glance
    seen, alerts = drive(
        glance(3.0, 7.0, mirror), 10.0, CONFIG.model_copy(update={"driving_glance_max_s": None})
    )
    assert first(seen, "heightened", 2.5) == pytest.approx(3.0)  # the look's first sample
    raised = at(seen, 3.0)
    assert (raised.rule, raised.reason, raised.since_s) == (
        "euroncap.support.forward",
        "head in left_mirror",
        3.0,
    )
    assert all(forward.value == "heightened" for t, forward, _ in seen if 3.0 <= t < 9.0 - 1e-9)
    assert at(seen, 8.0).reason == "watching the road 1.0 s of 2"
    assert first(seen, "normal", 3.0) == pytest.approx(9.0)  # back at 7.0 + support_clear_s
    assert at(seen, 9.0).since_s == pytest.approx(9.0)
    assert alerts == []  # a mirror look warns of nothing: support is all it raises
    assert [lane.value for _, _, lane in seen] == [forward.value for _, forward, _ in seen]
    assert at(seen, 3.0).rule != seen[45][2].rule  # each channel names its own rule
    assert seen[45][2].rule == "euroncap.support.lane"


@pytest.mark.parametrize(
    ("yaw_deg", "pitch_deg", "zone"),
    [
        (0.0, -30.0, "lap"),
        (0.0, -16.5, "cluster"),  # the road is left below -15 (hysteresis)
        (-35.0, -20.0, "centre_stack"),
        (35.0, 0.0, "left_mirror"),
        (-40.0, 0.0, "right_mirror"),
        (70.0, 0.0, "far_left"),
        (-70.0, 0.0, "far_right"),
        (0.0, 30.0, "roof"),
    ],
)
def test_every_non_road_zone_raises_support_at_the_first_sample(
    yaw_deg: float, pitch_deg: float, zone: str
) -> None:
    look = Pose(yaw_deg=yaw_deg, pitch_deg=pitch_deg, eyes=eyes_of())
    seen, _ = drive(glance(3.0, 4.0, look), 7.0)
    assert first(seen, "heightened", 2.5) == pytest.approx(3.0)
    assert at(seen, 3.0).reason == f"head in {zone}"
    assert first(seen, "normal", 3.0) == pytest.approx(6.0)


@pytest.mark.parametrize(("yaw_deg", "pitch_deg"), [(22.0, 0.0), (-24.0, 0.0), (0.0, -12.0)])
def test_a_head_past_the_road_entry_bound_raises_support_while_the_zone_stays_the_road(
    yaw_deg: float, pitch_deg: float
) -> None:
    # a 30 deg mirror look whose head reads 22-24 deg: past the road's entry bound (20 deg),
    # inside its exit bound (25 deg), so the zone is still the road and nothing warns
    look = Pose(yaw_deg=yaw_deg, pitch_deg=pitch_deg, eyes=eyes_of())
    seen, alerts = drive(glance(3.0, 7.0, look), 10.0)
    assert first(seen, "heightened", 2.5) == pytest.approx(3.0)
    raised = at(seen, 3.0)
    assert (raised.rule, raised.reason) == (
        "euroncap.support.forward",
        "head past the road's edge",
    )
    assert first(seen, "normal", 3.0) == pytest.approx(9.0)  # back at 7.0 + support_clear_s
    assert alerts == []  # on the road by hysteresis: no distraction
    off = CONFIG.model_copy(update={"support_road_edge": False})
    seen, _ = drive(glance(3.0, 7.0, look), 10.0, off)
    assert all(forward.value == "normal" for t, forward, _ in seen if t >= 2.0 - 1e-9)


def test_a_head_within_the_road_entry_bound_keeps_support_normal() -> None:
    look = Pose(yaw_deg=19.0, pitch_deg=-9.0, eyes=eyes_of())
    seen, _ = drive(glance(3.0, 7.0, look), 10.0)
    assert all(forward.value == "normal" for t, forward, _ in seen if t >= 2.0 - 1e-9)


def test_support_raise_s_delays_the_raise_and_a_shorter_glance_raises_nothing() -> None:
    config = CONFIG.model_copy(update={"support_raise_s": 0.4})
    look = Pose(yaw_deg=0.0, pitch_deg=-30.0, eyes=eyes_of())
    seen, _ = drive(glance(3.0, 4.0, look), 7.0, config)
    assert first(seen, "heightened", 2.5) == pytest.approx(3.4)  # 3.0 + 0.4, a frame exactly
    seen, _ = drive(glance(3.0, 3.3, look), 7.0, config)
    assert all(forward.value == "normal" for t, forward, _ in seen if t >= 2.0)


def test_raise_s_is_bounded_by_the_half_second() -> None:
    with pytest.raises(ValueError, match="support_raise_s"):
        MonitorConfig(support_raise_s=0.6)


def test_closed_eyes_on_the_road_raise_support() -> None:
    seen, _ = drive(glance(3.0, 3.6, Pose(eyes=eyes_of(openness=0.05))), 7.0)
    assert first(seen, "heightened", 2.5) == pytest.approx(3.0)
    assert at(seen, 3.0).reason == "eyes closed"
    assert first(seen, "normal", 3.0) == pytest.approx(5.6)


LONG_BLINK = Pose(eyes=eyes_of(openness=0.05))


def blinks_then_road(t_s: float) -> Pose:
    """Three long blinks of 0.6 s (at 3, 5, 7 s): `drowsy` (long_blinks_drowsy), then the road."""
    return LONG_BLINK if any(b <= t_s + 1e-9 < b + 0.6 for b in (3.0, 5.0, 7.0)) else AHEAD


def test_drowsiness_holds_support_to_the_end_of_the_trip() -> None:
    seen, alerts = drive(blinks_then_road, 40.0)
    drowsy = next(a for a in alerts if a.kind is AlertKind.DROWSY)
    held = [forward for t, forward, _ in seen if t >= drowsy.t_s - 1e-9]
    assert all(forward.value == "heightened" for forward in held)
    assert held[-1].rule == "euroncap.support.forward.impaired"
    assert held[-1].reason == "drowsy (euroncap.drowsiness): to the end of the trip"
    assert "next ignition cycle" in held[-1].source
    # heightened since the first blink: the next ones came before the clear time (2 s) ran out
    assert held[-1].since_s == pytest.approx(3.0)
    released = CONFIG.model_copy(update={"support_hold_impaired": False})
    seen, _ = drive(blinks_then_road, 40.0, released)
    assert seen[-1][1].value == "normal"


@dataclass(frozen=True, slots=True)
class RaisesAt:
    """A test behaviour: raises `degraded` by `rule` at `t_s`."""

    rule: Rule
    t_s: float

    def initial(self) -> None:
        return None

    def step(self, context: Context, state: None) -> tuple[None, tuple[Event, ...]]:
        if abs(context.t_s - self.t_s) > 1e-6:
            return None, ()
        return None, (Raise(AlertKind.DEGRADED, AlertLevel.WARNING, self.rule, "test"),)


@pytest.mark.parametrize("impairment", [True, False])
def test_any_alert_by_a_rule_marked_impairment_holds_support(impairment: bool) -> None:
    rule = Rule("test.impaired", "microsleep_s", "s", "a test", "a test", impairment=impairment)
    *others, clearing = behaviours(CONFIG.protocol)
    supports = [b for b in others if type(b).__name__ == "Support"]
    before = [b for b in others if type(b).__name__ != "Support"]
    monitor = Monitor(CONFIG, behaviours=(*before, RaisesAt(rule, 4.0), *supports, clearing))
    seen, _ = drive(lambda t: AHEAD, 10.0, monitor=monitor)
    assert seen[-1][1].value == ("heightened" if impairment else "normal")


@pytest.mark.parametrize(
    ("pose", "reason"),
    [
        (Pose(face=False), "no face"),
        (Pose(eyes=eyes_of(), ambiguous="two faces of similar size"), "two faces: "),
        (Pose(eyes=None), "eyes unavailable"),
        (Pose(eyes=eyes_of(occluded=True)), "eyes unavailable"),
        (Pose(eyes=eyes_of(), speed_kmh=None), "speed unknown"),
    ],
)
def test_support_fails_safe_when_the_service_cannot_tell(pose: Pose, reason: str) -> None:
    seen, _ = drive(glance(3.0, 4.0, pose), 7.0)
    assert first(seen, "heightened", 2.5) == pytest.approx(3.0)
    raised = at(seen, 3.0)
    assert raised.reason.startswith(reason), raised.reason
    assert raised.rule == "roadgaze.support.forward.unknown"
    assert first(seen, "normal", 3.0) == pytest.approx(6.0)


def test_each_channel_runs_before_clearing_with_documented_rules() -> None:
    from roadgaze.monitor.behaviours import Support
    from roadgaze.monitor.protocols import ALL_RULES

    supports = [b for b in behaviours("both") if isinstance(b, Support)]
    assert [s.channel for s in supports] == ["forward", "lane"]
    for behaviour in supports:
        for rule in behaviour.rules.all:
            assert rule in ALL_RULES and rule.source
            assert hasattr(CONFIG, rule.config_key)


IN_HAND = PhoneJudgement(phone_use=True, score=0.9, hand=HandSide.RIGHT, pose=PhonePose.HELD_UP)
NO_PHONE = PhoneJudgement(phone_use=False, score=0.1)


def test_a_phone_held_up_on_the_road_raises_support_with_its_warning_not_per_frame() -> None:
    # Eyes on the road throughout; the phone judged in hand from 3 s to 8 s: phone_use warns
    # after phone_use_s (3 s), at 6 s, and support with it; put down at 8 s, the alert clears
    # after phone_gap_s (0.7 s, at frame 130) and support after the clear time (2 s) on the road.
    held = Pose(eyes=eyes_of(), phone=IN_HAND)
    seen, alerts = drive(glance(3.0, 8.0, held, Pose(eyes=eyes_of(), phone=NO_PHONE)), 12.0,
                         MonitorConfig(neutral_yaw_deg=0.0, neutral_pitch_deg=0.0,
                                       protocol="euroncap"))  # fmt: skip
    assert [(round(a.t_s, 2), a.kind) for a in alerts] == [
        (6.0, AlertKind.PHONE_USE),
        (8.67, AlertKind.CLEARED),
    ]
    assert first(seen, "heightened", 3.0) == pytest.approx(6.0)  # not at the first frame in hand
    assert at(seen, 6.0).reason == "phone in use"
    # Watching the road counts from the frame after the alert cleared (frame 131).
    assert first(seen, "normal", 6.0) == pytest.approx(131 / FPS + 2.0)
