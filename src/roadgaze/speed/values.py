"""The speed the monitor is given at a frame, and the one check of a speed value (pure).

Each frame the loop asks `VehicleSpeed.kmh_at(t_s)` for the speed at the frame's own time on the
source's timeline (seconds) and hands it to the monitor; None means unknown and is taken as
moving (fail-safe: no alert is suppressed). Three kinds answer it: the bus (`BusSpeed` around
the newest valid payload, whatever `t_s`), a recorded drive's `SpeedTrack`, and `ConstantSpeed`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from roadgaze.errors import SpeedError

MAX_KMH = 400.0
"""Fastest speed accepted anywhere (bus, track, option); anything above is a broken or hostile
sender."""

SpeedSource = Callable[[], float | None]
"""The vehicle speed in km/h for the monitor; None when unknown (taken as moving)."""


def checked_kmh(value: float, what: str) -> float:
    """`value` when it is a speed: finite and within 0-`MAX_KMH` km/h. Otherwise `SpeedError`
    naming `what` (e.g. `--speed-kmh`, `speed track F line 3: kmh`)."""
    if not (math.isfinite(value) and 0.0 <= value <= MAX_KMH):
        raise SpeedError(f"{what} {value:g} is not a speed within 0-{MAX_KMH:g} km/h")
    return float(value)


def no_speed() -> float | None:
    """The speed source of a run without one: always unknown, i.e. moving (fail-safe)."""
    return None


@runtime_checkable
class VehicleSpeed(Protocol):
    """The speed at a frame: `kmh_at(t_s)` in km/h (>= 0) or None when unknown."""

    def kmh_at(self, t_s: float) -> float | None: ...


@dataclass(frozen=True, slots=True)
class BusSpeed:
    """A zero-argument speed source (the bus's newest speed) as a `VehicleSpeed`: `t_s` unused."""

    source: SpeedSource

    def kmh_at(self, t_s: float) -> float | None:
        return self.source()


@dataclass(frozen=True, slots=True)
class ConstantSpeed:
    """One speed for the whole drive (km/h, within 0-400; `SpeedError` otherwise)."""

    kmh: float

    def __post_init__(self) -> None:
        checked_kmh(self.kmh, "a constant speed of")

    def kmh_at(self, t_s: float) -> float | None:
        return self.kmh


def vehicle_speed(speed: SpeedSource | VehicleSpeed) -> VehicleSpeed:
    """`speed` as a `VehicleSpeed`: as is when it has `kmh_at`, else a `BusSpeed` around it."""
    if isinstance(speed, VehicleSpeed):
        return speed
    return BusSpeed(speed)
