"""The daemon's Zenoh link: publishers, speed input, liveliness token and state queryable.

Under the prefix (default `vehicle/{vehicle_id}/dms`):

- `yaw`: one `YawMessage` per frame, congestion control DROP (a slow subscriber loses yaw
  samples, never delays the pipeline);
- `alert`: one `AlertMessage` per monitor event, priority INTERACTIVE_HIGH, congestion control
  BLOCK (an alert is never dropped by the local queue);
- `alive`: a liveliness token, present while the daemon runs;
- `state`: a queryable answering a `StateMessage` (status, counters, config summary);
- with `vss_keys`, one text publisher per COVESA VSS signal (`roadgaze.transport.vss`).

When the session cannot be opened (client mode and no router, say) the link is degraded:
monitoring goes on, messages are counted as not sent (alerts are kept in a small bounded queue
and sent once connected) and the session is re-opened with backoff in a background thread. In
peer mode Zenoh itself retries the `connect` endpoints; the link reports degraded while none of
them is connected.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from roadgaze.config import ZenohConfig
from roadgaze.transport.keys import Keys
from roadgaze.transport.messages import AlertMessage, TransportStatus, YawMessage
from roadgaze.transport.session import build_zenoh_config, zenoh_error_text
from roadgaze.transport.speed import SpeedInput
from roadgaze.transport.vss import VSS_ATTACHMENT

log = logging.getLogger(__name__)

PENDING_ALERTS_MAX = 256
"""Alerts kept while no session is open; the oldest are dropped (and counted) beyond this."""
PENDING_FLUSH_WAIT_S = 2.0
"""After a session (re)opens, how long kept alerts wait for a matching subscriber."""


class _Declared:
    """Everything declared on one open session; closed together."""

    def __init__(
        self,
        session: Any,
        keys: Keys,
        state_reply: Callable[[], bytes] | None,
        speed: SpeedInput | None,
        vss_keys: tuple[str, ...] = (),
    ) -> None:
        import zenoh

        self.session = session
        self._entities: list[Any] = []
        self.vss: dict[str, Any] = {}
        try:
            for key in vss_keys:
                self.vss[key] = session.declare_publisher(
                    key,
                    encoding=zenoh.Encoding.TEXT_PLAIN,
                    congestion_control=zenoh.CongestionControl.BLOCK,
                    priority=zenoh.Priority.DATA,
                )
                self._entities.append(self.vss[key])
            self.yaw = session.declare_publisher(
                keys.yaw,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.DROP,
                priority=zenoh.Priority.DATA,
            )
            self._entities.append(self.yaw)
            self.alert = session.declare_publisher(
                keys.alert,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.BLOCK,
                priority=zenoh.Priority.INTERACTIVE_HIGH,
            )
            self._entities.append(self.alert)
            if speed is not None and keys.speed is not None:
                self._entities.append(
                    session.declare_subscriber(
                        keys.speed, lambda sample: speed.on_payload(sample.payload.to_bytes())
                    )
                )
            if state_reply is not None:
                self._entities.append(
                    session.declare_queryable(keys.state, _state_callback(keys.state, state_reply))
                )
            self._entities.append(session.liveliness().declare_token(keys.alive))
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        for entity in reversed(self._entities):
            try:
                entity.undeclare()
            except Exception as exc:
                log.debug("undeclare failed: %s", exc)
        self._entities.clear()
        try:
            self.session.close()
        except Exception as exc:
            log.debug("session close failed: %s", exc)


def _state_callback(key: str, state_reply: Callable[[], bytes]) -> Callable[[Any], None]:
    import zenoh

    def on_query(query: Any) -> None:
        try:
            query.reply(key, state_reply(), encoding=zenoh.Encoding.APPLICATION_JSON)
        except Exception:
            log.exception("could not answer a state query")

    return on_query


class ZenohLink:
    """The daemon's session: publishers, speed input, liveliness token and state queryable.

    Use as a context manager. Never raises on publish: failures are counted and logged, and an
    unopenable session is retried in the background with exponential backoff.
    """

    def __init__(
        self,
        config: ZenohConfig,
        keys: Keys,
        state_reply: Callable[[], bytes] | None = None,
        speed: SpeedInput | None = None,
        vss_keys: tuple[str, ...] = (),
    ) -> None:
        self.config = config
        self.keys = keys
        self.vss_keys = vss_keys
        self._state_reply = state_reply
        self.speed = speed
        self._zconf = build_zenoh_config(config)  # bad settings fail here, at once
        self._lock = threading.Lock()
        self._declared: _Declared | None = None
        self._pending: deque[bytes] = deque(maxlen=PENDING_ALERTS_MAX)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.session_reopens = 0
        self.yaw_sent = 0
        self.vss_sent = 0
        self.alerts_sent = 0
        self.not_sent = 0
        self.last_error: str | None = None

    def __enter__(self) -> ZenohLink:
        self.start()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def start(self) -> None:
        if not self._try_open():
            self._thread = threading.Thread(
                target=self._reopen_loop, name="zenoh-reopen", daemon=True
            )
            self._thread.start()

    def _try_open(self) -> bool:
        import zenoh

        try:
            session = zenoh.open(self._zconf)
            declared = _Declared(session, self.keys, self._state_reply, self.speed, self.vss_keys)
        except Exception as exc:
            self.last_error = zenoh_error_text(exc)
            log.warning("zenoh session not available (%s); monitoring goes on", self.last_error)
            return False
        self.last_error = None
        log.info("zenoh session open (%s), prefix %s", self.config.mode, self.keys.prefix)
        if self._pending:
            # Give subscribers a moment to be matched, so kept alerts reach somebody.
            deadline = time.monotonic() + PENDING_FLUSH_WAIT_S
            while not declared.alert.matching_status.matching and time.monotonic() < deadline:
                if self._stop.wait(0.05):
                    break
        while True:
            with self._lock:
                if self._stop.is_set():
                    declared.close()
                    return True
                pending = list(self._pending)
                self._pending.clear()
                if not pending:
                    self._declared = declared
                    return True
            for payload in pending:
                self._put(declared, payload)

    def _reopen_loop(self) -> None:
        delay_s = self.config.reconnect_initial_s
        while not self._stop.wait(delay_s):
            self.session_reopens += 1
            if self._try_open():
                return
            delay_s = min(delay_s * 2.0, self.config.reconnect_max_s)

    def publish_yaw(self, message: YawMessage) -> None:
        declared = self._declared
        if declared is None:
            self.not_sent += 1
            return
        try:
            declared.yaw.put(message.to_json_bytes())
            self.yaw_sent += 1
        except Exception as exc:
            self.not_sent += 1
            self.last_error = f"yaw put failed: {exc}"

    def publish_vss(self, key: str, payload: bytes) -> None:
        """One VSS value (text) on its key, with Kuksa's `currentValue` attachment; counted as
        not sent without a session (the next change is sent again)."""
        declared = self._declared
        publisher = None if declared is None else declared.vss.get(key)
        if publisher is None:
            self.not_sent += 1
            return
        try:
            publisher.put(payload, attachment=VSS_ATTACHMENT)
            self.vss_sent += 1
        except Exception as exc:
            self.not_sent += 1
            self.last_error = f"vss put failed: {exc}"

    def publish_alert(self, message: AlertMessage) -> None:
        payload = message.to_json_bytes()
        with self._lock:
            if self._declared is None:
                if len(self._pending) == self._pending.maxlen:
                    self.not_sent += 1
                self._pending.append(payload)
                log.warning("alert %s kept until the zenoh session opens", message.kind)
                return
        self._put_alert(payload)

    def _put_alert(self, payload: bytes) -> None:
        # Never hold the lock while Zenoh may block: its callbacks (state queries) take it too.
        with self._lock:
            declared = self._declared
            if declared is None:
                self._pending.append(payload)
                return
        self._put(declared, payload)

    def _put(self, declared: _Declared, payload: bytes) -> None:
        try:
            declared.alert.put(payload)
            self.alerts_sent += 1
        except Exception as exc:
            self.not_sent += 1
            self.last_error = f"alert put failed: {exc}"
            log.error("alert not sent: %s", exc)

    def status(self) -> TransportStatus:
        with self._lock:
            declared = self._declared
            pending = len(self._pending)
        peers = routers = 0
        if declared is not None:
            try:
                info = declared.session.info
                peers, routers = len(info.peers_zid()), len(info.routers_zid())
            except Exception as exc:
                log.debug("session info failed: %s", exc)
        needs_link = bool(self.config.connect) or self.config.mode == "client"
        connected = declared is not None and (not needs_link or peers + routers > 0)
        speed_messages = self.speed.messages if self.speed is not None else 0
        speed_rejected = self.speed.rejected if self.speed is not None else 0
        return TransportStatus(
            mode=self.config.mode,
            session_open=declared is not None,
            connected=connected,
            peers=peers,
            routers=routers,
            session_reopens=self.session_reopens,
            yaw_sent=self.yaw_sent,
            vss_sent=self.vss_sent,
            alerts_sent=self.alerts_sent,
            not_sent=self.not_sent,
            pending_alerts=pending,
            speed_messages=speed_messages,
            speed_rejected=speed_rejected,
        )

    def publish_final_state(self) -> None:
        """Put the current state on the state key (for subscribers; queries get it anyway)."""
        if self._state_reply is None:
            return
        import zenoh

        declared = self._declared
        if declared is None:
            return
        try:
            declared.session.put(
                self.keys.state,
                self._state_reply(),
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.BLOCK,
            )
        except Exception as exc:
            log.warning("final state not published: %s", exc)

    def close(self) -> None:
        """Undeclare everything and close the session; idempotent."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        with self._lock:
            declared, self._declared = self._declared, None
            if self._pending:
                log.warning("%d alerts never sent: no zenoh session", len(self._pending))
        if declared is not None:
            declared.close()
