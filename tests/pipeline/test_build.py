"""The one builder: every sink gets the alerts raised outside the frame loop (a camera gone for
good, a model that cannot be loaded) through `Sink.on_alert`, the writers, the recorder and the
bus each in their own way; the loop and those alerts never call a sink at once."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from fakes import FakeLink, ListSource, ScriptedDetector
from roadgaze.capture import SourceInfo, SourceStatus
from roadgaze.config import Config, MonitorConfig
from roadgaze.errors import ModelError
from roadgaze.pipeline import RunOptions, build_run
from roadgaze.transport import BusPublisher
from roadgaze.transport.failure_watch import failure_alert
from roadgaze.transport.vss import VssPublisher
from roadgaze.types import Alert, AlertKind, ClosesOnExit, Frame, FrameRecord, Sink


class Taken(Sink):
    """A sink of a kind the service does not know (a CAN frame, a ROS 2 topic): it takes
    whatever comes, the alerts raised outside the loop included."""

    def __init__(self) -> None:
        self.records = 0
        self.alerts: list[Alert] = []
        self.busy = threading.Lock()
        self.overlaps = 0

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        with self._alone():
            self.records += 1
            time.sleep(0.002)

    def on_alert(self, alert: Alert) -> None:
        with self._alone():
            self.alerts.append(alert)

    def _alone(self) -> threading.Lock:
        if self.busy.locked():
            self.overlaps += 1
        return self.busy

    def close(self) -> None:
        return None


class LostCamera(ClosesOnExit):
    """A live source whose camera is gone: no frame comes until it is closed."""

    def __init__(self) -> None:
        self._closed = threading.Event()

    @property
    def info(self) -> SourceInfo:
        return SourceInfo("/dev/video97", True, 30.0, None, 64, 48)

    @property
    def status(self) -> SourceStatus:
        return SourceStatus(connected=False, message="camera lost; reconnecting")

    def __iter__(self) -> Iterator[Frame]:
        self._closed.wait()
        return iter(())

    def close(self) -> None:
        self._closed.set()


def wait_until(predicate: object, timeout_s: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():  # type: ignore[operator]
            return True
        time.sleep(0.02)
    return False


def test_a_permanent_failure_raised_outside_the_loop_reaches_every_sink(tmp_path: Path) -> None:
    config = Config(monitor=MonitorConfig(permanent_failure_s=0.2))
    options = RunOptions(
        "/dev/video97",
        command="run",
        watch_failures=True,
        records=tmp_path / "frames.jsonl",
        csv=tmp_path / "frames.csv",
    )
    taken = Taken()
    with build_run(
        config, options, source=LostCamera(), detector=ScriptedDetector([]), sinks=(taken,)
    ) as run:
        assert wait_until(lambda: taken.alerts)
        assert run.health.alerts_raised == 1 and run.health.permanent_failure
    (alert,) = taken.alerts
    assert alert.kind is AlertKind.PERMANENT_FAILURE and alert.reason.startswith("camera lost")
    row = json.loads((tmp_path / "frames.jsonl").read_text(encoding="utf-8"))
    assert row["alerts"] == ["permanent_failure:critical"] and row["frame"] is None
    assert "permanent_failure:critical" in (tmp_path / "frames.csv").read_text(encoding="utf-8")


def test_a_model_that_cannot_be_loaded_is_raised_to_the_sinks_before_the_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import roadgaze.pipeline

    def unusable(config: Config) -> None:
        raise ModelError("face_landmarker.task: not a model file")

    monkeypatch.setattr(roadgaze.pipeline, "create_detector", unusable)
    taken = Taken()
    with (
        pytest.raises(ModelError),
        build_run(Config(), RunOptions("drive.mp4"), source=ListSource(3), sinks=(taken,)),
    ):
        pass
    assert [(a.kind, a.reason) for a in taken.alerts] == [
        (AlertKind.PERMANENT_FAILURE, "model unusable: face_landmarker.task: not a model file")
    ]


def test_the_loop_and_an_alert_from_another_thread_never_call_a_sink_at_once() -> None:
    taken = Taken()
    options = RunOptions("drive.mp4")
    with build_run(
        Config(), options, source=ListSource(200), detector=ScriptedDetector([0.0] * 200),
        sinks=(taken,),
    ) as run:  # fmt: skip
        sender = threading.Thread(
            target=lambda: [run.alert(failure_alert(0.1 * i, "test")) for i in range(50)]
        )
        sender.start()
        run.run()
        sender.join()
    assert taken.records == 200 and len(taken.alerts) == 50 and taken.overlaps == 0


def test_the_bus_and_vss_publishers_send_an_alert_raised_outside_the_loop() -> None:
    link = FakeLink()
    publisher = BusPublisher("car-1", link)
    failed, back = failure_alert(3.0, "camera lost 30 s"), failure_alert(9.0, "frames again", True)
    publisher.on_alert(failed)
    publisher.on_alert(back)
    assert [(m.kind, m.seq) for m in link.alerts] == [("permanent_failure", 0), ("cleared", 1)]

    class VssLink:
        def __init__(self) -> None:
            self.sent: list[tuple[str, bytes]] = []

        def publish_vss(self, key: str, payload: bytes) -> None:
            self.sent.append((key, payload))

    vss_link = VssLink()
    vss = VssPublisher(vss_link, MonitorConfig())
    vss.on_alert(failed)
    vss.on_alert(back)
    assert vss_link.sent == [
        ("Vehicle/ADAS/DMS/IsError", b"true"),
        ("Vehicle/ADAS/DMS/IsWarning", b"true"),
        ("Vehicle/ADAS/DMS/IsError", b"false"),
        ("Vehicle/ADAS/DMS/IsWarning", b"false"),
    ]


def test_the_recording_keeps_an_alert_raised_outside_the_loop(tmp_path: Path) -> None:
    pytest.importorskip("foxglove")
    from foxglove_helpers import read_mcap

    path = tmp_path / "drive.mcap"
    options = RunOptions("drive.mp4", command="replay", mcap=path)
    with build_run(
        Config(), options, source=ListSource(5), detector=ScriptedDetector([0.0] * 5)
    ) as run:
        run.run()
        run.alert(failure_alert(0.4, "camera lost 30 s"))
    alerts = read_mcap(path).json("/roadgaze/alerts")
    assert [(a["kind"], a["reason"]) for a in alerts] == [("permanent_failure", "camera lost 30 s")]


def test_a_sink_without_on_alert_is_refused_at_build_time() -> None:
    class OldSink:
        def on_record(self, record: FrameRecord, frame: Frame) -> None:
            return None

        def close(self) -> None:
            return None

    with (
        pytest.raises(TypeError, match="OldSink has no on_alert"),
        build_run(Config(), RunOptions("x"), source=ListSource(1), sinks=(OldSink(),)),  # type: ignore[arg-type]
    ):
        pass


def test_frames_feed_every_sink_before_yielding() -> None:
    taken = Taken()
    with build_run(
        Config(), RunOptions("x"), source=ListSource(4), detector=ScriptedDetector([0.0] * 4),
        sinks=(taken,),
    ) as run:  # fmt: skip
        seen = [(p.frame.index, taken.records) for p in run.frames()]
    assert seen == [(0, 1), (1, 2), (2, 3), (3, 4)]
    assert np.isfinite([run.pipeline.frame_received_s]).all()
