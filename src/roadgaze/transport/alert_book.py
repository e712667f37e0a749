"""What a consumer knows about the alerts it received: gaps, publishers, totals (pure: no Zenoh).

The consumer hands over each checked alert, each Zenoh sample-miss report and each liveliness
change; the book says what to tell about it.

- **Missed alerts.** A publisher's alerts are numbered from 0 (`seq`). A jump in `seq` is a gap
  (lost before the consumer could recover them: more alerts in an outage than the daemon's
  cache holds); a publisher whose first alert here is not #0 had earlier ones the consumer
  never got (raised before it joined and no longer cached, or lost in an outage). Each becomes
  one line with the missing range. Zenoh's sample-miss reports count the same losses; any not
  matched by a gap are reported with their count.
- **Publishers.** A vehicle's alerts should come from one publisher: the daemon's advanced
  publisher (a Zenoh source id). The first one seen since the vehicle's `alive` token changed is
  its *first* publisher; any other advanced publisher is a *second* one. On an open bus either
  may be the forger (a forger that speaks first is the first), so a consumer shows the alerts of
  both, flagged, and never hides one. A plain put (no source information) is never the daemon's
  (it always publishes through its advanced publisher): it is refused. A daemon that stops
  (`alive ... left`) and starts again is a new first publisher.
"""

from __future__ import annotations

from collections import Counter

from roadgaze.transport.checks import PLAIN_PUBLISHER

MAX_PUBLISHERS = 16
"""Publishers remembered per vehicle (the oldest second publishers are forgotten beyond it)."""


def seq_range(first: int, last: int) -> str:
    """`#3` or `#3-#5`."""
    return f"#{first}" if first == last else f"#{first}-#{last}"


class AlertBook:
    """Counts what a consumer received, rejected, missed, refused and flagged."""

    def __init__(self) -> None:
        self.printed = 0
        """Alerts of their vehicle's first publisher, handed on."""
        self.rejected = 0
        self.foreign = 0
        """Alerts of another source: `flagged` (a second publisher, handed on) + refused."""
        self.flagged = 0
        """Of the foreign ones, those of a second advanced publisher (handed on, flagged)."""
        self.missed = 0
        self.missed_ranges: list[str] = []
        self._publishers: dict[str, list[str]] = {}
        """Vehicle id -> the source ids of its publishers since its token changed, first first."""
        self._zenoh_misses: Counter[str] = Counter()
        """Sample-miss counts per source not yet matched by a seq gap."""
        self._vehicle_of_source: dict[str, str] = {}

    def on_alive(self, vehicle: str, alive: bool) -> None:
        """A vehicle's liveliness token appeared or went: its next publisher starts afresh."""
        self._publishers.pop(vehicle, None)

    def on_zenoh_miss(self, source: str, count: int) -> None:
        self._zenoh_misses[source] += count

    def publishers(self, vehicle: str) -> tuple[str, ...]:
        """The sources that published `vehicle`'s alerts since its token changed, first first."""
        return tuple(self._publishers.get(vehicle, ()))

    def foreign_source(self, vehicle: str, source: str | None) -> str | None:
        """Why an alert of `vehicle` from `source` is not from its first publisher, or None.
        Registers `source` as one of the vehicle's publishers."""
        if source is None or source == PLAIN_PUBLISHER:
            return "a plain put without Zenoh source information (not the daemon's publisher)"
        known = self._publishers.setdefault(vehicle, [])
        if not known:
            known.append(source)
        if known[0] == source:
            self._vehicle_of_source[source] = vehicle
            return None
        if source not in known:
            if len(known) >= MAX_PUBLISHERS:
                known.pop(1)
            known.append(source)
        return f"a second publisher ({source}; the vehicle's first is {known[0]})"

    def gap(self, vehicle: str, source: str, seq: int, missing: int, first: bool) -> str | None:
        """The line for alerts missing just before #`seq` of `source`, or None."""
        if first and seq > 0:
            missing = seq
        if missing <= 0:
            return None
        matched = min(missing, self._zenoh_misses[source])
        self._zenoh_misses[source] -= matched
        span = seq_range(seq - missing, seq - 1)
        self.missed += missing
        self.missed_ranges.append(f"{span} of {vehicle}")
        why = (
            "raised before this listener joined and no longer in the daemon's cache, or lost "
            "while a link was down"
            if first
            else "lost while a link was down: more alerts than the daemon's cache holds "
            "(zenoh.alert_cache_size)"
        )
        confirmed = f"; zenoh reported {matched} missed" if matched else ""
        return f"MISSED alerts {span} of {vehicle} ({missing}): {why}{confirmed}"

    def unmatched_misses(self) -> list[str]:
        """Zenoh sample-miss counts no gap explained (no later alert gave their numbers)."""
        return [line for _, _, line in self.unmatched()]

    def unmatched(self) -> list[tuple[str, int, str]]:
        """(vehicle, count, line) of each source whose sample-miss count no gap explained; each
        is counted missed once."""
        found = []
        for source, count in self._zenoh_misses.items():
            if count > 0:
                vehicle = self._vehicle_of_source.get(source, "?")
                self.missed += count
                self.missed_ranges.append(f"{count} unnumbered of {vehicle}")
                line = (
                    f"MISSED {count} alerts of {vehicle} (zenoh sample-miss from {source}; no "
                    "later alert gave their numbers)"
                )
                found.append((vehicle, count, line))
        self._zenoh_misses.clear()
        return found

    def totals(self, dropped: int) -> str:
        """The closing line: every alert accounted for."""
        ranges = f" ({', '.join(self.missed_ranges[:10])})" if self.missed_ranges else ""
        foreign = "another publisher"
        if self.foreign:
            foreign += (
                f": {self.flagged} of a second publisher, printed flagged; "
                f"{self.foreign - self.flagged} plain puts, not printed"
            )
        return (
            f"totals: {self.printed} alerts printed, {self.missed} missed{ranges}, "
            f"{self.rejected} messages rejected, {self.foreign} foreign alerts ({foreign}), "
            f"{dropped} dropped (printing too slow)"
        )
