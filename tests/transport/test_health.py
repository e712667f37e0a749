"""The health and publisher sinks with a fake link: sequence numbers, alerts, degraded states."""

from __future__ import annotations

import json
import logging
from collections.abc import Iterator
from dataclasses import replace

import jsonschema
import pytest

from fakes import BLANK_FRAME, FakeLink, ListSource, ScriptedDetector, eyes_of
from roadgaze.capture import SourceStatus
from roadgaze.config import Config
from roadgaze.monitor import Monitor
from roadgaze.outputs import verdict_text
from roadgaze.pipeline import Pipeline
from roadgaze.transport import (
    BusPublisher,
    Health,
    Keys,
    SpeedInput,
    YawMessage,
    json_schemas,
)
from roadgaze.types import FrameRecord, PoseSample

SCHEMAS = json_schemas()
FIXED = Config.model_validate({"monitor": {"neutral_yaw_deg": 0.0}})


def sample(t_s: float, yaw_deg: float | None) -> PoseSample:
    face = yaw_deg is not None
    return PoseSample(t_s, round(t_s * 30), face, yaw_deg, yaw_deg, 0.0, 1.0, n_faces=int(face))


def records(
    config: Config, yaws: list[tuple[float, float | None]], speed_kmh: float | None = None
) -> Iterator[FrameRecord]:
    """The frame records the monitor stage makes of (t_s, yaw) samples."""
    monitor = Monitor(config.monitor)
    for t_s, yaw_deg in yaws:
        alerts = monitor.update(sample(t_s, yaw_deg), speed_kmh)
        yield FrameRecord(sample(t_s, yaw_deg), monitor.verdict, alerts)


AWAY_YAW_DEG = -27.0
"""Right of the road, short of the right mirror: zone `away` (+45 deg is the left mirror, which
raises no long_distraction; -30 was away before ADDW's mirror bounds made it the right mirror's
edge)."""


def glance(frames: int) -> list[tuple[float, float | None]]:
    """1 s ahead, 4 s at -27 deg (zone away), then ahead, at 30 fps."""
    return [(f / 30, AWAY_YAW_DEG if 1.0 <= f / 30 < 5.0 else 0.0) for f in range(frames)]


def test_publisher_sends_every_record_and_each_alert_in_order() -> None:
    link = FakeLink()
    publisher = BusPublisher("car-0", link, wall_clock=lambda: 1e9)
    for record in records(FIXED, glance(300)):
        publisher.on_record(record, BLANK_FRAME)
    assert [m.seq for m in link.yaw] == list(range(300))
    assert [(m.seq, m.kind, m.level) for m in link.alerts] == [
        (0, "long_distraction", "warning"),
        (1, "cleared", "info"),
    ]
    assert link.alerts[0].t_s == pytest.approx(4.0, abs=1 / 30)
    assert link.alerts[1].clears == ["long_distraction"]
    assert link.yaw[40].on_road is False and link.yaw[40].gaze == "off_road"
    assert link.yaw[-1].on_road is True
    jsonschema.validate(json.loads(link.yaw[0].to_json_bytes()), SCHEMAS["yaw"])
    jsonschema.validate(json.loads(link.alerts[0].to_json_bytes()), SCHEMAS["alert"])


def test_yaw_message_from_a_record_keeps_every_value() -> None:
    record = list(records(FIXED, glance(40)))[-1]
    message = YawMessage.from_record(record, "car-9", 7, 123.0)
    assert (message.vehicle_id, message.seq, message.wall_time) == ("car-9", 7, 123.0)
    assert (message.t_s, message.frame, message.face) == (39 / 30, 39, True)
    assert (message.yaw_deg, message.gaze, message.on_road) == (AWAY_YAW_DEG, "off_road", False)
    assert (message.zone, message.eyes_on_road) == ("away", False)
    assert message.schema_id == "roadgaze.yaw/3"
    assert json.loads(message.to_json_bytes())["gaze"] == "off_road"


def test_verdict_text_for_the_annotated_video_names_gaze_time_and_alerts() -> None:
    lines = [
        verdict_text(record)
        for record in records(FIXED, [(f / 30, AWAY_YAW_DEG) for f in range(121)])
    ]
    assert lines[30] == "zone away  off road 1.0 s  in window 1.0 s"
    assert lines[90] == (
        "zone away  off road 3.0 s  in window 3.0 s  ALERT long_distraction:warning"
    )


def test_state_is_degraded_when_the_camera_or_zenoh_is_lost() -> None:
    config = Config()
    link = FakeLink()
    health = Health(config, Keys.from_config(config.zenoh), link, "/dev/video0")
    assert health.state_message().status == "starting"
    health.on_record(next(records(config, [(0.0, 0.0)])), BLANK_FRAME)
    assert (health.state_message().status, health.state_message().problems) == ("running", [])

    class LostCamera:
        status = SourceStatus(
            connected=False, reopen_attempts=2, message="camera 0 lost; reconnecting"
        )

    health.source = LostCamera()  # type: ignore[assignment]
    state = health.state_message()
    assert state.status == "degraded"
    assert state.problems == ["camera 0 lost; reconnecting"]
    assert (state.source_status, state.camera_reopens) == ("reconnecting", 2)
    health.source = None
    link.connected = False
    assert health.state_message().problems == ["zenoh not connected"]


def test_state_says_when_the_driver_cannot_be_told_from_another_face() -> None:
    config = Config()
    health = Health(config, Keys.from_config(config.zenoh), FakeLink(), "drive.mp4")
    reason = "another face of similar size sits at the driver's place in the image"
    first, second = records(config, [(0.0, 0.0), (0.1, 0.0)])
    health.on_record(
        replace(first, sample=replace(first.sample, driver_ambiguous=reason)), BLANK_FRAME
    )
    state = health.state_message()
    assert (state.status, state.driver_ambiguous) == ("degraded", reason)
    assert state.problems == [f"driver ambiguous: {reason}"]
    jsonschema.validate(json.loads(state.to_json_bytes()), SCHEMAS["state"])
    health.on_record(second, BLANK_FRAME)
    state = health.state_message()
    assert (state.status, state.driver_ambiguous, state.problems) == ("running", "", [])


def test_state_is_degraded_while_the_eyes_have_been_unavailable_ten_seconds() -> None:
    config = Config()
    health = Health(config, Keys.from_config(config.zenoh), FakeLink(), "drive.mp4")
    monitor = Monitor(config.monitor)
    for frame in range(16 * 30):
        t_s = frame / 30
        eyes = eyes_of(usable=t_s >= 12.0)  # a turned head or sunglasses for 12 s, then back
        sample_ = PoseSample(t_s, frame, True, 0.0, 0.0, 0.0, 1.0, n_faces=1, eyes=eyes)
        alerts = monitor.update(sample_, None)
        health.on_record(FrameRecord(sample_, monitor.verdict, alerts), BLANK_FRAME)
        if frame == 11 * 30:
            state = health.state_message()
            assert state.status == "degraded" and state.monitor.degraded
            assert state.problems == [
                "eyes unavailable for 11 s (head turned): monitoring on head pose only",
                "not functional: eyes_hidden: eyes hidden facing the road (head turned) 5.0 s",
            ]
            assert state.monitor.non_functional.startswith("eyes_hidden: eyes hidden facing")
            assert (state.monitor.eyes, state.monitor.gaze_source) == ("unavailable", "head")
            assert state.monitor.eye_calibration == "none"  # nothing to learn from yet
            jsonschema.validate(json.loads(state.to_json_bytes()), SCHEMAS["state"])
    state = health.state_message()
    assert (state.status, state.problems, state.monitor.eyes) == ("running", [], "open")
    assert state.monitor.eye_calibration == "calibrated"  # 4 s of open eyes on the road
    # Euro NCAP needs the eyes: unjudgeable eyes are also a temporary failure (alert/3), and
    # facing the road, a non-functional notice (alert/4), cleared 2 s after the eyes are back
    kinds = [a.kind for a in health.recent_alerts]
    assert kinds == ["non_functional", "degraded", "temporary_failure", "cleared", "cleared"]
    assert state.monitor.non_functional == ""


@pytest.mark.parametrize(
    ("speed_payload", "expected", "source"),
    [
        (b'{"kmh": 10}', 0, "fresh"),
        (b"50", 2, "fresh"),
        (None, 2, "waiting"),
        (b'{"kmh": 1e308}', 2, "invalid"),  # a spoofed absurd speed: unknown, i.e. moving
        (b'{"kmh": -1}', 2, "invalid"),
        (b"[" * 100_000, 2, "invalid"),
    ],
)
def test_alerts_are_gated_on_the_speed_received(
    speed_payload: bytes | None, expected: int, source: str
) -> None:
    # A frozen clock: the speed received stays as fresh as it came however slowly the machine
    # runs the 180 frames (a wall clock made it stale on a loaded machine).
    speed = SpeedInput(timeout_s=5.0, clock=lambda: 0.0)
    if speed_payload is not None:
        speed.on_payload(speed_payload)
    link = FakeLink(speed=speed)
    keys = Keys.from_config(FIXED.zenoh)
    health = Health(FIXED, keys, link, "test")
    # A scripted face at -30 reads -26.6 through the yaw model: zone away.
    yaws: list[float | None] = [-30.0 if 1.0 <= f / 30 < 5.0 else 0.0 for f in range(180)]
    pipeline = Pipeline.from_config(FIXED, ScriptedDetector(yaws), speed=speed.kmh)
    pipeline.run(ListSource(len(yaws)), [health, BusPublisher(keys.vehicle_id, link)])
    assert len(link.alerts) == expected
    assert health.alerts_raised == expected
    state = health.state_message()
    assert state.monitor.speed_source == source
    assert state.monitor.moving is (expected > 0)


class Collected(logging.Handler):
    """Every record that reaches roadgaze's top logger (whatever its handlers and level were)."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)


@pytest.mark.parametrize("log_name", [None, "roadgaze.replay"])
def test_each_alert_is_logged_once_under_the_logger_its_caller_names(log_name: str | None) -> None:
    keys = Keys.from_config(FIXED.zenoh)
    if log_name is None:
        health = Health(FIXED, keys, None, "test")
    else:
        health = Health(FIXED, keys, None, "test", log_name=log_name)
    top = logging.getLogger("roadgaze")
    collected, level = Collected(), top.level
    top.addHandler(collected)
    top.setLevel(logging.INFO)
    try:
        for record in records(FIXED, glance(180)):
            health.on_record(record, BLANK_FRAME)
    finally:
        top.removeHandler(collected)
        top.setLevel(level)
    logged = [(r.name, r.getMessage().split()[1]) for r in collected.records if hasattr(r, "alert")]
    expected = log_name or "roadgaze.daemon"
    assert logged == [(expected, "long_distraction"), (expected, "cleared")]
