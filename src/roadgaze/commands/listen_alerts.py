"""What `roadgaze listen` tells about the alerts it did not print: gaps, foreign publishers, totals.

Pure bookkeeping (no Zenoh): the listener hands over each checked alert, each Zenoh sample-miss
report and each liveliness change, and prints the lines this returns on stderr.

- **Missed alerts.** A publisher's alerts are numbered from 0 (`seq`). A jump in `seq` is a gap
  (lost before this listener could recover them: more alerts in an outage than the daemon's
  cache holds); a publisher whose first alert here is not #0 had earlier ones this listener
  never got (raised before it joined and no longer cached, or lost in an outage). Each becomes
  one line with the missing range. Zenoh's sample-miss reports count the same losses; any not
  matched by a gap are printed with their count.
- **A second publisher.** A vehicle's alerts come from one publisher at a time: the daemon's
  advanced publisher (Zenoh source id). The first one seen since the vehicle's `alive` token
  appeared is the vehicle's; alerts from any other source (another Zenoh session, or a plain put
  without source information) are flagged as suspicious every time and not printed. A daemon
  that stops (`alive ... left`) and starts again is a new publisher and is accepted.
"""

from __future__ import annotations

from collections import Counter

from roadgaze.transport.checks import PLAIN_PUBLISHER


def seq_range(first: int, last: int) -> str:
    """`#3` or `#3-#5`."""
    return f"#{first}" if first == last else f"#{first}-#{last}"


class AlertBook:
    """Counts what a listener received, rejected, missed and refused as foreign."""

    def __init__(self) -> None:
        self.printed = 0
        self.rejected = 0
        self.foreign = 0
        self.missed = 0
        self.missed_ranges: list[str] = []
        self._publisher: dict[str, str] = {}
        """Vehicle id -> the source id of its current publisher."""
        self._zenoh_misses: Counter[str] = Counter()
        """Sample-miss counts per source not yet matched by a seq gap."""
        self._vehicle_of_source: dict[str, str] = {}

    def on_alive(self, vehicle: str, alive: bool) -> None:
        """A vehicle's liveliness token appeared or went: its next publisher starts afresh."""
        self._publisher.pop(vehicle, None)

    def on_zenoh_miss(self, source: str, count: int) -> None:
        self._zenoh_misses[source] += count

    def foreign_source(self, vehicle: str, source: str | None) -> str | None:
        """Why an alert of `vehicle` from `source` is not the vehicle's own, or None."""
        if source is None or source == PLAIN_PUBLISHER:
            return "a plain put without Zenoh source information (not the daemon's publisher)"
        current = self._publisher.setdefault(vehicle, source)
        if current == source:
            self._vehicle_of_source[source] = vehicle
            return None
        return f"a second publisher ({source}; the vehicle's is {current})"

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
        lines = []
        for source, count in self._zenoh_misses.items():
            if count > 0:
                vehicle = self._vehicle_of_source.get(source, "?")
                self.missed += count
                self.missed_ranges.append(f"{count} unnumbered of {vehicle}")
                lines.append(
                    f"MISSED {count} alerts of {vehicle} (zenoh sample-miss from {source}; no "
                    "later alert gave their numbers)"
                )
        self._zenoh_misses.clear()
        return lines

    def totals(self, dropped: int) -> str:
        """The closing line: every alert accounted for."""
        ranges = f" ({', '.join(self.missed_ranges[:10])})" if self.missed_ranges else ""
        return (
            f"totals: {self.printed} alerts printed, {self.missed} missed{ranges}, "
            f"{self.rejected} messages rejected, {self.foreign} foreign alerts (another "
            f"publisher), {dropped} dropped (printing too slow)"
        )
