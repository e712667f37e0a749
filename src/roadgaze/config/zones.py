"""Glance zones as configured (`[[monitor.zones]]`), their left-hand-drive defaults, the mirrored
right-hand-drive ones, and the check that no driving-related zone reaches ADDW's distraction
area 1. Pure (pydantic only); the classifier is `roadgaze.monitor.zones`."""

from __future__ import annotations

from typing import Protocol

from pydantic import Field, field_validator

from roadgaze.config.protocol import AREA1_ZONE_NAMES
from roadgaze.config.section import Section

__all__ = ["ZoneConfig", "ZoneSettings", "check_area1", "default_zones", "mirrored_zones"]


class ZoneConfig(Section):
    """One glance zone: a rectangle in yaw and pitch relative to the neutral pose, degrees."""

    name: str = Field(pattern=r"^[a-z][a-z0-9_]{0,31}$")
    yaw_deg: tuple[float, float]
    """[min, max], > 0 = the driver's own left."""
    pitch_deg: tuple[float, float]
    """[min, max], > 0 = up."""

    @field_validator("yaw_deg", "pitch_deg")
    @classmethod
    def _ordered(cls, value: tuple[float, float]) -> tuple[float, float]:
        if not value[0] <= value[1]:
            raise ValueError(f"needs [min, max] with min <= max, found {list(value)}")
        return value


def default_zones() -> list[ZoneConfig]:
    """Left-hand drive (sources: docs/monitor.md); `mirrored_zones` gives right-hand drive."""
    return [
        ZoneConfig(name="lap", yaw_deg=(-25.0, 25.0), pitch_deg=(-90.0, -18.0)),
        ZoneConfig(name="cluster", yaw_deg=(-15.0, 15.0), pitch_deg=(-18.0, -10.0)),
        ZoneConfig(name="centre_stack", yaw_deg=(-55.0, -15.0), pitch_deg=(-50.0, -5.0)),
        ZoneConfig(name="left_mirror", yaw_deg=(20.0, 50.0), pitch_deg=(-25.0, 10.0)),
        ZoneConfig(name="right_mirror", yaw_deg=(-55.0, -30.0), pitch_deg=(-25.0, 10.0)),
    ]


def mirrored_zones(zones: list[ZoneConfig]) -> list[ZoneConfig]:
    """The zones of the mirrored cabin: yaw [a, b] -> [-b, -a]; left and right names swap."""
    swap = {"left_mirror": "right_mirror", "right_mirror": "left_mirror"}
    return [
        ZoneConfig(
            name=swap.get(z.name, z.name),
            yaw_deg=(-z.yaw_deg[1], -z.yaw_deg[0]),
            pitch_deg=z.pitch_deg,
        )
        for z in zones
    ]


class ZoneSettings(Protocol):
    """What the zone checks read of `[monitor]` (`MonitorConfig`, which builds on this module)."""

    @property
    def zones(self) -> list[ZoneConfig]: ...
    @property
    def driving_related_zones(self) -> list[str]: ...
    @property
    def distraction_yaw_deg(self) -> float: ...
    @property
    def roof_pitch_deg(self) -> float: ...
    @property
    def road_pitch_deg(self) -> tuple[float, float]: ...
    @property
    def road_half_width_deg(self) -> float: ...
    def effective_zones(self) -> list[ZoneConfig]: ...


def check_area1(monitor: ZoneSettings) -> None:
    """Raise ValueError when a zone takes an area-1 name, a driving-related zone reaches into
    area 1, or the road does."""
    names = [zone.name for zone in monitor.zones]
    taken = sorted(set(AREA1_ZONE_NAMES) & set(names))
    if taken:
        raise ValueError(f"zone names {taken} are reserved for ADDW's distraction area 1")
    for zone in monitor.effective_zones():
        if zone.name in monitor.driving_related_zones and (
            max(abs(zone.yaw_deg[0]), abs(zone.yaw_deg[1])) > monitor.distraction_yaw_deg
            or zone.pitch_deg[1] > monitor.roof_pitch_deg
        ):
            raise ValueError(
                f"driving-related zone '{zone.name}' (yaw {list(zone.yaw_deg)}, pitch "
                f"{list(zone.pitch_deg)}) reaches into ADDW's distraction area 1 (beyond "
                f"+-distraction_yaw_deg {monitor.distraction_yaw_deg:g} or above roof_pitch_deg "
                f"{monitor.roof_pitch_deg:g}), which is always distraction"
            )
    if monitor.road_pitch_deg[1] >= monitor.roof_pitch_deg:
        raise ValueError(
            f"road_pitch_deg's top ({monitor.road_pitch_deg[1]:g}) must be below roof_pitch_deg "
            f"({monitor.roof_pitch_deg:g})"
        )
    if monitor.road_half_width_deg >= monitor.distraction_yaw_deg:
        raise ValueError(
            f"road_half_width_deg ({monitor.road_half_width_deg:g}) must be below "
            f"distraction_yaw_deg ({monitor.distraction_yaw_deg:g})"
        )
