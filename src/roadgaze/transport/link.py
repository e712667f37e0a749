"""The daemon's Zenoh link: publishers, speed input, liveliness token and state queryable.

Under the prefix (default `vehicle/{vehicle_id}/dms`):

- `alert`: one `AlertMessage` per monitor event through Zenoh's advanced publisher: reliable,
  congestion control BLOCK, priority REAL_TIME, express, a cache of the last
  `zenoh.alert_cache_size` alerts, sample-miss detection (heartbeat every 0.5 s) and publisher
  detection. An advanced subscriber with history and recovery (`roadgaze listen`,
  docs/zenoh.md) gets every alert in order: those of a link outage from the cache once the link
  is back, and the last ones when it joins late. Plain subscribers get what is published while
  they are connected.
- `yaw`: one `YawMessage` per frame, congestion control DROP, priority DATA (droppable).
- `support`: one `SupportMessage` per frame (forward and lane support), congestion control DROP
  (the next frame says it again: never stalls the loop), priority REAL_TIME, express; a
  consumer that hears none for longer than it can wait takes support as heightened.
- `alive`: a liveliness token, present while the daemon runs.
- `state`: a queryable answering a `StateMessage` from a bounded thread (`StateResponder`).
- with `vss_keys`, one text publisher per COVESA VSS signal (`roadgaze.transport.vss`):
  congestion control BLOCK, priority DATA; no cache (every value is sent again each second).

The link state comes from Zenoh's transport events (`LinkState`): an alert published while no
transport is open is counted as held, never as sent. The speed subscriber keeps only the newest
sample inside Zenoh; the frame loop reads it (`SpeedInput.kmh`). A peer session opens without a
router; a client session cannot, so it is re-opened with backoff in a background thread while
alerts wait in a bounded queue (then enter the cache like any other).
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from roadgaze.config import ZenohConfig
from roadgaze.transport.declared import Declared
from roadgaze.transport.keys import Keys
from roadgaze.transport.ledger import NAMED_LOST, AlertId
from roadgaze.transport.link_state import RECOVERY_GRACE_S as RECOVERY_GRACE_S
from roadgaze.transport.link_state import LinkState
from roadgaze.transport.messages import AlertMessage, TransportStatus, YawMessage
from roadgaze.transport.session import (
    SessionPlan,
    build_zenoh_config,
    check_daemon_file,
    insecure_endpoints,
    plan_session,
    zenoh_error_text,
)
from roadgaze.transport.speed import SpeedInput
from roadgaze.transport.support_message import SupportMessage
from roadgaze.transport.vss import VSS_ATTACHMENT

log = logging.getLogger(__name__)


class ZenohLink:
    """The daemon's session: publishers, speed input, liveliness token and state queryable.

    Use as a context manager. Never raises on publish: failures are counted and logged.
    `state_reply` builds the state bytes (called from the responder thread).
    """

    def __init__(
        self,
        config: ZenohConfig,
        keys: Keys,
        state_reply: Callable[[], bytes] | None = None,
        speed: SpeedInput | None = None,
        plan: SessionPlan | None = None,
        vss_keys: tuple[str, ...] = (),
    ) -> None:
        self.config = config
        self.keys = keys
        self.vss_keys = vss_keys
        self.state_reply = state_reply
        self.speed = speed
        self._zconf, self.plan = build_zenoh_config(plan or plan_session(config, "daemon"))
        check_daemon_file(self._zconf, self.plan, keys.vehicle_id)
        self.link_state = LinkState(config.alert_cache_size)
        self._lock = threading.Lock()
        self._declared: Declared | None = None
        self._pending: deque[tuple[bytes, AlertId]] = deque(maxlen=config.alert_cache_size)
        self._pending_dropped = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.session_reopens = 0
        self.yaw_sent = 0
        self.yaw_not_sent = 0
        self.support_sent = 0
        self.support_not_sent = 0
        self.vss_sent = 0
        self.vss_not_sent = 0
        self.last_error: str | None = None

    def __enter__(self) -> ZenohLink:
        self.start()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def start(self) -> None:
        """Log the endpoints, warn about plain TCP off this machine, open (or keep trying)."""
        log.info("zenoh: %s", self.plan.describe())
        insecure = insecure_endpoints(self.plan.connect + self.plan.listen)
        if insecure:
            log.warning(
                "zenoh endpoints %s leave this machine without TLS: anyone on the network can "
                "read, forge or silence alerts (see docs/security.md, roadgaze security init)",
                ", ".join(insecure),
            )
        if not self._try_open():
            self._thread = threading.Thread(
                target=self._reopen_loop, name="zenoh-reopen", daemon=True
            )
            self._thread.start()

    def _try_open(self) -> bool:
        import zenoh

        try:
            session = zenoh.open(self._zconf)
        except Exception as exc:
            self.last_error = zenoh_error_text(exc)
            log.warning(
                "zenoh session not open yet (%s): monitoring goes on, alerts are held (up to "
                "%d) and retried",
                self.last_error,
                self.config.alert_cache_size,
            )
            return False
        try:
            declared = Declared(session, self)
        except Exception as exc:
            self.last_error = zenoh_error_text(exc)
            log.error("zenoh declarations failed: %s", self.last_error)
            return False
        self.last_error = None
        while True:  # alerts held before the session opened go first, in order
            with self._lock:
                if self._stop.is_set():
                    declared.close()
                    return True
                pending = list(self._pending)
                self._pending.clear()
                if not pending:
                    self._declared = declared
                    return True
            for payload, alert in pending:
                self._put(declared, payload, alert)

    def _reopen_loop(self) -> None:
        delay_s = self.config.reconnect_initial_s
        while not self._stop.wait(delay_s):
            self.session_reopens += 1
            if self._try_open():
                return
            delay_s = min(delay_s * 2.0, self.config.reconnect_max_s)

    def reply(self, query: Any, data: bytes) -> None:
        """Answer one state query (called by the responder thread)."""
        import zenoh

        query.reply(self.keys.state, data, encoding=zenoh.Encoding.APPLICATION_JSON)

    def publish_yaw(self, message: YawMessage) -> None:
        if self._put_frame("yaw", message.to_json_bytes()):
            self.yaw_sent += 1
        else:
            self.yaw_not_sent += 1  # droppable by design: the next frame says it again

    def publish_support(self, message: SupportMessage) -> None:
        """One frame's support; counted as not sent without a link (the next frame says it
        again, and a consumer hearing nothing takes support as heightened)."""
        if self._put_frame("support", message.to_json_bytes()):
            self.support_sent += 1
        else:
            self.support_not_sent += 1

    def _put_frame(self, name: str, payload: bytes) -> bool:
        """Put one frame's message on the publisher `name` (`yaw`, `support`); False when no
        link is up (nobody could receive it) or the put failed."""
        declared = self._declared
        if declared is None or not self.link_state.up:
            return False
        try:
            getattr(declared, name).put(payload)
        except Exception as exc:
            self.last_error = f"{name} put failed: {exc}"
            return False
        return True

    def publish_vss(self, key: str, payload: bytes) -> None:
        """One VSS value (text) on its key, with Kuksa's `currentValue` attachment; counted as
        not sent without a session (the next change is sent again)."""
        declared = self._declared
        publisher = None if declared is None else declared.vss.get(key)
        if publisher is None:
            self.vss_not_sent += 1
            return
        try:
            publisher.put(payload, attachment=VSS_ATTACHMENT)
            self.vss_sent += 1
        except Exception as exc:
            self.vss_not_sent += 1
            self.last_error = f"vss put failed: {exc}"

    def publish_alert(self, message: AlertMessage) -> None:
        """Publish (or, before a client session opens, hold) one alert; never raises."""
        payload = message.to_json_bytes()
        alert = AlertId(message.seq, message.kind.value, message.level.value, message.t_s)
        with self._lock:
            declared = self._declared
            if declared is None:
                if len(self._pending) == self._pending.maxlen:
                    self._pending_dropped += 1
                    dropped = self._pending[0][1]
                    self.link_state.gone(dropped, "dropped before the zenoh session opened")
                    log.error(
                        "alert %s dropped: held too long before the session opened",
                        dropped.describe(),
                    )
                self._pending.append((payload, alert))
                log.warning("alert %s held until the zenoh session opens", message.kind.value)
                return
        self._put(declared, payload, alert)

    def _put(self, declared: Declared, payload: bytes, alert: AlertId) -> None:
        # Never under self._lock: a BLOCK put may wait for a slow subscriber.
        try:
            declared.alert.put(payload)
        except Exception as exc:
            self.link_state.count_alert(False, alert, f"its put failed: {zenoh_error_text(exc)}")
            self.last_error = f"alert put failed: {exc}"
            log.error("alert not published: %s", exc)
            return
        self.link_state.count_alert(published=True, alert=alert)

    def undelivered(self) -> tuple[int, int, list[str]]:
        """(alerts waiting for a link: held in the cache or before the session; alerts gone;
        the newest of both, named with their fate)."""
        with self._lock:
            pending = [alert for _, alert in self._pending]
        held, gone, named = self.link_state.undelivered()
        waiting = [f"{alert.describe()}: held, no zenoh session yet" for alert in pending]
        return held + len(pending), gone, named + waiting[-NAMED_LOST:]

    def settle(self, wait_s: float, stop: Callable[[], bool] = lambda: False) -> None:
        """Before closing: with alerts still waiting (no link, no subscriber, or one that just
        came), wait up to `wait_s` for a link and a subscriber, then up to `RECOVERY_GRACE_S`
        more for that subscriber to fetch them from the cache."""
        waiting = self.undelivered()[0]
        if not waiting or wait_s <= 0:
            return
        log.warning(
            "%d alert%s not delivered yet: waiting up to %g s for a zenoh link and a subscriber "
            "(zenoh.delivery_wait_s)",
            waiting,
            "" if waiting == 1 else "s",
            wait_s,
        )
        deadline = time.monotonic() + wait_s
        while self.undelivered()[0] and not stop():
            settled = self.link_state.settled_at()
            now = time.monotonic()
            if now >= deadline + RECOVERY_GRACE_S or (settled is None and now >= deadline):
                return
            time.sleep(0.05)

    def stop_ledger(self, ending: str = "the daemon stopped") -> None:
        """At exit: alerts still waiting for a link (or a session, or a first subscriber) are
        gone; those left on a bus whose subscribers have gone are named in a warning. `ending`
        says what ended (`the replay ended`)."""
        left = self.link_state.stopped(ending)
        if left:
            log.warning(
                "%d alert%s published after the last subscriber left stay%s on the bus, not "
                "fetched by a new one (zenoh.delivery_wait_s = %g s): %s",
                len(left),
                "" if len(left) == 1 else "s",
                "s" if len(left) == 1 else "",
                self.config.delivery_wait_s,
                "; ".join(left[-NAMED_LOST:]),
            )
        with self._lock:
            pending, self._pending = list(self._pending), deque(maxlen=self._pending.maxlen)
        for _, alert in pending:
            self.link_state.gone(alert, f"never published: no zenoh session when {ending}")

    def status(self) -> TransportStatus:
        with self._lock:
            declared = self._declared
            pending = len(self._pending)
        routers, peers, clients = self.link_state.remotes()
        counts = self.link_state.snapshot()
        waiting, gone, named = self.undelivered()
        speed = self.speed
        return TransportStatus(
            mode="client"
            if self.plan.mode == "client"
            else "router"
            if self.plan.mode == "router"
            else "peer",
            session_open=declared is not None,
            connected=declared is not None and self.link_state.up,
            peers=peers,
            routers=routers,
            session_reopens=self.session_reopens,
            yaw_sent=self.yaw_sent,
            support_sent=self.support_sent,
            vss_sent=self.vss_sent,
            alerts_sent=counts.sent,
            not_sent=self.yaw_not_sent
            + self.support_not_sent
            + self.vss_not_sent
            + counts.failed
            + self._pending_dropped,
            pending_alerts=pending,
            speed_messages=speed.messages if speed is not None else 0,
            speed_rejected=speed.rejected if speed is not None else 0,
            clients=clients,
            link_downs=self.link_state.downs,
            connect=list(self.plan.connect),
            listen=list(self.plan.listen),
            alerts_published=counts.published,
            alerts_held_while_down=counts.held_while_down + pending,
            alerts_beyond_cache=counts.beyond_cache,
            alerts_failed=counts.failed + self._pending_dropped,
            alert_cache_size=self.config.alert_cache_size,
            yaw_not_sent=self.yaw_not_sent,
            speed_oversize=speed.oversize if speed is not None else 0,
            state_queries_answered=(
                declared.responder.answered
                if declared is not None and declared.responder is not None
                else 0
            ),
            alerts_waiting=waiting,
            alerts_lost=gone,
            undelivered_alerts=named,
        )

    def publish_final_state(self) -> None:
        """Put the current state on the state key (for subscribers; queries get it anyway). It is
        the service's last word, put just before the session closes: like an alert it goes out
        at once (express, REAL_TIME), not in a batch behind the frames' data."""
        declared = self._declared
        if self.state_reply is None:
            return
        if declared is None:
            log.warning("final state not published: no zenoh session")
            return
        import zenoh

        try:
            declared.session.put(
                self.keys.state,
                self.state_reply(),
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.BLOCK,
                priority=zenoh.Priority.REAL_TIME,
                express=True,
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
                log.error("%d alerts never published: no zenoh session", len(self._pending))
                pending, self._pending = list(self._pending), deque(maxlen=self._pending.maxlen)
                for _, alert in pending:
                    self.link_state.gone(alert, "never published: no zenoh session")
        if declared is not None:
            declared.close()
