"""systemd supervision of the daemon against a fake `$NOTIFY_SOCKET`: READY after the first
frame (or degraded while a missing camera is waited for), WATCHDOG while frames flow and none
when the loop stalls, STOPPING on a stop request and at the end of the source."""

from __future__ import annotations

import itertools
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import roadgaze.capture as capture
import roadgaze.pipeline as pipeline
import roadgaze.service.supervision as supervision
from fakes import FakeCamera, FakeNotifySocket, ListSource, ScriptedDetector
from repo_paths import child_env
from roadgaze.capture import SourceInfo, SourceStatus
from roadgaze.config import Config
from roadgaze.daemon import run_daemon
from roadgaze.service.sdnotify import Notifier
from roadgaze.service.signals import StopFlag
from roadgaze.service.supervision import Supervisor, waiting_for_camera
from zenoh_helpers import LineReader, stop_process, wait_for

WATCHDOG_USEC = 1_000_000
"""WatchdogSec=1s in the tests: pings expected every 0.25 s."""


@pytest.fixture
def notify(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[FakeNotifySocket]:
    fake = FakeNotifySocket(tmp_path, abstract=True)
    monkeypatch.setenv("NOTIFY_SOCKET", fake.address)
    monkeypatch.setenv("WATCHDOG_USEC", str(WATCHDOG_USEC))
    monkeypatch.delenv("WATCHDOG_PID", raising=False)
    try:
        yield fake
    finally:
        fake.close()


class TimedDetector(ScriptedDetector):
    """Straight-ahead faces; notes when the first frame was detected; blocks at call `stall_at`
    until `release` is set."""

    def __init__(self, frames: int, stall_at: int | None = None) -> None:
        super().__init__([0.0] * frames)
        self.first_call_s: float | None = None
        self.stall_at = stall_at
        self.release = threading.Event()

    def detect(self, image: np.ndarray, t_s: float | None = None) -> Any:
        if self.first_call_s is None:
            self.first_call_s = time.monotonic()
        if self.stall_at is not None and len(self.calls) == self.stall_at:
            self.release.wait(30.0)
        return super().detect(image, t_s)


def start_daemon(
    monkeypatch: pytest.MonkeyPatch,
    source: Callable[[Config], capture.FrameSource],
    detector: TimedDetector,
    config: Config | None = None,
) -> tuple[threading.Thread, StopFlag, list[int]]:
    """`run_daemon` on a thread with the fake source and detector; signals left alone."""

    def open_fake(
        spec: str, config: Config | None = None, *, wait_for_camera: bool = False
    ) -> capture.FrameSource:
        assert config is not None and wait_for_camera
        return source(config)

    monkeypatch.setattr(capture, "open_source", open_fake)
    monkeypatch.setattr(pipeline, "create_detector", lambda config: detector)
    config = config or Config.model_validate({"zenoh": {"vehicle_id": "sd"}})
    stop = StopFlag()
    result: list[int] = []
    thread = threading.Thread(
        target=lambda: result.append(run_daemon(config, "/dev/video42", stop, True, False)),
        daemon=True,
    )
    thread.start()
    return thread, stop, result


def gaps_s(times: list[float]) -> list[float]:
    return [later - earlier for earlier, later in itertools.pairwise(times)]


def test_ready_after_the_first_frame_watchdog_while_frames_flow_stopping_at_the_end(
    notify: FakeNotifySocket, monkeypatch: pytest.MonkeyPatch
) -> None:
    detector = TimedDetector(60)
    thread, _, result = start_daemon(monkeypatch, lambda config: ListSource(60), detector)
    thread.join(timeout=60.0)
    assert result == [0]
    assert wait_for(lambda: len(notify.with_key("STOPPING")) == 1, timeout_s=5.0)
    statuses = [fields.get("STATUS", "") for _, fields in notify.messages]
    assert statuses[:2] == ["loading the face landmarker model", "opening /dev/video42"]
    ready = notify.with_key("READY")
    assert len(ready) == 1
    assert ready[0][1]["STATUS"] == "monitoring /dev/video42: first frame processed"
    assert detector.first_call_s is not None and ready[0][0] >= detector.first_call_s
    pings = [t_s for t_s, _ in notify.with_key("WATCHDOG")]
    assert len(pings) >= 5  # 2 s of frames, a ping due every 0.25 s
    assert pings[0] >= ready[0][0]
    assert max(gaps_s(pings)) < WATCHDOG_USEC / 1e6
    assert list(notify.messages[-1][1]) == ["STOPPING", "STATUS"]
    assert notify.messages[-1][1]["STATUS"] == "stopping (end of source) after 60 frames"
    assert len(notify.with_key("STOPPING")) == 1


def test_a_stop_request_sends_stopping_at_once(
    notify: FakeNotifySocket, monkeypatch: pytest.MonkeyPatch
) -> None:
    thread, stop, result = start_daemon(
        monkeypatch, lambda config: ListSource(900), TimedDetector(900)
    )
    try:
        assert wait_for(lambda: len(notify.with_key("READY")) == 1, timeout_s=30.0)
        asked_s = time.monotonic()
        stop.set("SIGTERM")  # what the signal handler does
        assert wait_for(lambda: len(notify.with_key("STOPPING")) == 1, timeout_s=5.0)
    finally:
        stop.set("test end")
        thread.join(timeout=30.0)
    stopping_s, fields = notify.with_key("STOPPING")[0]
    assert stopping_s - asked_s < 1.0
    assert fields["STATUS"].startswith("stopping (SIGTERM) after ")
    assert result == [0]


def test_a_stalled_frame_loop_gets_no_watchdog_ping(
    notify: FakeNotifySocket, monkeypatch: pytest.MonkeyPatch
) -> None:
    detector = TimedDetector(900, stall_at=10)
    thread, stop, _ = start_daemon(monkeypatch, lambda config: ListSource(900), detector)
    try:
        assert wait_for(lambda: len(detector.calls) == 10, timeout_s=30.0)
        stalled_s = time.monotonic()
        time.sleep(2.5 * WATCHDOG_USEC / 1e6)
        pings = [t_s for t_s, _ in notify.with_key("WATCHDOG")]
    finally:
        stop.set("test end")
        detector.release.set()
        thread.join(timeout=30.0)
    assert pings and pings[-1] - stalled_s < 0.1  # none after the stall (systemd would abort)
    assert len(notify.with_key("STOPPING")) == 1


def test_a_camera_missing_at_start_is_ready_degraded_and_fed_while_it_is_waited_for(
    notify: FakeNotifySocket, monkeypatch: pytest.MonkeyPatch
) -> None:
    opens: list[float] = []

    def factory(device: int | str) -> FakeCamera:
        opens.append(time.monotonic())
        if len(opens) <= 12:  # about 2 s without a camera
            return FakeCamera(0, opened=False)
        return FakeCamera(None, period_s=1 / 30)

    config = Config.model_validate(
        {
            "zenoh": {"vehicle_id": "sd"},
            "capture": {"reconnect_initial_s": 0.1, "reconnect_max_s": 0.2},
        }
    )
    detector = TimedDetector(3000)
    thread, stop, result = start_daemon(
        monkeypatch,
        lambda config: capture.CameraSource(
            "/dev/video42", config.capture, capture_factory=factory, wait_for_device=True
        ),
        detector,
        config,
    )
    try:
        assert wait_for(lambda: len(detector.calls) >= 30, timeout_s=30.0)
    finally:
        stop.set("test end")
        thread.join(timeout=30.0)
    assert result == [0]
    ready = notify.with_key("READY")
    assert len(ready) == 1
    assert ready[0][1]["STATUS"].startswith("degraded: camera unavailable: cannot open camera")
    assert detector.first_call_s is not None and ready[0][0] < detector.first_call_s
    waiting_pings = [
        t_s for t_s, _ in notify.with_key("WATCHDOG") if t_s < detector.first_call_s - 0.05
    ]
    assert len(waiting_pings) >= 4  # fed while waiting: systemd does not restart the daemon
    assert max(gaps_s([ready[0][0], *waiting_pings])) < WATCHDOG_USEC / 1e6
    statuses = [fields["STATUS"] for _, fields in notify.with_key("STATUS")]
    assert any(text.startswith("degraded: camera unavailable") for text in statuses)
    assert any(text.startswith("monitoring /dev/video42: ") for text in statuses)


# --- the waiting policy, without a daemon ----------------------------------------------------


@pytest.mark.parametrize(
    ("live", "status", "processed", "waiting"),
    [
        (True, SourceStatus(connected=False, frames_delivered=5), 5, True),
        (True, SourceStatus(connected=False, ever_connected=False), 0, True),
        (True, SourceStatus(connected=False, frames_delivered=5), 4, False),  # stuck on a frame
        (True, SourceStatus(connected=True, frames_delivered=5), 5, False),
        (True, SourceStatus(connected=False, ended=True, frames_delivered=5), 5, False),
        (False, SourceStatus(connected=False), 0, False),
    ],
)
def test_waiting_for_camera(
    live: bool, status: SourceStatus, processed: int, waiting: bool
) -> None:
    assert waiting_for_camera(live, status, processed) is waiting


class LostCamera:
    """A live source whose status the test sets."""

    def __init__(self) -> None:
        self.status = SourceStatus(connected=False, message="camera /dev/video0 lost; reconnecting")

    @property
    def info(self) -> SourceInfo:
        return SourceInfo("camera", True, 30.0, None, 640, 480)


def test_a_camera_wait_whose_attempts_stop_is_no_longer_fed(
    notify: FakeNotifySocket, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(supervision, "WAIT_STALL_MARGIN_S", 0.5)
    source = LostCamera()
    stop = StopFlag()
    with Supervisor(Notifier.from_environment(), stop, reconnect_max_s=0.1) as supervisor:
        supervisor.watch(source, "/dev/video0")  # type: ignore[arg-type]
        for attempt in range(1, 9):  # re-open attempts every 0.1 s: progress
            time.sleep(0.1)
            source.status = SourceStatus(
                connected=False, reopen_attempts=attempt, message=source.status.message
            )
        progressing = len(notify.with_key("WATCHDOG"))
        last_attempt_s = time.monotonic()
        time.sleep(1.5)  # no attempt any more: stalled after 0.6 s
        pings = [t_s for t_s, _ in notify.with_key("WATCHDOG")]
    assert progressing >= 2
    assert pings[-1] - last_attempt_s < 0.6 + 0.3
    stalled = [f["STATUS"] for _, f in notify.with_key("STATUS") if "stalled" in f["STATUS"]]
    assert stalled and stalled[0].startswith("degraded: camera wait stalled")
    assert wait_for(lambda: len(notify.with_key("STOPPING")) == 1, timeout_s=5.0)
    assert notify.with_key("STOPPING")[0][1]["STATUS"].startswith("stopping (stopped)")


def test_without_notify_socket_the_supervisor_does_nothing(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv("NOTIFY_SOCKET", raising=False)
    with Supervisor.from_environment(StopFlag(), reconnect_max_s=10.0) as supervisor:
        assert supervisor._thread is None
    assert supervisor.notifier.sent == 0


# --- the real daemon, real MediaPipe, a real SIGTERM ---------------------------------------


@pytest.mark.slow
def test_roadgaze_run_under_a_notify_socket_ready_watchdog_and_stopping_on_sigterm(
    tmp_path: Path, synthetic_clip: Callable[[str], tuple[Path, Any]]
) -> None:
    clip, _ = synthetic_clip("0:2,30:2,0:2,30:2,0:2,30:2,0:2,30:2,0:2")
    fake = FakeNotifySocket(tmp_path)
    env = child_env(
        NOTIFY_SOCKET=fake.address, WATCHDOG_USEC=str(WATCHDOG_USEC), GLOG_minloglevel="2"
    )
    env.pop("WATCHDOG_PID", None)
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "roadgaze",
            "run",
            "--source",
            str(clip),
            "--vehicle-id",
            "sd",
            "--set",
            "zenoh.delivery_wait_s=0",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        LineReader(process, process.stderr)
        assert wait_for(lambda: len(fake.with_key("READY")) == 1, timeout_s=120.0)
        assert wait_for(lambda: len(fake.with_key("WATCHDOG")) >= 3, timeout_s=30.0)
        process.send_signal(signal.SIGTERM)
        code = process.wait(timeout=30)
        assert wait_for(lambda: len(fake.with_key("STOPPING")) == 1, timeout_s=5.0)
    finally:
        stop_process(process)
        fake.close()
    assert code in (0, 4)  # 4: an alert was raised, and nobody was connected to receive it
    assert fake.with_key("READY")[0][1]["STATUS"] == (f"monitoring {clip}: first frame processed")
    assert fake.with_key("STOPPING")[0][1]["STATUS"].startswith("stopping (SIGTERM) after ")
