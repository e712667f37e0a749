"""Where every alert went: delivered, waiting for a subscriber, or gone (pure: no Zenoh import).

An alert published while a subscriber of the alert key is matched (Zenoh's matching status) is
*delivered*: the publisher is reliable and blocks on congestion. Any other alert *waits* in the
advanced publisher's cache: published while no link was up, or while no subscriber was there
(a router without consumers, a consumer still connecting). It is delivered once a link is up
and a subscriber is matched, when that subscriber has had `grace_s` to fetch it (its history
query when it joins, its recovery after an outage) or leaves on its own after fetching what it
wanted (`roadgaze listen --count`). It is *gone* when it was pushed out of the cache first (more
than `zenoh.alert_cache_size` newer ones), when its put failed, when it was dropped before a
client session opened, or when the daemon stopped with it still waiting. `LinkState` says what
gone means on a bus whose subscribers have left (see there). `AlertLedger` keeps the waiting
ones and names the newest gone ones, so the state message, the final log line and the exit
status can say which alerts never reached anyone.
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


@dataclass(frozen=True, slots=True)
class Waiting:
    """One alert in the publisher's cache that no subscriber is known to have received."""

    alert: AlertId | None
    index: int
    """Its place among every alert published (the cache keeps the newest `cache_size`)."""
    put_s: float
    """When it was published (monotonic seconds)."""


class AlertLedger:
    """Waiting and gone alerts of one daemon; not thread-safe (`LinkState` holds the lock)."""

    def __init__(self, cache_size: int, grace_s: float) -> None:
        self.cache_size = cache_size
        self.grace_s = grace_s
        self.held: deque[Waiting] = deque()
        """Published and not known to be delivered, still in the cache, oldest first."""
        self.published_total = 0
        self.lost_total = 0
        self.lost: deque[str] = deque(maxlen=NAMED_LOST)
        """The newest gone alerts, each with why."""

    def published(
        self, alert: AlertId | None, delivered: bool, now_s: float, pushed_out_why: str | None
    ) -> None:
        """An alert handed to the advanced publisher: `delivered` when a subscriber was matched
        on a live link; otherwise it waits. An alert the new one pushes out of the cache while
        still waiting is gone (`pushed_out_why`), or with None no longer waits."""
        index = self.published_total
        self.published_total += 1
        if not delivered:
            self.held.append(Waiting(alert, index, now_s))
        while self.held and self.published_total - self.held[0].index > self.cache_size:
            oldest = self.held.popleft()
            if pushed_out_why is not None:
                self.gone(oldest.alert, pushed_out_why)

    def confirm(self, available_s: float | None, now_s: float) -> int:
        """Waiting alerts a subscriber has had `grace_s` to fetch are delivered; `available_s`
        is when a link was up with a subscriber matched (None: not now). Returns how many."""
        if available_s is None:
            return 0
        count = 0
        while self.held and max(self.held[0].put_s, available_s) + self.grace_s <= now_s:
            self.held.popleft()
            count += 1
        return count

    def fetched(self) -> int:
        """A subscriber that was there with a link up left: it had every waiting alert to fetch
        (all are delivered). Returns how many."""
        count = len(self.held)
        self.held.clear()
        return count

    def gone(self, alert: AlertId | None, why: str) -> None:
        """One alert that will never reach a subscriber."""
        self.lost_total += 1
        self.lost.append(f"{_name(alert)}: {why}")

    def stopped(self, why: str = "never delivered: no link when the daemon stopped") -> int:
        """At exit: every still waiting alert is gone; returns how many."""
        count = len(self.held)
        while self.held:
            self.gone(self.held.popleft().alert, why)
        return count

    def release(self) -> list[str]:
        """Every waiting alert stops waiting without being gone; returns their names."""
        names = [_name(entry.alert) for entry in self.held]
        self.held.clear()
        return names

    def undelivered(self, waiting_why: str = "held, no link yet") -> list[str]:
        """The waiting alerts (with `waiting_why`) and the newest gone ones, each with its fate."""
        waiting = [f"{_name(entry.alert)}: {waiting_why}" for entry in self.held]
        return [*self.lost, *waiting[-NAMED_LOST:]]


def _name(alert: AlertId | None) -> str:
    return "an alert" if alert is None else alert.describe()
