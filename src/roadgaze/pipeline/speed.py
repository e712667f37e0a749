"""The vehicle speed the monitor gates alerts with: kept importable here; it lives in
`roadgaze.speed`."""

from roadgaze.speed import (
    BusSpeed,
    ConstantSpeed,
    SpeedSource,
    VehicleSpeed,
    no_speed,
    vehicle_speed,
)

__all__ = ["BusSpeed", "ConstantSpeed", "SpeedSource", "VehicleSpeed", "no_speed", "vehicle_speed"]
