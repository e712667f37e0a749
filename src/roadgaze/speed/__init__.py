"""Vehicle speed: one range check, one speed-track reader, one rule between samples (pure)."""

from roadgaze.speed.reader import (
    DEFAULT_MAX_ROWS,
    MAX_LINE_CHARS,
    SPEED_TRACK_SUFFIXES,
    SpeedChoice,
    read_speed_track,
    recorded_speed,
    track_beside,
)
from roadgaze.speed.track import DEFAULT_HOLD_S, SpeedTrack
from roadgaze.speed.values import (
    MAX_KMH,
    BusSpeed,
    ConstantSpeed,
    SpeedSource,
    VehicleSpeed,
    checked_kmh,
    no_speed,
    vehicle_speed,
)

__all__ = [
    "DEFAULT_HOLD_S",
    "DEFAULT_MAX_ROWS",
    "MAX_KMH",
    "MAX_LINE_CHARS",
    "SPEED_TRACK_SUFFIXES",
    "BusSpeed",
    "ConstantSpeed",
    "SpeedChoice",
    "SpeedSource",
    "SpeedTrack",
    "VehicleSpeed",
    "checked_kmh",
    "no_speed",
    "read_speed_track",
    "recorded_speed",
    "track_beside",
    "vehicle_speed",
]
