"""What the daemon knows about its Zenoh link, from Zenoh's transport events, and the alert counts.

The link is up while at least one transport to a router, peer or client is open (a consumer
connected straight to a listening daemon is a client). `LinkState.on_event` is the transport
events callback; it logs each change once: "zenoh connected" only when a transport really opened.
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass
from typing import Any

from roadgaze.transport.ledger import AlertId, AlertLedger

log = logging.getLogger("roadgaze.daemon")


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

    def __init__(self, cache_size: int) -> None:
        self._cache_size = cache_size
        self._lock = threading.Lock()
        self._remote: dict[str, str] = {}
        """Remote zenoh id -> 'router' | 'peer' | 'client'."""
        self.ups = 0
        self.downs = 0
        self.changed_at = time.monotonic()
        self._puts_while_down = 0
        self.counts = AlertCounts()
        self.ledger = AlertLedger(cache_size)
        """Which alerts are held for recovery or gone; read through `undelivered()`."""

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
                self.changed_at = time.monotonic()
                if up:
                    self.ups += 1
                    held, self._puts_while_down = self._puts_while_down, 0
                    self.ledger.link_up()
                else:
                    self.downs += 1
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
            self.ledger.published(alert, link_up=bool(self._remote))
            if self._remote:
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

    def stopped(self, why: str = "never delivered: no link when the daemon stopped") -> int:
        """At exit: alerts still held (no link since they were published) are gone."""
        with self._lock:
            return self.ledger.stopped(why)

    def undelivered(self) -> tuple[int, int, list[str]]:
        """(held now, gone in all, the newest of both named with their fate)."""
        with self._lock:
            ledger = self.ledger
            return len(ledger.held), ledger.lost_total, ledger.undelivered()

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
