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

Before all of these, ADDW's distraction area 1 (EU 2023/2590 Annex I): a sample beyond
+-`distraction_yaw_deg` (55) of yaw is `far_left` / `far_right`, one above `roof_pitch_deg` is
`roof`, whatever the previous zone or the configured rectangles; they are never driving-related
(the configuration refuses it).

The rectangles are the limits for *entering* a zone: with the defaults the road is entered within
+-20 deg yaw and left beyond +-25 deg (`road_half_width_deg` 25, `hysteresis_deg` 5). The
classifier is a pure function of the two angles, so any source of angles (head pose today, eye
gaze later) can be fed into it. Defaults (a left-hand-drive car, camera roughly in front of the
driver) and their sources: docs/monitor.md.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from roadgaze.config import MonitorConfig
from roadgaze.config.protocol import AREA1_ZONE_NAMES

__all__ = [
    "AREA1_ZONES",
    "AWAY",
    "DEFAULT_DRIVING_RELATED",
    "DEFAULT_ZONES",
    "LEAN",
    "ROAD",
    "Zone",
    "ZoneMap",
    "classify_zone",
]

ROAD = "road"
AWAY = "away"
LEAN = "body_lean"
"""A head leaning out of the driving place (roadgaze.monitor.lean): off road, not a rectangle."""
FAR_LEFT, FAR_RIGHT, ROOF = AREA1_ZONE_NAMES
AREA1_ZONES = AREA1_ZONE_NAMES
"""ADDW's distraction area 1: beyond the +-55 deg planes (the driver's left, right) and the roof."""
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
    Zone("left_mirror", 20.0, 50.0, -25.0, 10.0),
    Zone("right_mirror", -55.0, -30.0, -25.0, 10.0),
)
"""In priority order; each number's source is in docs/monitor.md."""
DEFAULT_HYSTERESIS_DEG = 5.0
DEFAULT_DISTRACTION_YAW_DEG = 55.0
DEFAULT_ROOF_PITCH_DEG = 20.0


def area1_zone(
    yaw_deg: float, pitch_deg: float, yaw_limit_deg: float, roof_deg: float
) -> str | None:
    """ADDW's distraction area 1 for these angles (relative to the neutral), or None."""
    if yaw_deg > yaw_limit_deg:
        return FAR_LEFT
    if yaw_deg < -yaw_limit_deg:
        return FAR_RIGHT
    if pitch_deg > roof_deg:
        return ROOF
    return None


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
    distraction_yaw_deg: float = DEFAULT_DISTRACTION_YAW_DEG
    """ADDW area 1: beyond +-this yaw is always `far_left` / `far_right`."""
    roof_pitch_deg: float = DEFAULT_ROOF_PITCH_DEG
    """ADDW area 1: above this pitch is always `roof`."""

    @classmethod
    def from_config(cls, config: MonitorConfig) -> ZoneMap:
        """The zones of `[monitor]` as the monitor classifies with them, the road first."""
        road_yaw = config.road_half_width_deg - config.hysteresis_deg
        road = Zone(ROAD, -road_yaw, road_yaw, *config.road_pitch_deg)
        others = tuple(Zone(z.name, *z.yaw_deg, *z.pitch_deg) for z in config.effective_zones())
        return cls(
            zones=(road, *others),
            hysteresis_deg=config.hysteresis_deg,
            driving_related=frozenset(config.driving_related_zones),
            distraction_yaw_deg=config.distraction_yaw_deg,
            roof_pitch_deg=config.roof_pitch_deg,
        )

    def __post_init__(self) -> None:
        names = [zone.name for zone in self.zones]
        if set(AREA1_ZONES) & set(names):
            raise ValueError(f"zone names {list(AREA1_ZONES)} are reserved, found {names}")
        if not names or names[0] != ROAD:
            raise ValueError(f"the first zone must be '{ROAD}', found {names[:1]}")
        if AWAY in names or LEAN in names or len(set(names)) != len(names):
            raise ValueError(
                f"zone names must be unique and not '{AWAY}' or '{LEAN}', found {names}"
            )
        unknown = sorted(self.driving_related - set(names))
        if ROAD in self.driving_related or unknown:
            raise ValueError(
                f"driving-related zones must be configured zones other than '{ROAD}', "
                f"found {sorted(self.driving_related)}"
            )

    @property
    def road(self) -> Zone:
        """The road's rectangle (the first zone): its entry bound, before any hysteresis."""
        return self.zones[0]

    @property
    def names(self) -> tuple[str, ...]:
        """Every zone a sample can be given: the configured ones, then area 1's, then `away`."""
        return (*(zone.name for zone in self.zones), *AREA1_ZONES, LEAN, AWAY)

    def classify(self, yaw_deg: float, pitch_deg: float, previous_zone: str | None) -> str:
        """ADDW's area 1 first, else `classify_zone` with this map's zones and hysteresis."""
        area = area1_zone(yaw_deg, pitch_deg, self.distraction_yaw_deg, self.roof_pitch_deg)
        if area is not None:
            return area
        return classify_zone(yaw_deg, pitch_deg, previous_zone, self.zones, self.hysteresis_deg)

    def is_driving_related(self, zone: str | None) -> bool:
        return zone is not None and zone in self.driving_related
