"""Failure warnings: the frame checks' closed forms, the temporary failure's timers, recovery,
and the permanent failure watch."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from fakes import drive_monitor
from roadgaze.config import Config, MonitorConfig
from roadgaze.monitor import Monitor
from roadgaze.monitor.failures import FRAME_STRIDE, check_frame, frame_issue
from roadgaze.transport import Health, Keys
from roadgaze.transport.failure_watch import PermanentFailureWatch
from roadgaze.transport.vss import VssPublisher
from roadgaze.types import Alert, AlertKind, FrameCheck

FPS = 15.0
CONFIG = MonitorConfig()


def test_check_frame_closed_forms() -> None:
    image = np.zeros((480, 640, 3), np.uint8)
    image[:, :, 1] = 100
    image[::FRAME_STRIDE, ::FRAME_STRIDE][:30, :, 1] = 255  # top half of the samples saturated
    check, grey = check_frame(image, None)
    assert grey.shape == (60, 80) and check.diff_grey is None
    assert check.mean_grey == pytest.approx((100 + 255) / 2)
    assert check.std_grey == pytest.approx((255 - 100) / 2)
    assert check.saturated_fraction == pytest.approx(0.5)
    shifted = image.copy()
    shifted[:, :, 1] += 0  # the same frame again: frozen
    again, _ = check_frame(shifted, grey)
    assert again.diff_grey == 0.0
    brighter = image.copy()
    brighter[::FRAME_STRIDE, ::FRAME_STRIDE][30:, :, 1] = 110
    moved, _ = check_frame(brighter, grey)
    assert moved.diff_grey == pytest.approx(10.0)  # half the samples 10 grey levels brighter


@pytest.mark.parametrize(
    ("mean", "std", "saturated", "issue"),
    [
        (5.0, 2.0, 0.0, "black"),
        (120.0, 1.0, 0.0, "blocked"),
        (240.0, 20.0, 0.9, "saturated"),
        (120.0, 40.0, 0.1, ""),
    ],
)
def test_frame_issues(mean: float, std: float, saturated: float, issue: str) -> None:
    assert frame_issue(CONFIG, FrameCheck(mean, std, saturated, None)) == issue


def run(
    check_at: Callable[[float], FrameCheck],
    face_at: Callable[[float], bool],
    duration_s: float,
    speed_kmh: float | None = 70.0,
) -> tuple[Monitor, list[Alert]]:
    monitor = Monitor(CONFIG)
    alerts = drive_monitor(
        monitor, lambda t: (0.0, 0.0) if face_at(t) else (None, 0.0), speed_kmh, duration_s,
        FPS, check_at,
    )  # fmt: skip
    return monitor, alerts


GOOD = FrameCheck(120.0, 40.0, 0.0, 3.0)
BLACK = FrameCheck(2.0, 0.5, 0.0, 0.0)
FROZEN = FrameCheck(120.0, 40.0, 0.0, 0.0)


def test_a_covered_camera_is_a_temporary_failure_not_only_driver_unavailable() -> None:
    monitor, alerts = run(
        lambda t: BLACK if 2.0 <= t < 8.0 else GOOD, lambda t: not 2.0 <= t < 8.0, 10.0
    )
    failure = [a for a in alerts if a.kind is AlertKind.TEMPORARY_FAILURE]
    assert len(failure) == 1 and failure[0].t_s == pytest.approx(4.0, abs=1 / FPS)
    assert (
        failure[0].reason.startswith("frames black") and failure[0].rule == "addw.failure.temporary"
    )
    assert any(a.kind is AlertKind.DRIVER_UNAVAILABLE for a in alerts)
    cleared = [a for a in alerts if a.kind is AlertKind.CLEARED]
    assert any(AlertKind.TEMPORARY_FAILURE in a.clears for a in cleared)
    assert (
        monitor.verdict.failure == "" and AlertKind.TEMPORARY_FAILURE not in monitor.verdict.active
    )


def test_a_frozen_frontal_frame_is_a_temporary_failure_after_ten_seconds() -> None:
    monitor, alerts = run(lambda t: FROZEN if t >= 1.0 else GOOD, lambda t: True, 21.0)
    assert [a.kind for a in alerts] == [AlertKind.TEMPORARY_FAILURE]
    assert alerts[0].t_s == pytest.approx(11.0, abs=1 / FPS)
    assert alerts[0].rule == "roadgaze.failure.frozen"
    assert monitor.verdict.failure == "frames frozen 19.9 s"  # the reason keeps counting


def test_no_face_for_ten_seconds_and_a_parked_car() -> None:
    _, alerts = run(lambda t: GOOD, lambda t: t < 1.0, 12.0)
    failure = [a for a in alerts if a.kind is AlertKind.TEMPORARY_FAILURE]
    assert len(failure) == 1 and failure[0].reason.startswith("no face 10.0")
    assert run(lambda t: BLACK, lambda t: False, 20.0, speed_kmh=5.0)[1] == []


def test_a_dark_frame_with_a_face_is_working() -> None:
    assert run(lambda t: FrameCheck(8.0, 3.0, 0.0, 2.0), lambda t: True, 6.0)[1] == []


class _Status:
    def __init__(self) -> None:
        self.connected = True
        self.message: str | None = None
        self.reopen_attempts = 0

    @property
    def state(self) -> str:
        return "open" if self.connected else "reconnecting"


class _Source:
    def __init__(self) -> None:
        self.status = _Status()


def test_a_camera_lost_past_the_limit_is_a_permanent_failure_cleared_by_frames() -> None:
    config = Config()
    health = Health(config, Keys.from_config(config.zenoh), None, "camera")
    source = _Source()
    health.source = source  # type: ignore[assignment]
    now = [0.0]
    watch = PermanentFailureWatch(health, lambda alert: None, 30.0, clock=lambda: now[0])
    assert watch.check() is None
    source.status.connected, source.status.message = False, "camera 0 lost; reconnecting"
    for now[0] in (1.0, 20.0, 30.5):
        assert watch.check() is None
    now[0] = 31.5
    alert = watch.check()
    assert alert is not None and alert.kind is AlertKind.PERMANENT_FAILURE
    assert alert.reason == "camera lost 30 s (camera 0 lost; reconnecting)"
    assert alert.rule == "addw.failure.permanent"
    state = health.state_message()
    assert state.permanent_failure == alert.reason and state.status == "degraded"
    assert watch.check() is None  # once
    source.status.connected = True
    health.frames += 1
    cleared = watch.check()
    assert cleared is not None and cleared.clears == (AlertKind.PERMANENT_FAILURE,)
    assert health.state_message().permanent_failure == ""


def test_a_permanent_failure_sets_the_vss_error_signal() -> None:
    sent: list[tuple[str, bytes]] = []

    class Link:
        def publish_vss(self, key: str, payload: bytes) -> None:
            sent.append((key, payload))

    publisher = VssPublisher(Link(), CONFIG)
    publisher.publish_failure(True)
    publisher.publish_failure(False)
    assert sent == [
        ("Vehicle/ADAS/DMS/IsError", b"true"),
        ("Vehicle/ADAS/DMS/IsWarning", b"true"),
        ("Vehicle/ADAS/DMS/IsError", b"false"),
        ("Vehicle/ADAS/DMS/IsWarning", b"false"),
    ]


def test_the_pipeline_checks_every_frame_a_repeated_frame_is_frozen() -> None:
    """Through the loop: 11 s of one blank frame with a face read as road (at 30 fps)."""
    from fakes import ListSource, ScriptedDetector
    from roadgaze.pipeline import Pipeline
    from test_pipeline_synthetic import Collect

    collect = Collect()
    Pipeline.from_config(Config(), ScriptedDetector([0.0] * 330)).run(ListSource(330), [collect])
    failures = [
        a for r in collect.records for a in r.alerts if a.kind is AlertKind.TEMPORARY_FAILURE
    ]
    assert len(failures) == 1  # the scripted face has no eyes either: that one came first
    assert [r.sample.frame_check is not None for r in collect.records] == [True] * 330
    assert collect.records[-1].verdict.failure == "frames frozen 10.9 s"
