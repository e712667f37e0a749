"""Glance zones: where the driver looks, from yaw and pitch relative to the neutral pose. Pure.

A zone map is an ordered list of rectangles in (yaw, pitch) degrees relative to the learned
neutral (road-ahead) pose, yaw > 0 = the driver's own left, pitch > 0 = up; the first is always
`road`. Rules:

1. Back to the road: a sample inside the road's rectangle is `road`, whatever the previous zone
   (returning to the road is never delayed by another zone's hysteresis).
2. Hysteresis: otherwise a sample stays in the previous zone while it lies inside that zone's
   rectangle grown by `hysteresis_deg` on every side (`away` is not sticky).
3. Otherwise the rectangles are tested in order, first match wins (edges included).
4. Nothing matched: `away`.

The rectangles are the limits for *entering* a zone: with the defaults the road is entered within
+-20 deg yaw and left beyond +-25 deg (`road_half_width_deg` 25, `hysteresis_deg` 5). The
classifier is a pure function of the two angles, so any source of angles (head pose today, eye
gaze later) can be fed into it. Defaults (a left-hand-drive car, camera roughly in front of the
driver) and their sources: docs/monitor.md.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

__all__ = [
    "AWAY",
    "DEFAULT_DRIVING_RELATED",
    "DEFAULT_ZONES",
    "ROAD",
    "Zone",
    "ZoneMap",
    "classify_zone",
]

ROAD = "road"
AWAY = "away"
DEFAULT_DRIVING_RELATED = ("left_mirror", "right_mirror")
"""Zones whose glances belong to the driving task: off road (for VATS and `eyes_on_road`), but
they do not run the long-distraction timer (docs/monitor.md)."""


@dataclass(frozen=True, slots=True)
class Zone:
    """One rectangle: yaw_min <= yaw <= yaw_max and pitch_min <= pitch <= pitch_max (degrees,
    relative to the neutral pose)."""

    name: str
    yaw_min_deg: float
    yaw_max_deg: float
    pitch_min_deg: float
    pitch_max_deg: float

    def contains(self, yaw_deg: float, pitch_deg: float, grow_deg: float = 0.0) -> bool:
        """Whether the point lies inside the rectangle grown by `grow_deg` on every side."""
        return (
            self.yaw_min_deg - grow_deg <= yaw_deg <= self.yaw_max_deg + grow_deg
            and self.pitch_min_deg - grow_deg <= pitch_deg <= self.pitch_max_deg + grow_deg
        )


DEFAULT_ZONES: tuple[Zone, ...] = (
    Zone(ROAD, -20.0, 20.0, -10.0, 15.0),
    Zone("lap", -25.0, 25.0, -90.0, -18.0),
    Zone("cluster", -15.0, 15.0, -18.0, -10.0),
    Zone("centre_stack", -55.0, -15.0, -50.0, -5.0),
    Zone("left_mirror", 20.0, 75.0, -25.0, 15.0),
    Zone("right_mirror", -85.0, -40.0, -25.0, 15.0),
)
"""In priority order; each number's source is in docs/monitor.md."""
DEFAULT_HYSTERESIS_DEG = 5.0


def classify_zone(
    yaw_deg: float,
    pitch_deg: float,
    previous_zone: str | None,
    zones: Iterable[Zone] = DEFAULT_ZONES,
    hysteresis_deg: float = DEFAULT_HYSTERESIS_DEG,
) -> str:
    """The zone of one sample (angles relative to the neutral pose, degrees).

    The first of `zones` is the road. `previous_zone` (None for a still or a first sample) keeps
    the sample in that zone within `hysteresis_deg` of its edges, unless the sample is inside the
    road's rectangle. Returns `AWAY` when no rectangle contains the sample.
    """
    ordered = tuple(zones)
    if ordered and ordered[0].name != previous_zone and ordered[0].contains(yaw_deg, pitch_deg):
        return ordered[0].name
    for zone in ordered:
        if zone.name == previous_zone and zone.contains(yaw_deg, pitch_deg, hysteresis_deg):
            return zone.name
    for zone in ordered:
        if zone.contains(yaw_deg, pitch_deg):
            return zone.name
    return AWAY


@dataclass(frozen=True, slots=True)
class ZoneMap:
    """The configured zones (road first), their hysteresis and which are driving-related."""

    zones: tuple[Zone, ...] = DEFAULT_ZONES
    hysteresis_deg: float = DEFAULT_HYSTERESIS_DEG
    driving_related: frozenset[str] = frozenset(DEFAULT_DRIVING_RELATED)

    def __post_init__(self) -> None:
        names = [zone.name for zone in self.zones]
        if not names or names[0] != ROAD:
            raise ValueError(f"the first zone must be '{ROAD}', found {names[:1]}")
        if AWAY in names or len(set(names)) != len(names):
            raise ValueError(f"zone names must be unique and not '{AWAY}', found {names}")
        unknown = sorted(self.driving_related - set(names))
        if ROAD in self.driving_related or unknown:
            raise ValueError(
                f"driving-related zones must be configured zones other than '{ROAD}', "
                f"found {sorted(self.driving_related)}"
            )

    @property
    def names(self) -> tuple[str, ...]:
        """Every zone a sample can be given: the configured ones, then `away`."""
        return (*(zone.name for zone in self.zones), AWAY)

    def classify(self, yaw_deg: float, pitch_deg: float, previous_zone: str | None) -> str:
        """`classify_zone` with this map's zones and hysteresis."""
        return classify_zone(yaw_deg, pitch_deg, previous_zone, self.zones, self.hysteresis_deg)

    def is_driving_related(self, zone: str | None) -> bool:
        return zone is not None and zone in self.driving_related
