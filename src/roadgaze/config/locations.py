"""A cabin's own gaze locations (`[[monitor.locations]]`): where Euro NCAP's sheet locations lie
in this car when they differ from roadgaze's estimates (`roadgaze.cabin.LOCATIONS`). Pure
(pydantic only)."""

from __future__ import annotations

from pydantic import field_validator

from roadgaze.cabin import LOCATION_NAMES
from roadgaze.config.section import Section

__all__ = ["LocationConfig"]


class LocationConfig(Section):
    """One location's point in the driver's frame of this cabin (metres from the driver's eyes:
    forward, left, up; as the cabin is, not mirrored)."""

    name: str
    point_m: tuple[float, float, float]

    @field_validator("name")
    @classmethod
    def _known(cls, value: str) -> str:
        if value not in LOCATION_NAMES:
            raise ValueError(
                f"unknown gaze location {value!r}; expected one of {', '.join(LOCATION_NAMES)}"
            )
        return value
