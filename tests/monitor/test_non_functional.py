"""The non-functional notice (roadgaze.monitor.behaviours.non_functional): the eyes or the face
hidden while the camera works, told within Euro NCAP's 10 s, again every 10 minutes, shown in
the state while it lasts, cleared when it ends; never for a turn away, a covered lens or a parked
car."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from fakes import BLANK_FRAME, eyes_of, face_sample
from roadgaze.config import Config, MonitorConfig
from roadgaze.monitor import Alert, AlertKind, Monitor
from roadgaze.monitor.behaviours.non_functional import notice_in
from roadgaze.transport import Health, Keys
from roadgaze.types import EyesFeatures, FrameCheck, FrameRecord, PoseSample

FPS = 15.0
CONFIG = MonitorConfig(neutral_yaw_deg=0.0, neutral_pitch_deg=0.0)
GOOD = FrameCheck(120.0, 40.0, 0.0, 3.0)
BLACK = FrameCheck(2.0, 0.5, 0.0, 0.0)

BLACKED = eyes_of(openness=0.31)
"""Marker (this very object): the frame is black (a covered lens), no face."""

Script = Callable[[float], tuple[float, EyesFeatures | None]]
"""Head yaw and the eyes at time t (eyes None: no face)."""


def sample(t_s: float, frame: int, yaw_deg: float, eyes: EyesFeatures | None) -> PoseSample:
    check = BLACK if eyes is BLACKED else GOOD
    eyes = None if eyes is BLACKED else eyes
    return face_sample(t_s, frame, yaw_deg, eyes=eyes, face=eyes is not None, frame_check=check)


def run(
    script: Script, duration_s: float, speed_kmh: float | None = 70.0, fps: float = FPS
) -> tuple[Monitor, list[Alert]]:
    monitor = Monitor(CONFIG)
    alerts: list[Alert] = []
    for frame in range(round(duration_s * fps)):
        t_s = frame / fps
        yaw_deg, eyes = script(t_s)
        alerts.extend(monitor.update(sample(t_s, frame, yaw_deg, eyes), speed_kmh))
    return monitor, alerts


def between(start_s: float, end_s: float, inside: EyesFeatures | None, yaw: float = 0.0) -> Script:
    def script(t_s: float) -> tuple[float, EyesFeatures | None]:
        if start_s <= t_s + 1e-9 < end_s:
            return yaw, inside
        return 0.0, eyes_of()

    return script


def notices(alerts: list[Alert]) -> list[Alert]:
    return [a for a in alerts if a.kind is AlertKind.NON_FUNCTIONAL]


def test_hidden_eyes_facing_the_road_are_told_after_five_seconds_and_cleared_after_two() -> None:
    monitor, alerts = run(between(2.0, 14.0, eyes_of(occluded=True)), 14.0)
    told = notices(alerts)
    assert len(told) == 1 and told[0].t_s == pytest.approx(7.0, abs=1.01 / FPS)
    assert told[0].reason.startswith("eyes hidden facing the road (eyes hidden) 5.0 s")
    assert told[0].rule == "euroncap.non_functional" and "within 10 s" in told[0].source
    assert notice_in(monitor.verdict.outputs).startswith("eyes_hidden: eyes hidden facing")
    # first, within 10 s; degraded and the eyes' temporary failure follow at 10 s, apart
    assert monitor.verdict.active == (
        AlertKind.NON_FUNCTIONAL,
        AlertKind.DEGRADED,
        AlertKind.TEMPORARY_FAILURE,
    )
    monitor, alerts = run(between(2.0, 14.0, eyes_of(occluded=True)), 18.0)
    cleared = [a for a in alerts if AlertKind.NON_FUNCTIONAL in a.clears]
    assert len(cleared) == 1 and cleared[0].t_s == pytest.approx(16.0, abs=1.01 / FPS)
    assert notice_in(monitor.verdict.outputs) == ""
    assert AlertKind.NON_FUNCTIONAL not in monitor.verdict.active


def test_a_hidden_face_is_its_own_notice_beside_the_no_face_failure() -> None:
    _, alerts = run(between(2.0, 20.0, None), 20.0)
    told = notices(alerts)
    assert len(told) == 1 and told[0].t_s == pytest.approx(7.0, abs=1.01 / FPS)
    assert told[0].reason.startswith("face hidden: no face found, not turned away")
    failure = [a for a in alerts if a.kind is AlertKind.TEMPORARY_FAILURE]
    assert len(failure) == 1 and failure[0].t_s > told[0].t_s  # 10 s: the camera's failure


@pytest.mark.parametrize(
    ("script", "speed_kmh", "why"),
    [
        (between(2.0, 14.0, BLACKED), 70.0, "a covered lens is the camera's failure"),
        (between(2.0, 14.0, eyes_of(usable=False), yaw=-60.0), 70.0, "a turn away"),
        (between(2.0, 14.0, eyes_of(occluded=True)), 5.0, "parked"),
        (between(2.0, 6.5, eyes_of(occluded=True)), 70.0, "4.5 s: a hand passing by"),
    ],
)
def test_no_notice(script: Script, speed_kmh: float, why: str) -> None:
    assert notices(run(script, 16.0, speed_kmh)[1]) == [], why


def test_a_lasting_condition_is_told_again_every_ten_minutes_and_shown_throughout() -> None:
    fps = 2.0
    monitor = Monitor(CONFIG)
    told: list[float] = []
    shown = 0
    for frame in range(round(1300 * fps)):
        t_s = frame / fps
        alerts = monitor.update(sample(t_s, frame, 0.0, eyes_of(occluded=True)), 70.0)
        told += [a.t_s for a in alerts if a.kind is AlertKind.NON_FUNCTIONAL]
        shown += bool(notice_in(monitor.verdict.outputs))
    assert told == pytest.approx([5.0, 605.0, 1205.0])
    assert shown == round((1300 - 5.0) * fps)  # every frame from the first notice on


def test_the_state_message_shows_the_notice_in_force() -> None:
    config = Config()
    health = Health(config, Keys.from_config(config.zenoh), None, "camera")
    monitor = Monitor(CONFIG)
    for frame in range(round(8 * FPS)):
        t_s = frame / FPS
        monitor.update(sample(t_s, frame, 0.0, eyes_of(occluded=True)), 70.0)
    record = FrameRecord(sample(8.0, 120, 0.0, eyes_of(occluded=True)), monitor.verdict, ())
    health.on_record(record, BLANK_FRAME)
    state = health.state_message()
    assert state.schema_id == "roadgaze.state/6"
    assert state.monitor.non_functional.startswith("eyes_hidden: eyes hidden facing the road")
    assert any(p.startswith("not functional: eyes_hidden") for p in state.problems)
