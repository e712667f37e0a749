"""The key expressions of one vehicle under the configured prefix (pure)."""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.config import ZenohConfig
from roadgaze.errors import TransportError


@dataclass(frozen=True, slots=True)
class Keys:
    """The key expressions of one vehicle (or of all, with vehicle id `*`)."""

    vehicle_id: str
    prefix: str
    yaw: str
    alert: str
    alive: str
    state: str
    speed: str | None

    @classmethod
    def from_config(cls, config: ZenohConfig, vehicle_id: str | None = None) -> Keys:
        vid = config.vehicle_id if vehicle_id is None else vehicle_id
        try:
            prefix = config.prefix.format(vehicle_id=vid).strip("/")
            speed = config.speed_key.format(vehicle_id=vid).strip("/") or None
        except (KeyError, IndexError, ValueError) as exc:
            raise TransportError(
                f"zenoh.prefix/speed_key may only use the placeholder {{vehicle_id}}: {exc}"
            ) from None
        if not prefix:
            raise TransportError("zenoh.prefix is empty; use e.g. 'vehicle/{vehicle_id}/dms'")
        return cls(
            vehicle_id=vid,
            prefix=prefix,
            yaw=f"{prefix}/yaw",
            alert=f"{prefix}/alert",
            alive=f"{prefix}/alive",
            state=f"{prefix}/state",
            speed=speed,
        )
