"""The `[zenoh]` configuration section: session, endpoints, key templates and bus limits (pure).

Part of `Config` (`roadgaze.config.settings`); its names are re-exported by `roadgaze.config`.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Literal, Self

from pydantic import Field, ValidationInfo, field_validator, model_validator

from roadgaze.config.section import Section

VEHICLE_ID_PATTERN = r"^[A-Za-z0-9_-]{1,64}$"
"""Vehicle ids: letters, digits, '_' and '-', at most 64 (no wildcard, no '/', no empty id)."""
KEY_MAX_CHARS = 1024
"""Longest key expression roadgaze accepts (Zenoh panics on keys over about 64 KiB)."""
_KEY_CHUNK = re.compile(r"[A-Za-z0-9_.~+=%,:;!'()\[\]-]+")


class ZenohConfig(Section):
    """Zenoh session and key expressions. Safe defaults: loopback only, no multicast scouting."""

    mode: Literal["peer", "client"] = "peer"
    """The daemon's session: `peer` opens at once, with or without a router; `client` needs its
    router to open (alerts raised before that are held by roadgaze, see docs/zenoh.md)."""
    connect: list[str] = Field(default_factory=list)
    listen: list[str] = Field(default_factory=list)
    rendezvous: str = "tcp/127.0.0.1:7447"
    """Where `run` and `listen` meet when `connect` and `listen` are both empty: the daemon
    connects here when something already listens (a router or another daemon) and listens here
    itself otherwise; `listen` connects here. '' for none."""
    multicast_scouting: bool = False
    config_file: Path | None = None
    """A Zenoh JSON5 config file; when set it is the base and the fields above override it."""
    vehicle_id: str = Field(default="car-0", pattern=VEHICLE_ID_PATTERN)
    prefix: str = "vehicle/{vehicle_id}/dms"
    speed_key: str = "vehicle/{vehicle_id}/speed"
    """Key expression of the speed input; '' for none. Without a (fresh) speed: taken as moving."""
    vss: bool = False
    """Also publish the COVESA VSS driver signals (docs/zenoh.md), as `--vss` does."""
    vss_prefix: str = Field(default="", pattern=r"^[^*$?#\s{}]*$")
    """Key prefix of the VSS signals; '' publishes the bare VSS paths (one vehicle per network,
    as Eclipse Kuksa assumes), e.g. 'car-0' gives car-0/Vehicle/Driver/IsEyesOnRoad."""
    speed_timeout_s: float = Field(default=2.0, gt=0)
    """No valid speed for this long (monotonic time) means unknown, taken as moving. The old
    name `speed_stale_s` is still accepted."""
    alert_cache_size: int = Field(default=100, ge=1, le=10_000)
    """Alerts the daemon keeps for late and recovering subscribers (Zenoh advanced publisher)."""
    reconnect_initial_s: float = Field(default=0.25, gt=0)
    """First delay before retrying a `connect` endpoint or re-opening a client session."""
    reconnect_max_s: float = Field(default=1.0, gt=0)
    delivery_wait_s: float = Field(default=5.0, ge=0, le=600)
    """At the end of a source or a stop, with alerts not yet delivered (no link since they were
    raised): how long to wait for a link before they are counted lost (docs/zenoh.md)."""

    @model_validator(mode="before")
    @classmethod
    def _old_speed_timeout_name(cls, data: Any) -> Any:
        if isinstance(data, dict) and "speed_stale_s" in data:
            data = dict(data)
            if "speed_timeout_s" in data:
                raise ValueError("set speed_timeout_s only (speed_stale_s is its old name)")
            data["speed_timeout_s"] = data.pop("speed_stale_s")
        return data

    @field_validator("prefix", "speed_key")
    @classmethod
    def _key_template(cls, template: str, info: ValidationInfo) -> str:
        if template == "" and info.field_name == "speed_key":
            return template
        check_key_template(template)
        return template

    @model_validator(mode="after")
    def _backoff_order(self) -> Self:
        if self.reconnect_initial_s > self.reconnect_max_s:
            raise ValueError(
                f"reconnect_initial_s ({self.reconnect_initial_s:g}) must not exceed "
                f"reconnect_max_s ({self.reconnect_max_s:g})"
            )
        return self


def check_key_template(template: str) -> None:
    """Raise ValueError unless `template` makes a plain key expression for every vehicle id.

    Only the placeholder `{vehicle_id}` is allowed; chunks (between '/') must be non-empty and
    free of wildcards (`*`, `$`), `?`, `#` and a leading `@`; the longest key stays under
    `KEY_MAX_CHARS`.
    """
    try:
        key = template.format(vehicle_id="x" * 64)
    except (KeyError, IndexError, ValueError) as exc:
        raise ValueError(f"only the placeholder {{vehicle_id}} is allowed ({exc})") from None
    if len(key) > KEY_MAX_CHARS:
        raise ValueError(f"key expression longer than {KEY_MAX_CHARS} characters")
    chunks = key.split("/")
    bad = [chunk for chunk in chunks if not _KEY_CHUNK.fullmatch(chunk)]
    if bad:
        raise ValueError(
            f"each part between '/' must be non-empty, without wildcards, '?', '#' or '@'; "
            f"found {bad[0][:40]!r}"
        )
