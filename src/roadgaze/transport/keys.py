"""The key expressions of one vehicle under the configured prefix (pure)."""

from __future__ import annotations

import re
from dataclasses import dataclass

from roadgaze.config import VEHICLE_ID_PATTERN, ZenohConfig
from roadgaze.errors import ConfigError

ALL_VEHICLES = "*"


@dataclass(frozen=True, slots=True)
class Keys:
    """The key expressions of one vehicle (or, for subscribers only, of all: vehicle id `*`)."""

    vehicle_id: str
    prefix: str
    yaw: str
    alert: str
    alive: str
    state: str
    speed: str | None
    support: str = ""
    """Forward and lane support, one message per frame."""

    @classmethod
    def from_config(cls, config: ZenohConfig, vehicle_id: str | None = None) -> Keys:
        """The keys a daemon publishes on. Raises `ConfigError` unless the vehicle id matches
        `[A-Za-z0-9_-]{1,64}` (a wildcard or an empty id would publish as other vehicles)."""
        vid = config.vehicle_id if vehicle_id is None else vehicle_id
        if not re.fullmatch(VEHICLE_ID_PATTERN, vid):
            shown = vid if len(vid) <= 40 else f"{vid[:40]}... ({len(vid)} characters)"
            raise ConfigError(
                f"vehicle id must be 1-64 letters, digits, '_' or '-', found {shown!r}"
            )
        return cls._build(config, vid)

    @classmethod
    def matching(cls, config: ZenohConfig, vehicle_id: str | None = None) -> Keys:
        """The keys a subscriber listens on: one vehicle, or every vehicle with None or `*`."""
        if vehicle_id is None or vehicle_id == ALL_VEHICLES:
            return cls._build(config, ALL_VEHICLES)
        return cls.from_config(config, vehicle_id)

    @classmethod
    def _build(cls, config: ZenohConfig, vehicle_id: str) -> Keys:
        # The templates were checked when the configuration was loaded (config.check_key_template).
        prefix = config.prefix.format(vehicle_id=vehicle_id).strip("/")
        speed = config.speed_key.format(vehicle_id=vehicle_id).strip("/") or None
        return cls(
            vehicle_id=vehicle_id,
            prefix=prefix,
            yaw=f"{prefix}/yaw",
            alert=f"{prefix}/alert",
            alive=f"{prefix}/alive",
            state=f"{prefix}/state",
            speed=speed,
            support=f"{prefix}/support",
        )

    @property
    def advanced(self) -> str:
        """The keys Zenoh's advanced publisher and subscriber use beside the data key (cache
        queries, heartbeats, publisher tokens): `**` never matches these `@adv` chunks."""
        return f"{self.prefix}/*/@adv/**"
