"""The `run` service: frames -> yaw samples -> monitor -> Zenoh, until a signal or the end.

`MonitorPublisher` is the sample sink shared by `roadgaze run` and `roadgaze replay --publish`:
it steps the monitor on each sample, publishes the yaw message and every alert, keeps the
counters and answers the state query. `run_daemon` wires it to a frame source, retries a lost
camera with backoff, and on SIGINT/SIGTERM finishes the current frame, publishes a final state,
undeclares everything and returns 0.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import signal
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from types import FrameType
from typing import TYPE_CHECKING, Any, Literal, Protocol

from roadgaze.config import Config
from roadgaze.errors import SourceError
from roadgaze.monitor import Alert, AlertKind, Monitor
from roadgaze.transport import (
    AlertMessage,
    Keys,
    MonitorSnapshot,
    SpeedInput,
    StateMessage,
    TransportStatus,
    YawMessage,
    ZenohLink,
)
from roadgaze.types import YawSample

if TYPE_CHECKING:
    from roadgaze.capture import FrameSource
    from roadgaze.types import LandmarkDetector

log = logging.getLogger("roadgaze.daemon")

Status = Literal["starting", "running", "degraded", "stopping", "stopped"]
LINK_CHECK_PERIOD_S = 1.0


class MessageLink(Protocol):
    """Where messages go: `transport.ZenohLink` in production, a list in tests."""

    speed: SpeedInput | None

    def publish_yaw(self, message: YawMessage) -> None: ...

    def publish_alert(self, message: AlertMessage) -> None: ...

    def status(self) -> TransportStatus: ...


class MonitorPublisher:
    """Sample sink: monitor + publisher + counters; thread-safe `state_json` for the queryable."""

    def __init__(
        self,
        config: Config,
        keys: Keys,
        link: MessageLink | None,
        source_label: str,
        wall_clock: Callable[[], float] = time.time,
    ) -> None:
        self.config = config
        self.keys = keys
        self.link = link
        self.source_label = source_label
        self.monitor = Monitor(config.monitor)
        self._wall_clock = wall_clock
        self._started = time.monotonic()
        self.status: Status = "starting"
        self.source_status = "opening"
        self.source: FrameSource | None = None
        """The open frame source, read for its status (camera lost/reconnected)."""
        self.problems: list[str] = []
        self.frames = 0
        self.faces = 0
        self.camera_reopens = 0
        self._yaw_seq = 0
        self._alert_seq = 0
        self.alerts: list[Alert] = []
        """Every alert raised, in order (bounded by what one run can raise: a few per glance)."""
        self.last_extras: dict[str, Any] = {}
        """The monitor's view of the last sample, for frame records (JSONL extras)."""
        self._link_connected: bool | None = None
        self._link_checked_at = -math.inf

    def _speed(self) -> tuple[float | None, Literal["none", "waiting", "fresh", "stale"]]:
        speed = None if self.link is None else self.link.speed
        if speed is None:
            return None, "none"
        return speed.current()

    def on_sample(self, sample: YawSample) -> None:
        speed_kmh, _ = self._speed()
        alerts = self.monitor.update(sample, speed_kmh)
        state = self.monitor.state
        self.frames += 1
        self.faces += int(sample.face)
        if self.status == "starting":
            self.status = "running"
        on_road = None if state.gaze.value == "unknown" else state.on_road
        window_s = self.config.monitor.vats_window_s
        self.last_extras = {
            "on_road": on_road,
            "gaze": state.gaze.value,
            "neutral_yaw_deg": round(state.neutral_yaw_deg, 3),
            "off_road_s": round(state.off_road_s(), 3),
            "window_off_road_s": round(state.window_off_road_s(window_s), 3),
            "alerts": [f"{a.kind.value}:{a.level.value}" for a in alerts],
        }
        wall_time = self._wall_clock()
        if self.link is not None:
            self.link.publish_yaw(
                YawMessage(
                    vehicle_id=self.keys.vehicle_id,
                    seq=self._yaw_seq,
                    t_s=sample.t_s,
                    wall_time=wall_time,
                    frame=sample.frame,
                    face=sample.face,
                    yaw_deg=sample.yaw_deg,
                    yaw_raw_deg=sample.yaw_raw_deg,
                    yaw_rate_dps=sample.yaw_rate_dps,
                    on_road=on_road,
                    gaze=state.gaze.value,
                    neutral_yaw_deg=state.neutral_yaw_deg,
                    n_faces=sample.n_faces,
                )
            )
        self._yaw_seq += 1
        for alert in alerts:
            self._publish_alert(alert, wall_time)
        self._watch_link()

    def _watch_link(self) -> None:
        """Log when the Zenoh link comes or goes (checked at most once a second)."""
        now = time.monotonic()
        if self.link is None or now - self._link_checked_at < LINK_CHECK_PERIOD_S:
            return
        self._link_checked_at = now
        connected = self.link.status().connected
        if connected != self._link_connected:
            if connected:
                again = " again" if self._link_connected is False else ""
                log.info("zenoh connected: publishing to subscribers%s", again)
            else:
                log.warning("zenoh not connected: monitoring goes on, state is degraded")
            self._link_connected = connected

    def _publish_alert(self, alert: Alert, wall_time: float) -> None:
        self.alerts.append(alert)
        message = alert_message(alert, self.keys.vehicle_id, self._alert_seq, wall_time)
        self._alert_seq += 1
        log.info(
            "alert %s %s at t=%.2fs (off road %.2fs, window %.2fs)",
            alert.kind.value,
            alert.level.value,
            alert.t_s,
            alert.off_road_s,
            alert.window_off_road_s,
            extra={"alert": message.model_dump(by_alias=True)},
        )
        if self.link is not None:
            self.link.publish_alert(message)

    def state_message(self) -> StateMessage:
        """The current state; safe to call from Zenoh's callback thread."""
        state = self.monitor.state  # immutable: one consistent snapshot
        speed_kmh, speed_source = self._speed()
        transport = (
            self.link.status()
            if self.link is not None
            else TransportStatus(mode=self.config.zenoh.mode, session_open=False, connected=False)
        )
        problems = list(self.problems)
        source_status = self.source_status
        if self.source is not None:
            current = self.source.status
            if not current.connected:
                problems.append(current.message or "camera lost; reconnecting")
                source_status = "reconnecting"
        if self.link is not None and not transport.connected:
            problems.append("zenoh not connected")
        status = self.status
        if status in ("starting", "running") and problems:
            status = "degraded"
        monitor = self.config.monitor
        return StateMessage(
            vehicle_id=self.keys.vehicle_id,
            wall_time=self._wall_clock(),
            status=status,
            problems=problems,
            t_s=state.t_s,
            uptime_s=time.monotonic() - self._started,
            source=self.source_label,
            source_status=source_status,
            frames=self.frames,
            faces=self.faces,
            camera_reopens=self.camera_reopens
            + (self.source.status.reconnects if self.source is not None else 0),
            transport=transport,
            monitor=MonitorSnapshot(
                gaze=state.gaze.value,
                on_road=state.on_road,
                neutral_yaw_deg=state.neutral_yaw_deg,
                yaw_deg=state.yaw_deg,
                off_road_s=state.off_road_s(),
                window_off_road_s=state.window_off_road_s(monitor.vats_window_s),
                unavailable_s=state.unavailable_s(),
                vats_armed=state.vats_armed,
                active_alerts=[kind.value for kind in state.active],
                moving=state.moving,
                speed_kmh=speed_kmh,
                speed_source=speed_source,
                alert_counts=dict(state.alert_counts),
            ),
            config={
                "monitor": monitor.model_dump(mode="json"),
                "keys": {
                    "yaw": self.keys.yaw,
                    "alert": self.keys.alert,
                    "alive": self.keys.alive,
                    "state": self.keys.state,
                    "speed": self.keys.speed,
                },
                "zenoh_mode": self.config.zenoh.mode,
            },
        )

    def state_json(self) -> bytes:
        return self.state_message().to_json_bytes()

    def extras(self, sample: YawSample) -> dict[str, Any]:
        """The monitor's fields for the frame record of `sample` (this sink must run first)."""
        return self.last_extras

    def state_text(self, sample: YawSample) -> str:
        """One line for an annotated video: the gaze, off-road time and this frame's alerts."""
        extras = self.last_extras
        text = f"gaze {extras.get('gaze', '?')}"
        if extras.get("off_road_s"):
            text += f"  off road {extras['off_road_s']:.1f} s"
        text += f"  in window {extras.get('window_off_road_s', 0.0):.1f} s"
        if extras.get("alerts"):
            text += "  ALERT " + " ".join(extras["alerts"])
        return text

    def close(self) -> None:
        """Nothing to release: the link is owned by whoever opened it."""


def alert_message(alert: Alert, vehicle_id: str, seq: int, wall_time: float) -> AlertMessage:
    """The wire form of one monitor alert."""
    return AlertMessage(
        vehicle_id=vehicle_id,
        seq=seq,
        kind=alert.kind.value,
        level=alert.level.value,
        t_s=alert.t_s,
        wall_time=wall_time,
        yaw_deg=alert.yaw_deg,
        off_road_s=max(0.0, alert.off_road_s),
        window_off_road_s=max(0.0, alert.window_off_road_s),
        unavailable_s=max(0.0, alert.unavailable_s),
        speed_kmh=alert.speed_kmh,
        clears=[kind.value for kind in alert.clears if kind is not AlertKind.CLEARED],
    )


class StopFlag:
    """Set by SIGINT/SIGTERM; the loop checks it between frames."""

    def __init__(self) -> None:
        self._event = threading.Event()
        self.signal_name: str | None = None

    def set(self, name: str = "request") -> None:
        self.signal_name = name
        self._event.set()

    def is_set(self) -> bool:
        return self._event.is_set()

    def wait(self, timeout_s: float) -> bool:
        return self._event.wait(timeout_s)


@contextmanager
def signal_handlers(stop: StopFlag) -> Iterator[None]:
    """SIGINT/SIGTERM set `stop` (the current frame is finished); a second one exits at once."""

    def on_signal(number: int, frame: FrameType | None) -> None:
        name = signal.Signals(number).name
        if stop.is_set():
            log.warning("second %s: exiting without waiting", name)
            raise SystemExit(1)
        log.info("%s received: finishing the current frame", name)
        stop.set(name)

    previous = {
        number: signal.signal(number, on_signal) for number in (signal.SIGINT, signal.SIGTERM)
    }
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


@contextmanager
def publishing_sink(config: Config, source_label: str, publish: bool) -> Iterator[MonitorPublisher]:
    """A `MonitorPublisher`, with a Zenoh link when `publish`; on exit the final state is
    published and everything undeclared."""
    keys = Keys.from_config(config.zenoh)
    if not publish:
        yield MonitorPublisher(config, keys, None, source_label)
        return
    speed = SpeedInput(config.zenoh.speed_stale_s) if keys.speed is not None else None
    holder: list[MonitorPublisher] = []
    link = ZenohLink(config.zenoh, keys, state_reply=lambda: holder[0].state_json(), speed=speed)
    sink = MonitorPublisher(config, keys, link, source_label)
    holder.append(sink)
    with link:
        try:
            yield sink
        finally:
            sink.status = "stopped"
            link.publish_final_state()


def _close_when_stopped(stop: StopFlag, source: FrameSource, done: threading.Event) -> None:
    """Unblock a source that waits for a lost camera once a stop is asked for."""
    while not done.wait(0.1):
        if stop.is_set():
            if not done.wait(1.0):  # the current frame had a second to finish
                source.close()
            return


def run_daemon(
    config: Config,
    source_spec: str,
    stop: StopFlag | None = None,
    realtime: bool = True,
    handle_signals: bool = True,
) -> int:
    """Monitor `source_spec` and publish until the source ends or a stop; returns 0.

    A camera that cannot be opened is retried with backoff (capture.reconnect_*), reported in
    the state as degraded; a missing file is a `SourceError`. An unreachable Zenoh peer never
    stops monitoring (see `ZenohLink`).
    """
    from roadgaze.capture import camera_device, open_source
    from roadgaze.pipeline import Pipeline, create_detector

    stop = stop if stop is not None else StopFlag()
    is_camera = camera_device(source_spec) is not None
    with ExitStack() as stack:
        if handle_signals:
            stack.enter_context(signal_handlers(stop))
        sink = stack.enter_context(publishing_sink(config, source_spec, publish=True))
        log.info(
            "roadgaze run: source %s, vehicle %s, prefix %s",
            source_spec,
            sink.keys.vehicle_id,
            sink.keys.prefix,
        )
        delay_s = config.capture.reconnect_initial_s
        offset_s = 0.0
        detector: LandmarkDetector | None = None
        stack.callback(lambda: detector.close() if detector is not None else None)
        while not stop.is_set():
            if detector is None:
                # Ready before the camera opens, so no frame waits for MediaPipe to load; VIDEO
                # mode needs one detector per source timeline.
                detector = create_detector(config)
            try:
                source = open_source(source_spec, config)
            except SourceError as exc:
                if not is_camera:
                    raise
                sink.problems = [f"camera unavailable: {exc}"]
                sink.source_status = "unavailable"
                sink.camera_reopens += 1
                log.warning("%s; next try in %.1f s", exc, delay_s)
                stop.wait(delay_s)
                delay_s = min(delay_s * 2.0, config.capture.reconnect_max_s)
                continue
            delay_s = config.capture.reconnect_initial_s
            sink.problems = []
            sink.source_status = "open"
            done = threading.Event()
            watcher = threading.Thread(
                target=_close_when_stopped, args=(stop, source, done), daemon=True
            )
            with source:
                try:
                    sink.source = source
                    watcher.start()
                    pipeline = Pipeline.from_config(config, detector)
                    live = source.info.live
                    for processed in pipeline.frames(source, realtime=realtime and not live):
                        sample = processed.sample
                        if offset_s:
                            sample = dataclasses.replace(sample, t_s=sample.t_s + offset_s)
                        sink.on_sample(sample)
                        if stop.is_set():
                            break
                finally:
                    done.set()
                    sink.source = None
                    detector.close()
                    detector = None
            if sink.monitor.state.t_s is not None:
                offset_s = sink.monitor.state.t_s + 1.0 / (config.capture.fps or 30.0)
            if not is_camera:
                sink.source_status = "ended"
                break
            if not stop.is_set():
                sink.problems = ["camera stream ended; reopening"]
        sink.status = "stopping"
        log.info(
            "roadgaze run: stopping (%s) after %d frames, %d alerts",
            stop.signal_name or "end of source",
            sink.frames,
            len(sink.alerts),
        )
    return 0
