"""A consumer of roadgaze's messages: every alert of a vehicle once, in order, checked.

`AlertConsumer` subscribes on a Zenoh session to a vehicle's (or every vehicle's) alerts through
Zenoh's advanced subscriber (history: the last alerts when it joins or when a daemon appears;
recovery: alerts missed during a link outage), to its liveliness token, its state and, if asked,
its yaw messages and the COVESA VSS values. Zenoh's callbacks only hand the raw bytes over to a
bounded queue (a slow callback would stall the whole session); every check runs in the caller's
thread, where `events()` (or `next_event()`) turns each message into one or more typed events
(`roadgaze.transport.consumer_events`; or `run(on_event)` calls you with each): a checked alert,
flagged when its vehicle has a second publisher or when it arrives late; the range of alerts
missed before it; a duplicate, a rejected or a refused (forged) message; a daemon appearing or
going (after its final state); the link up or lost. `AlertBook` keeps the totals. `roadgaze
listen` and docs/examples/consume_alerts.py are built on it.

    with AlertConsumer.connect(ZenohConfig(connect=["tcp/127.0.0.1:7447"]), "car-42") as c:
        for event in c.events(timeout_s=60.0):
            if isinstance(event, AlertReceived):
                print(event.alert["kind"], event.suspicious or "")
"""

from __future__ import annotations

import collections
import math
import queue
import time
from collections.abc import Callable, Iterator
from typing import Any

from roadgaze.config import ZenohConfig
from roadgaze.transport.alert_book import AlertBook
from roadgaze.transport.checks import (
    PLAIN_PUBLISHER,
    Checked,
    DuplicateSeqError,
    MessageChecker,
    vehicle_of,
)
from roadgaze.transport.consumer_events import (
    AlertReceived,
    AlertRefused,
    AlertsMissed,
    ConsumerEvent,
    DuplicateAlert,
    LinkLost,
    LinkUp,
    MessageReceived,
    MessageRejected,
    PublisherGone,
    PublisherJoined,
    SecondPublisher,
    VssReceived,
)
from roadgaze.transport.declared import undeclare_all
from roadgaze.transport.keys import Keys
from roadgaze.transport.payloads import MESSAGE_MAX_BYTES, PayloadError
from roadgaze.types import ClosesOnExit

QUEUE_SIZE = 10_000
"""Raw messages waiting for the caller's thread; beyond it they are dropped and counted."""
VSS_MAX_BYTES = 256
"""A VSS value is a short text; anything longer is refused unread."""
LEFT_HOLD_S = 0.5
"""A daemon's `PublisherGone` waits this long for its final state, handed on before it."""
ALIVE_HISTORY_S = 0.5
"""At start, how long the liveliness history may take before alerts are subscribed (so a
running daemon's `PublisherJoined` comes before its cached alerts)."""
POLL_S = 0.2


def _never() -> bool:
    return False


class AlertConsumer(ClosesOnExit):
    """The subscriptions of one consumer on `session` and the checks of what they receive.

    `keys` name one vehicle or, with vehicle id `*`, all; `prefix_template` is the configured
    prefix (`vehicle/{vehicle_id}/dms`) the vehicle id is read from. `history` is how many
    alerts the advanced subscriber asks each publisher for (the daemon's cache size). Not
    thread-safe: one thread reads the events. `close()` undeclares everything (and closes the
    session when `connect` opened it).
    """

    def __init__(
        self,
        session: Any,
        keys: Keys,
        prefix_template: str,
        *,
        history: int = 100,
        yaw: bool = False,
        vss_prefix: str | None = None,
        max_bytes: int = MESSAGE_MAX_BYTES,
        queue_size: int = QUEUE_SIZE,
    ) -> None:
        import zenoh

        self.session = session
        self.keys = keys
        self.prefix_template = prefix_template
        self.history = history
        self.yaw = yaw
        self.vss_prefix = vss_prefix
        """The prefix of the VSS keys ('' for the bare paths); None: not subscribed."""
        self.max_bytes = max_bytes
        self.checker = MessageChecker(prefix_template, max_bytes)
        self.book = AlertBook()
        self.dropped = 0
        """Raw messages dropped because the queue was full (the reader too slow)."""
        self.connected: set[str] = set()
        self.ever_connected = False
        self.owns_session = False
        self.subscribed = False
        self._received: queue.Queue[tuple[str, str, bytes | int, str | None]] = queue.Queue(
            queue_size
        )
        self._ready: collections.deque[ConsumerEvent] = collections.deque()
        self._left: dict[str, tuple[float, str]] = {}
        """Vehicle -> (deadline, key) of a `PublisherGone` held for the vehicle's final state."""
        self._alive_seen = False
        self._put = zenoh.SampleKind.PUT
        self._entities: list[Any] = [
            session.info.declare_transport_events_listener(self._on_transport, history=True)
        ]

    @classmethod
    def connect(
        cls,
        config: ZenohConfig,
        vehicle_id: str | None = None,
        *,
        mode: str | None = None,
        wait_s: float = math.inf,
        stopped: Callable[[], bool] = _never,
        yaw: bool = False,
        vss: bool = False,
    ) -> AlertConsumer:
        """A consumer on a session of its own for `config` (a client of the rendezvous or of
        `config.connect` unless `mode` says peer), opened when its router answers (waiting up to
        `wait_s`); `vehicle_id` None or `*` for every vehicle. Raises `TransportError` when no
        session opens."""
        from roadgaze.transport.session import open_session, plan_session

        keys = Keys.matching(config, vehicle_id)
        plan = plan_session(config, "consumer", mode=mode)
        session = open_session(plan, wait_s=wait_s, stopped=stopped)
        try:
            consumer = cls(
                session,
                keys,
                config.prefix,
                history=config.alert_cache_size,
                yaw=yaw,
                vss_prefix=config.vss_prefix if vss else None,
            )
        except BaseException:
            session.close()
            raise
        consumer.owns_session = True
        return consumer

    # Zenoh's threads: O(1), hand over only.

    def _emit(self, kind: str, key: str, data: bytes | int, source: str | None = None) -> None:
        try:
            self._received.put_nowait((kind, key, data, source))
        except queue.Full:
            self.dropped += 1

    def _on_transport(self, event: Any) -> None:
        zid = str(event.transport.zid)
        whatami = str(event.transport.whatami).rsplit(".", 1)[-1].lower()
        if event.kind == self._put:
            self.connected.add(zid)
            self.ever_connected = True
            self._emit("link-up", whatami, zid.encode())
        else:
            self.connected.discard(zid)
            self._emit("link-lost", whatami, zid.encode())

    def _on_sample(self, sample: Any) -> None:
        """Size check before any copy."""
        key = str(sample.key_expr)
        size = len(sample.payload)
        info = sample.source_info
        source = None if info is None else str(info.source_id)
        data = size if size > self.max_bytes else sample.payload.to_bytes()
        self._emit(key.rsplit("/", 1)[-1], key, data, source)

    def _on_vss(self, sample: Any) -> None:
        size = len(sample.payload)
        data = size if size > VSS_MAX_BYTES else sample.payload.to_bytes()
        self._emit("vss", str(sample.key_expr), data)

    def _on_alive(self, sample: Any) -> None:
        self._alive_seen = True
        self._emit("alive", str(sample.key_expr), int(sample.kind == self._put))

    def _on_miss(self, miss: Any) -> None:
        self._emit("missed", self.keys.alert, int(miss.nb), str(miss.source))

    # The caller's thread.

    def subscribe(self, stopped: Callable[[], bool] = _never) -> None:
        """Declare the subscriptions: once the session's links are told, the liveliness token
        (waiting up to `ALIVE_HISTORY_S` for its history, so a running daemon's `PublisherJoined`
        comes before its cached alerts), then alerts, state, yaw and VSS as asked."""
        from zenoh.ext import HistoryConfig, RecoveryConfig, declare_advanced_subscriber

        if self.subscribed:
            return
        self.subscribed = True
        session, keys = self.session, self.keys
        # The links the session already has are told first (the transport listener's history
        # comes on Zenoh's thread, in no set order with the liveliness history): a publisher is
        # never seen before the link it came by.
        linked = [*session.info.routers_zid(), *session.info.peers_zid()]
        deadline = time.monotonic() + ALIVE_HISTORY_S
        while linked and not self.ever_connected and time.monotonic() < deadline and not stopped():
            time.sleep(0.02)
        self._entities.append(
            session.liveliness().declare_subscriber(keys.alive, self._on_alive, history=True)
        )
        deadline = time.monotonic() + ALIVE_HISTORY_S
        while not self._alive_seen and time.monotonic() < deadline and not stopped():
            time.sleep(0.02)
        alerts = declare_advanced_subscriber(
            session,
            keys.alert,
            self._on_sample,
            history=HistoryConfig(detect_late_publishers=True, max_samples=self.history),
            recovery=RecoveryConfig(heartbeat=True),  # type: ignore[call-arg]  # stub: both required
        )
        self._entities.append(alerts)
        self._entities.append(alerts.sample_miss_listener(self._on_miss))
        self._entities.append(session.declare_subscriber(keys.state, self._on_sample))
        if self.yaw:
            self._entities.append(session.declare_subscriber(keys.yaw, self._on_sample))
        if self.vss_prefix is not None:
            from roadgaze.transport.vss import vss_key

            self._entities.append(
                session.declare_subscriber(vss_key("Vehicle.**", self.vss_prefix), self._on_vss)
            )

    def events(
        self, timeout_s: float | None = None, stopped: Callable[[], bool] = _never
    ) -> Iterator[ConsumerEvent]:
        """The events, in order, until `timeout_s` (None: until `stopped()`); subscribes first
        when `subscribe` was not called. `finish()` gives what is left at the end."""
        self.subscribe(stopped)
        deadline = math.inf if timeout_s is None else time.monotonic() + timeout_s
        while not stopped():
            wait_s = min(POLL_S, deadline - time.monotonic())
            if wait_s <= 0:
                return
            event = self.next_event(wait_s)
            if event is not None:
                yield event

    def run(
        self,
        on_event: Callable[[ConsumerEvent], None],
        timeout_s: float | None = None,
        stopped: Callable[[], bool] = _never,
    ) -> None:
        """Call `on_event` with each event, in the caller's thread, until `timeout_s` (None:
        until `stopped()`), then with those `finish()` gives."""
        for event in self.events(timeout_s, stopped):
            on_event(event)
        for event in self.finish():
            on_event(event)

    def next_event(self, timeout_s: float) -> ConsumerEvent | None:
        """The next event, waiting up to `timeout_s`; None when nothing came."""
        self._release_left(time.monotonic())
        if not self._ready:
            if self._left:
                timeout_s = min(timeout_s, 0.05)
            try:
                self._process(*self._received.get(timeout=max(0.0, timeout_s)))
            except queue.Empty:
                self._release_left(time.monotonic())
        return self._ready.popleft() if self._ready else None

    def finish(self) -> list[ConsumerEvent]:
        """At the end: the held `PublisherGone` events and the Zenoh miss reports no later
        alert explained."""
        self._release_left(math.inf)
        events = list(self._ready)
        self._ready.clear()
        for vehicle, count, line in self.book.unmatched():
            events.append(AlertsMissed(vehicle, count, line))
        return events

    def _release_left(self, now: float, only: str | None = None) -> None:
        due = [
            vehicle
            for vehicle, (deadline, _) in self._left.items()
            if (only is None or vehicle == only) and deadline <= now
        ]
        for vehicle in due:
            _, key = self._left.pop(vehicle)
            self._ready.append(PublisherGone(vehicle, key))

    def _process(self, kind: str, key: str, data: bytes | int, source: str | None) -> None:
        ready = self._ready
        if kind in ("link-up", "link-lost"):
            remote = bytes(data).decode() if isinstance(data, bytes) else str(data)
            ready.append((LinkUp if kind == "link-up" else LinkLost)(remote, key))
            return
        if kind == "vss":
            self._vss(key, data)
            return
        vehicle = vehicle_of(key, self.prefix_template)
        if kind == "missed":
            self.book.on_zenoh_miss(str(source), int(data))
        elif kind == "alive":
            self.book.on_alive(vehicle, bool(data))
            if data:
                self._left.pop(vehicle, None)  # back at once: no `gone` in between
                ready.append(PublisherJoined(vehicle, key))
            else:
                self._left[vehicle] = (time.monotonic() + LEFT_HOLD_S, key)
        elif isinstance(data, int):
            self.book.rejected += 1
            ready.append(MessageRejected(kind, key, f"{data} bytes, limit {self.max_bytes}"))
        else:
            try:
                checked = self.checker.check(kind, key, data, source)
            except DuplicateSeqError as exc:
                self.book.rejected += 1
                ready.append(DuplicateAlert(vehicle, key, exc.seq, exc.expected))
                return
            except PayloadError as exc:
                self.book.rejected += 1
                ready.append(MessageRejected(kind, key, str(exc)))
                return
            if kind == "alert":
                self._alert(checked, source)
                return
            ready.append(MessageReceived(kind, vehicle, key, checked.payload))
            if kind == "state" and vehicle in self._left:
                self._release_left(math.inf, vehicle)

    def _alert(self, checked: Checked, source: str | None) -> None:
        """Hand on an alert of any advanced publisher (flagged when its vehicle has two);
        refuse a plain put; report the gap before it (first publisher only)."""
        book, vehicle, payload = self.book, checked.vehicle_id, checked.payload
        if source is None or source == PLAIN_PUBLISHER:
            book.foreign += 1
            refused = book.foreign_source(vehicle, source) or "a plain put"
            self._ready.append(AlertRefused(vehicle, checked.key, payload, refused))
            return
        before = book.publishers(vehicle)
        second = book.foreign_source(vehicle, source) is not None
        publishers = book.publishers(vehicle)
        if second:
            book.foreign += 1
            book.flagged += 1
            if source not in before:
                self._ready.append(SecondPublisher(vehicle, source, publishers))
        else:
            seq = int(payload["seq"])
            line = book.gap(vehicle, source, seq, checked.missing_before, checked.first)
            if line is not None:
                first = 0 if checked.first else seq - checked.missing_before
                self._ready.append(AlertsMissed(vehicle, seq - first, line, first, seq - 1))
            book.printed += 1
        self._ready.append(
            AlertReceived(vehicle, checked.key, payload, source, publishers, checked.late)
        )

    def _vss(self, key: str, data: bytes | int) -> None:
        from roadgaze.transport.vss import parse_vss_text

        try:
            if isinstance(data, int):
                raise PayloadError(f"{data} bytes, limit {VSS_MAX_BYTES}")
            value = parse_vss_text(key, data, self.vss_prefix or "")
        except PayloadError as exc:
            self._ready.append(MessageRejected("vss", key, str(exc)))
            return
        self._ready.append(VssReceived(key, value))

    def close(self) -> None:
        undeclare_all(self._entities)
        if self.owns_session:
            self.owns_session = False
            self.session.close()
