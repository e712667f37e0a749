"""The vehicle speed the monitor gates alerts with, behind one small Protocol (pure).

Each frame the loop asks `VehicleSpeed.kmh_at(t_s)` for the speed at the frame's own time on the
source's timeline (seconds) and hands it to the monitor; None means unknown and is taken as
moving (fail-safe: no alert is suppressed). Three kinds answer it:

- the bus (`roadgaze run`, `replay --publish`): the newest valid payload, whatever `t_s`; a plain
  zero-argument speed function (`SpeedSource`, e.g. `SpeedInput.kmh`) is wrapped by `BusSpeed`;
- a recorded drive's speed track (`roadgaze.capture.speed_track.SpeedTrack`), looked up at `t_s`;
- a constant (`ConstantSpeed`, `--speed-kmh`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

SpeedSource = Callable[[], float | None]
"""The vehicle speed in km/h for the monitor; None when unknown (taken as moving)."""


def no_speed() -> float | None:
    """The speed source of a replay without a bus: always unknown, i.e. moving (fail-safe)."""
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
    """One speed for the whole drive (km/h, finite, >= 0; ValueError otherwise)."""

    kmh: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.kmh) and self.kmh >= 0.0):
            raise ValueError(f"a constant speed must be finite and >= 0 km/h, found {self.kmh}")

    def kmh_at(self, t_s: float) -> float | None:
        return self.kmh


def vehicle_speed(speed: SpeedSource | VehicleSpeed) -> VehicleSpeed:
    """`speed` as a `VehicleSpeed`: as is when it has `kmh_at`, else a `BusSpeed` around it."""
    if isinstance(speed, VehicleSpeed):
        return speed
    return BusSpeed(speed)
