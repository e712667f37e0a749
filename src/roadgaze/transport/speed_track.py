"""`roadgaze speed`'s track and publisher: kept importable here; the track lives in
`roadgaze.speed`, the speed message and its publisher in `roadgaze.transport.speed`."""

from roadgaze.speed import SpeedTrack, read_speed_track
from roadgaze.transport.speed import SPEED_RATE_HZ, publish_track, speed_payload

__all__ = ["SPEED_RATE_HZ", "SpeedTrack", "publish_track", "read_speed_track", "speed_payload"]
