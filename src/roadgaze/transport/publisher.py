"""The bus sink: every frame record's yaw message and each of its alerts, onto a message link."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Protocol

from roadgaze.transport.messages import AlertMessage, TransportStatus, YawMessage
from roadgaze.transport.speed import SpeedInput
from roadgaze.transport.support_message import SupportMessage
from roadgaze.types import Alert, Frame, FrameRecord


class MessageLink(Protocol):
    """Where messages go: `ZenohLink` in production, a list in tests."""

    speed: SpeedInput | None

    def publish_yaw(self, message: YawMessage) -> None: ...

    def publish_alert(self, message: AlertMessage) -> None: ...

    def publish_support(self, message: SupportMessage) -> None: ...

    def status(self) -> TransportStatus: ...


class BusPublisher:
    """Pipeline sink: publishes one `YawMessage` and one `SupportMessage` per record and one
    `AlertMessage` per alert.

    Sequence numbers count per key from 0; `wall_time` is stamped when the message is built.
    """

    def __init__(
        self,
        vehicle_id: str,
        link: MessageLink,
        wall_clock: Callable[[], float] = time.time,
    ) -> None:
        self.vehicle_id = vehicle_id
        self.link = link
        self._wall_clock = wall_clock
        self._yaw_seq = 0
        self._alert_seq = 0
        self._support_seq = 0
        self._lock = threading.Lock()

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        wall_time = self._wall_clock()
        self.link.publish_yaw(
            YawMessage.from_record(record, self.vehicle_id, self._yaw_seq, wall_time)
        )
        self._yaw_seq += 1
        self.link.publish_support(
            SupportMessage.from_record(record, self.vehicle_id, self._support_seq, wall_time)
        )
        self._support_seq += 1
        for alert in record.alerts:
            self.publish_alert(alert, wall_time)

    def on_alert(self, alert: Alert) -> None:
        """An alert raised outside the frame loop (a camera gone, a model unusable)."""
        self.publish_alert(alert)

    def publish_alert(self, alert: Alert, wall_time: float | None = None) -> None:
        """Publish one alert with the next sequence number (also from outside the loop: the
        permanent failure watch)."""
        wall_time = self._wall_clock() if wall_time is None else wall_time
        with self._lock:
            message = AlertMessage.from_alert(alert, self.vehicle_id, self._alert_seq, wall_time)
            self._alert_seq += 1
        self.link.publish_alert(message)

    def close(self) -> None:
        """Nothing to release: the link is owned by whoever opened it."""
