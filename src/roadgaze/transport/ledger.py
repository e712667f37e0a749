"""Where every alert went: on the bus, held for recovery, or gone (pure: no Zenoh import).

An alert published while a link is up has reached the bus. One published while no link is up
is *held*: it waits in the advanced publisher's cache and reaches every subscriber with
recovery (or history) once a link is back. It is *gone* when it was pushed out of the cache
before that (more than `zenoh.alert_cache_size` in one outage), when its put failed, when it
was dropped before a client session opened, or when the daemon stopped with it still held (no
link at exit). `AlertLedger` keeps the held ones and names the newest gone ones, so the state
message, the final log line and the exit status can say which alerts never reached anyone.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

NAMED_LOST = 20
"""Gone alerts named in the state and the final warning (all are counted)."""


@dataclass(frozen=True, slots=True)
class AlertId:
    """What names one alert to a reader: its sequence number, kind, level and source time."""

    seq: int
    kind: str
    level: str
    t_s: float

    def describe(self) -> str:
        """`#3 long_distraction critical t=5.00s`."""
        return f"#{self.seq} {self.kind} {self.level} t={self.t_s:.2f}s"


class AlertLedger:
    """Held and gone alerts of one daemon; not thread-safe (`LinkState` holds the lock)."""

    def __init__(self, cache_size: int) -> None:
        self.cache_size = cache_size
        self.held: deque[AlertId | None] = deque()
        """Published while no link was up, still in the cache, oldest first."""
        self.lost_total = 0
        self.lost: deque[str] = deque(maxlen=NAMED_LOST)
        """The newest gone alerts, each with why."""

    def published(self, alert: AlertId | None, link_up: bool) -> None:
        """An alert handed to the advanced publisher (with or without a link)."""
        if link_up:
            return
        self.held.append(alert)
        if len(self.held) > self.cache_size:
            oldest = self.held.popleft()
            self.gone(
                oldest,
                f"pushed out of the publisher's cache (zenoh.alert_cache_size = "
                f"{self.cache_size}) while no link was up",
            )

    def link_up(self) -> int:
        """A link came up: the held alerts are on the bus for recovery; returns how many."""
        count = len(self.held)
        self.held.clear()
        return count

    def gone(self, alert: AlertId | None, why: str) -> None:
        """One alert that will never reach a subscriber."""
        self.lost_total += 1
        self.lost.append(f"{_name(alert)}: {why}")

    def stopped(self, why: str = "never delivered: no link when the daemon stopped") -> int:
        """At exit: every still held alert is gone; returns how many."""
        count = len(self.held)
        while self.held:
            self.gone(self.held.popleft(), why)
        return count

    def undelivered(self) -> list[str]:
        """The held alerts (waiting for a link) and the newest gone ones, each with its fate."""
        waiting = [f"{_name(alert)}: held, no link yet" for alert in self.held]
        return [*self.lost, *waiting[-NAMED_LOST:]]


def _name(alert: AlertId | None) -> str:
    return "an alert" if alert is None else alert.describe()
