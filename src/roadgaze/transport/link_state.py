"""What the daemon knows about its Zenoh link, from Zenoh's transport events, and the alert counts.

The link is up while at least one transport to a router, peer or client is open (a consumer
connected straight to a listening daemon is a client). `LinkState.on_event` is the transport
events callback; it logs each change once: "zenoh connected" only when a transport really opened.
`LinkState.on_matching` is told whether a subscriber of the alert key is there (Zenoh's matching
status): the alert ledger counts an alert delivered only when one was, or came in time.

On a live link with no subscriber an alert waits for one (at exit, up to `zenoh.delivery_wait_s`:
a consumer still connecting gets it). If no subscriber came to the bus during the whole run,
such an alert is gone when the daemon stops (nobody ever listened: a consumer not started, or
on the wrong keys). Once subscribers have come and left (consumers come and go, as `listen
--count` does), it is taken as on the bus, as a put on a live link always was, and named in a
warning at exit if no subscriber came back for it.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from roadgaze.transport.ledger import AlertId, AlertLedger

log = logging.getLogger("roadgaze.daemon")

RECOVERY_GRACE_S = 2.0
"""How long a subscriber that just matched (or whose link just came back) is given to fetch the
waiting alerts from the cache: its history query or its recovery after a heartbeat (0.5 s)."""


@dataclass(slots=True)
class AlertCounts:
    """Where each alert went. `published` = `sent` + `held_while_down` (+ `pending` before the
    first session); `failed` were never published."""

    published: int = 0
    """Handed to the advanced publisher (in `seq` order)."""
    sent: int = 0
    """Published while a transport was open: handed to a live link."""
    held_while_down: int = 0
    """Published while no transport was open: only in the publisher's cache, delivered to
    subscribers with history or recovery when the link is back."""
    beyond_cache: int = 0
    """Of those, pushed out of the cache before the link came back: lost to every subscriber
    that had not received them."""
    failed: int = 0
    """The put raised (session closed under us): never published."""


class LinkState:
    """Open transports by remote id, from `session.info.declare_transport_events_listener`.

    Thread-safe. `cache_size` is the advanced publisher's cache: alerts put during one outage
    beyond it are counted as `beyond_cache`.
    """

    def __init__(
        self,
        cache_size: int,
        grace_s: float = RECOVERY_GRACE_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._cache_size = cache_size
        self._clock = clock
        self._lock = threading.Lock()
        self._remote: dict[str, str] = {}
        """Remote zenoh id -> 'router' | 'peer' | 'client'."""
        self.ups = 0
        self.downs = 0
        self.changed_at = clock()
        self._up_since: float | None = None
        self._matched_since: float | None = None
        """Since when a subscriber of the alert key is matched (None: none now)."""
        self.ever_matched = False
        """A subscriber of the alert key was there at some time during the run."""
        self._puts_while_down = 0
        self.counts = AlertCounts()
        self.ledger = AlertLedger(cache_size, grace_s)
        """Which alerts wait for a subscriber or are gone; read through `undelivered()`."""

    def on_event(self, event: Any) -> None:
        """Zenoh transport event callback: PUT = a transport opened, DELETE = it closed."""
        transport = event.transport
        zid = str(transport.zid)
        whatami = str(transport.whatami).rsplit(".", 1)[-1].lower()
        opened = str(event.kind).rsplit(".", 1)[-1].upper() == "PUT"
        with self._lock:
            was_up = bool(self._remote)
            if opened:
                self._remote[zid] = whatami
            else:
                self._remote.pop(zid, None)
            up = bool(self._remote)
            if up != was_up:
                self.changed_at = self._clock()
                if up:
                    self.ups += 1
                    held, self._puts_while_down = self._puts_while_down, 0
                    self._up_since = self.changed_at
                else:
                    self.downs += 1
                    self._up_since = None
        if up and not was_up:
            again = (
                f"; {held} alerts held while down go to subscribers with recovery" if held else ""
            )
            log.info("zenoh connected: %s %s%s", whatami, zid, again)
        elif opened:
            log.info("zenoh connected: %s %s (one more)", whatami, zid)
        elif was_up and not up:
            log.warning(
                "zenoh link down (%s %s gone): monitoring goes on, alerts are held in the "
                "publisher cache (last %d) until a link is back",
                whatami,
                zid,
                self._cache_size,
            )

    def on_matching(self, matched: bool) -> None:
        """Whether a subscriber of the alert key is there now (Zenoh's matching status). One
        that leaves while the link is up had the waiting alerts to fetch: they are delivered."""
        with self._lock:
            if not matched:
                if self._available_s() is not None:
                    self.ledger.fetched()
                self._matched_since = None
            elif self._matched_since is None:
                self._matched_since = self._clock()
                self.ever_matched = True

    def _available_s(self) -> float | None:
        """Since when a link is up with a subscriber matched (None: not now); under the lock."""
        if self._up_since is None or self._matched_since is None:
            return None
        return max(self._up_since, self._matched_since)

    def _waiting_why(self) -> str:
        if self._up_since is None:
            return "held, no link yet"
        if self._matched_since is None:
            return "in the publisher's cache, no subscriber yet"
        return "in the publisher's cache, a subscriber just came: fetching it"

    @property
    def up(self) -> bool:
        with self._lock:
            return bool(self._remote)

    def remotes(self) -> tuple[int, int, int]:
        """Open transports to (routers, peers, clients)."""
        with self._lock:
            kinds = list(self._remote.values())
        return kinds.count("router"), kinds.count("peer"), kinds.count("client")

    def count_alert(
        self, published: bool, alert: AlertId | None = None, why: str = "its put failed"
    ) -> None:
        """Count one alert handed to the publisher (`published`) or whose put raised (`why`)."""
        with self._lock:
            counts = self.counts
            if not published:
                counts.failed += 1
                self.ledger.gone(alert, why)
                return
            counts.published += 1
            now = self._clock()
            up = bool(self._remote)
            pushed_out: str | None = None  # on a live bus subscribers have left: on the bus
            if not up or not self.ever_matched:
                pushed_out = (
                    f"pushed out of the publisher's cache (zenoh.alert_cache_size = "
                    f"{self._cache_size}) "
                    + ("while no link was up" if not up else "before any subscriber came")
                )
            self.ledger.confirm(self._available_s(), now)
            delivered = up and self._matched_since is not None
            self.ledger.published(alert, delivered, now, pushed_out)
            if up:
                counts.sent += 1
                return
            counts.held_while_down += 1
            self._puts_while_down += 1
            if self._puts_while_down > self._cache_size:
                counts.beyond_cache += 1

    def gone(self, alert: AlertId | None, why: str) -> None:
        """One alert that never reached the publisher (dropped before a session opened)."""
        with self._lock:
            self.ledger.gone(alert, why)

    def stopped(self, ending: str = "the daemon stopped") -> list[str]:
        """At exit: alerts still waiting are gone (no link, no subscriber during the whole run,
        or one that had no time to fetch them); on a live bus whose subscribers have left they
        stay on it: their names are returned. `ending` says what ended (`the replay ended`)."""
        with self._lock:
            self.ledger.confirm(self._available_s(), self._clock())
            if self._up_since is None:
                why = f"never delivered: no link when {ending}"
            elif self._matched_since is not None:
                why = f"perhaps never delivered: a subscriber had just come when {ending}"
            elif self.ever_matched:
                return self.ledger.release()
            else:
                who = "the replay" if "replay" in ending else "the daemon"
                why = f"never delivered: no subscriber came to the bus while {who} ran"
            self.ledger.stopped(why)
            return []

    def undelivered(self) -> tuple[int, int, list[str]]:
        """(waiting now, gone in all, the newest of both named with their fate)."""
        with self._lock:
            ledger = self.ledger
            ledger.confirm(self._available_s(), self._clock())
            return len(ledger.held), ledger.lost_total, ledger.undelivered(self._waiting_why())

    def settled_at(self) -> float | None:
        """When the alerts waiting now will count as delivered if the link and the subscriber
        stay (None: nothing waits, or no link or no subscriber now)."""
        with self._lock:
            available = self._available_s()
            if not self.ledger.held or available is None:
                return None
            return max(self.ledger.held[-1].put_s, available) + self.ledger.grace_s

    def snapshot(self) -> AlertCounts:
        with self._lock:
            counts = self.counts
            return AlertCounts(
                counts.published,
                counts.sent,
                counts.held_while_down,
                counts.beyond_cache,
                counts.failed,
            )
