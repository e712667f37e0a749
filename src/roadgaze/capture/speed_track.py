"""The vehicle speed of a recorded drive: kept importable here; it lives in `roadgaze.speed`."""

from roadgaze.speed import (
    DEFAULT_HOLD_S,
    MAX_KMH,
    SPEED_TRACK_SUFFIXES,
    SpeedChoice,
    SpeedTrack,
    read_speed_track,
    recorded_speed,
    track_beside,
)

__all__ = [
    "DEFAULT_HOLD_S",
    "MAX_KMH",
    "SPEED_TRACK_SUFFIXES",
    "SpeedChoice",
    "SpeedTrack",
    "read_speed_track",
    "recorded_speed",
    "track_beside",
]
