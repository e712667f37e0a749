"""The service's health: counters, status and problems, answered on the `state` key.

`Health` is a pipeline sink. It counts frames, faces and alerts, logs each alert once (under
`roadgaze.daemon`, or the logger its caller names: `replay` logs them as its own) and builds
the `StateMessage` the state queryable answers (thread-safe: it reads only immutable records and
plain counters). The link logs its own changes (`LinkState`, from Zenoh's transport events).
"""

from __future__ import annotations

import logging
import time
from collections import deque
from collections.abc import Callable
from typing import Literal

from roadgaze.capture import FrameSource
from roadgaze.config import Config
from roadgaze.monitor import initial_state, verdict_of
from roadgaze.monitor.behaviours.non_functional import notice_in
from roadgaze.monitor.protocols.support import FORWARD, LANE
from roadgaze.mounting import CameraMounting
from roadgaze.transport.keys import Keys
from roadgaze.transport.messages import (
    AlertMessage,
    EyeFields,
    MonitorSnapshot,
    StateMessage,
    TransportStatus,
)
from roadgaze.transport.publisher import MessageLink
from roadgaze.transport.support_message import SupportLevel
from roadgaze.types import Alert, Frame, FrameRecord

ALERT_LOG = "roadgaze.daemon"
"""The logger of the alert lines unless the caller names another."""

Status = Literal["starting", "running", "degraded", "stopping", "stopped"]
RECENT_ALERTS = 100
"""Alerts kept for inspection; older ones are only counted (memory stays flat)."""


class Health:
    """Sink keeping what the state query answers; `state_message()` may be called any time."""

    def __init__(
        self,
        config: Config,
        keys: Keys,
        link: MessageLink | None,
        source_label: str,
        wall_clock: Callable[[], float] = time.time,
        log_name: str = ALERT_LOG,
    ) -> None:
        self.config = config
        self.keys = keys
        self.link = link
        self.source_label = source_label
        self._wall_clock = wall_clock
        self._log = logging.getLogger(log_name)
        self._started = time.monotonic()
        self.status: Status = "starting"
        self.source: FrameSource | None = None
        """The open frame source, read for its status (camera unavailable, lost, ended)."""
        self.frames = 0
        self.faces = 0
        self.alerts_raised = 0
        self.recent_alerts: deque[Alert] = deque(maxlen=RECENT_ALERTS)
        self.last: FrameRecord | None = None
        self._initial_verdict = verdict_of(config.monitor, initial_state(config.monitor))
        self.permanent_failure = ""
        """The permanent failure in force ('' for none; roadgaze.transport.failure_watch)."""
        self.problem_checks: list[Callable[[], str | None]] = []
        """Other parts' problems (a recording that stopped), asked at each state message."""

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self.last = record
        self.frames += 1
        self.faces += int(record.sample.face)
        if self.status == "starting":
            self.status = "running"
        for alert in record.alerts:
            self.note_alert(alert)

    def on_alert(self, alert: Alert) -> None:
        """An alert raised outside the frame loop: counted and logged like the others."""
        self.note_alert(alert)

    def note_alert(self, alert: Alert) -> None:
        """Count and log one alert (from a record, or raised outside the loop)."""
        message = AlertMessage.from_alert(
            alert, self.keys.vehicle_id, self.alerts_raised, self._wall_clock()
        )
        self.alerts_raised += 1
        self.recent_alerts.append(alert)
        self._log.info(
            "alert %s %s at t=%.2fs (off road %.2fs, window %.2fs)%s",
            alert.kind.value,
            alert.level.value,
            alert.t_s,
            alert.off_road_s,
            alert.window_off_road_s,
            f": {alert.reason}" if alert.reason else "",
            extra={"alert": message.model_dump(mode="json", by_alias=True)},
        )

    def _speed(
        self,
    ) -> tuple[float | None, Literal["none", "waiting", "fresh", "stale", "invalid"]]:
        speed = None if self.link is None else self.link.speed
        if speed is None:
            return None, "none"
        return speed.current()

    def state_message(self) -> StateMessage:
        """The current state; safe to call from Zenoh's callback thread."""
        record = self.last  # immutable: one consistent snapshot
        speed_kmh, speed_source = self._speed()
        transport = (
            self.link.status()
            if self.link is not None
            else TransportStatus(mode=self.config.zenoh.mode, session_open=False, connected=False)
        )
        problems: list[str] = []
        source_status = "opening"
        camera_reopens = 0
        if self.source is not None:
            current = self.source.status
            source_status = current.state
            camera_reopens = current.reopen_attempts
            if not current.connected:
                problems.append(current.message or "camera lost; reconnecting")
        if self.link is not None and not transport.connected:
            problems.append("zenoh not connected")
        verdict = self._initial_verdict if record is None else record.verdict
        eyes = verdict.eyes
        if eyes.degraded:
            problems.append(
                f"eyes unavailable for {eyes.unavailable_s:.0f} s ({eyes.reason or 'unknown'}): "
                "monitoring on head pose only"
            )
        if verdict.failure and not (eyes.degraded and verdict.failure == "eyes unjudgeable"):
            problems.append(f"temporary failure: {verdict.failure}")  # (the eyes: said above)
        if notice := notice_in(verdict.outputs):
            problems.append(f"not functional: {notice}")
        if self.permanent_failure:
            problems.append(f"permanent failure: {self.permanent_failure}")
        ambiguous = "" if record is None else record.sample.driver_ambiguous
        phone = None if record is None else record.sample.phone
        if ambiguous:
            problems.append(f"driver ambiguous: {ambiguous}")
        problems.extend(problem for check in self.problem_checks if (problem := check()))
        status = self.status
        if status in ("starting", "running") and problems:
            status = "degraded"
        monitor = self.config.monitor
        return StateMessage(
            vehicle_id=self.keys.vehicle_id,
            wall_time=self._wall_clock(),
            status=status,
            problems=problems,
            t_s=None if record is None else record.t_s,
            uptime_s=time.monotonic() - self._started,
            source=self.source_label,
            source_status=source_status,
            frames=self.frames,
            faces=self.faces,
            driver_ambiguous=ambiguous,
            camera_reopens=camera_reopens,
            permanent_failure=self.permanent_failure,
            transport=transport,
            monitor=MonitorSnapshot(
                **EyeFields.of(eyes),
                gaze=verdict.gaze,
                on_road=verdict.on_road is not False,
                neutral_yaw_deg=verdict.neutral_yaw_deg,
                yaw_deg=verdict.yaw_deg,
                zone=verdict.zone,
                neutral_pitch_deg=verdict.neutral_pitch_deg,
                pitch_deg=verdict.pitch_deg,
                off_road_s=verdict.off_road_s,
                window_off_road_s=verdict.window_off_road_s,
                unavailable_s=verdict.unavailable_s,
                vats_armed=verdict.vats_armed,
                active_alerts=[kind.value for kind in verdict.active],
                moving=verdict.moving,
                speed_kmh=speed_kmh,
                speed_source=speed_source,
                alert_counts=dict(verdict.alert_counts),
                eye_calibration=eyes.calibration,
                protocol=monitor.protocol,
                camera_mounting=CameraMounting.from_config(monitor).name,
                distraction_s=max(0.0, verdict.distraction_s),
                distraction_warn_s=verdict.distraction_warn_s,
                distraction_rule=verdict.distraction_rule,
                failure=verdict.failure,
                phone_detection=phone is not None,
                phone_use=None if phone is None else phone.phone_use,
                non_functional=notice_in(verdict.outputs),
                support_forward=SupportLevel.of(verdict, FORWARD),
                support_lane=SupportLevel.of(verdict, LANE),
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

    def close(self) -> None:
        """Nothing to release."""
