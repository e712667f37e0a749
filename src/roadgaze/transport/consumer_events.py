"""What an `AlertConsumer` tells its user, one frozen record per event (pure: no Zenoh import).

Every message that arrived is one of these, checked: an alert (`AlertReceived`, flagged when
its vehicle has more than one publisher or when it arrives late), a state, yaw or VSS value, a
vehicle's daemon appearing or going (`PublisherJoined`, `PublisherGone`), or why something was
not handed on (`AlertsMissed`, `DuplicateAlert`, `AlertRefused`, `MessageRejected`). The link
itself is `LinkUp` and `LinkLost`. `describe()` gives the line `roadgaze listen` prints.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from roadgaze.transport.alert_book import seq_range

SECURITY_DOC = "see docs/security.md"


@dataclass(frozen=True, slots=True)
class LinkUp:
    """A transport to a router, peer or daemon opened."""

    remote: str
    whatami: str


@dataclass(frozen=True, slots=True)
class LinkLost:
    """A transport closed (the router stopped, a cable was pulled); Zenoh retries by itself."""

    remote: str
    whatami: str


@dataclass(frozen=True, slots=True)
class PublisherJoined:
    """A vehicle's daemon appeared (its liveliness token)."""

    vehicle_id: str
    key: str


@dataclass(frozen=True, slots=True)
class PublisherGone:
    """A vehicle's daemon went (its token's DELETE); comes after its final state, if one came."""

    vehicle_id: str
    key: str


@dataclass(frozen=True, slots=True)
class AlertReceived:
    """A checked alert. `publishers` are the vehicle's alert publishers since its daemon
    appeared, first first; more than one means another process publishes this vehicle's alerts
    (on an open bus either may be the forger: both are handed on, flagged)."""

    vehicle_id: str
    key: str
    alert: dict[str, Any]
    source: str
    publishers: tuple[str, ...]
    late: bool = False
    """Its number was missing before: it arrives after later ones (counted missed then)."""

    @property
    def seq(self) -> int:
        return int(self.alert["seq"])

    @property
    def second_publisher(self) -> bool:
        """From a publisher other than the vehicle's first."""
        return bool(self.publishers) and self.source != self.publishers[0]

    def describe_second(self) -> str | None:
        """The warning for an alert of a second publisher (handed on, flagged), or None."""
        if not self.second_publisher:
            return None
        alert = self.alert
        return (
            f"SUSPICIOUS alert #{alert['seq']} {alert['kind']} {alert['level']} of "
            f"{self.vehicle_id} from a second publisher ({self.source}; the vehicle's first is "
            f"{self.publishers[0]}): printed, flagged (another process publishes this vehicle's "
            f"alerts, either may be the forger; {SECURITY_DOC})"
        )

    @property
    def suspicious(self) -> str | None:
        """Why this alert cannot be trusted to be the vehicle's daemon's, or None."""
        if len(self.publishers) < 2:
            return None
        return (
            f"publisher {self.publishers.index(self.source) + 1} of {len(self.publishers)} of "
            f"{self.vehicle_id} ({self.source}): another process publishes this vehicle's alerts"
        )


@dataclass(frozen=True, slots=True)
class MessageReceived:
    """A checked state or yaw message."""

    kind: str
    vehicle_id: str
    key: str
    payload: dict[str, Any]


@dataclass(frozen=True, slots=True)
class VssReceived:
    """A checked COVESA VSS value (text) on its key."""

    key: str
    value: str


@dataclass(frozen=True, slots=True)
class AlertsMissed:
    """Alerts a publisher numbered that never arrived; `last_seq` None: Zenoh counted them but
    no later alert gave their numbers."""

    vehicle_id: str
    count: int
    line: str
    first_seq: int | None = None
    last_seq: int | None = None

    def describe(self) -> str:
        return self.line

    @property
    def span(self) -> str:
        if self.first_seq is None or self.last_seq is None:
            return f"{self.count} unnumbered"
        return seq_range(self.first_seq, self.last_seq)


@dataclass(frozen=True, slots=True)
class SecondPublisher:
    """A vehicle's alerts now come from more than one publisher (`publishers`, first first)."""

    vehicle_id: str
    source: str
    publishers: tuple[str, ...]

    def describe(self) -> str:
        return (
            f"SUSPICIOUS: {len(self.publishers)} publishers of {self.vehicle_id}'s alerts "
            f"({', '.join(self.publishers)}): one is not its daemon; every alert of both is "
            f"printed, flagged with its publisher ({SECURITY_DOC})"
        )


@dataclass(frozen=True, slots=True)
class AlertRefused:
    """An alert that cannot be the daemon's and is not handed on: a plain put (the daemon
    publishes only through its advanced publisher, with source information)."""

    vehicle_id: str
    key: str
    alert: dict[str, Any]
    why: str

    def describe(self) -> str:
        alert = self.alert
        return (
            f"SUSPICIOUS alert #{alert['seq']} {alert['kind']} {alert['level']} of "
            f"{self.vehicle_id} from {self.why}: not printed (another process publishes this "
            f"vehicle's alerts; {SECURITY_DOC})"
        )


@dataclass(frozen=True, slots=True)
class DuplicateAlert:
    """An alert whose number its publisher already used: not handed on again."""

    vehicle_id: str
    key: str
    seq: int
    expected: int


@dataclass(frozen=True, slots=True)
class MessageRejected:
    """A message that failed its checks (size, JSON, schema, vehicle id): not handed on."""

    kind: str
    key: str
    reason: str


ConsumerEvent = (
    LinkUp
    | LinkLost
    | PublisherJoined
    | PublisherGone
    | AlertReceived
    | MessageReceived
    | VssReceived
    | AlertsMissed
    | SecondPublisher
    | AlertRefused
    | DuplicateAlert
    | MessageRejected
)
