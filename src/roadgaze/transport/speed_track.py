"""A speed to put on the bus without a CAN bus: a constant or a recorded track (pure).

`roadgaze speed` publishes what `SpeedTrack.kmh_at` gives every 1/rate seconds on the speed key,
for bench tests in a car or on a desk. A track is a CSV with the columns `t_s` (seconds from its
start, non-decreasing) and `kmh` (0-400); between two rows the speed is interpolated linearly,
and a track of one row is a constant.
"""

from __future__ import annotations

import bisect
import csv
import json
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from roadgaze.errors import ConfigError
from roadgaze.transport.speed import SPEED_MAX_KMH

SPEED_RATE_HZ = 10.0
"""How often `roadgaze speed` publishes: well inside the daemon's 2 s `zenoh.speed_timeout_s`."""


@dataclass(frozen=True, slots=True)
class SpeedTrack:
    """Speeds in km/h at times in seconds from the track's start (at least one point)."""

    t_s: tuple[float, ...]
    kmh: tuple[float, ...]

    @classmethod
    def constant(cls, kmh: float) -> SpeedTrack:
        """The same speed for ever; ConfigError outside 0-400 km/h."""
        _check_kmh(kmh, "--kmh")
        return cls((0.0,), (float(kmh),))

    @property
    def duration_s(self) -> float:
        return self.t_s[-1]

    def kmh_at(self, t_s: float) -> float:
        """The speed at `t_s` (clamped to the track's ends), linear between rows."""
        if t_s <= self.t_s[0]:
            return self.kmh[0]
        if t_s >= self.t_s[-1]:
            return self.kmh[-1]
        right = bisect.bisect_right(self.t_s, t_s)
        t0, t1 = self.t_s[right - 1], self.t_s[right]
        v0, v1 = self.kmh[right - 1], self.kmh[right]
        return v0 if t1 == t0 else v0 + (v1 - v0) * (t_s - t0) / (t1 - t0)


def _check_kmh(value: float, where: str) -> None:
    if not (math.isfinite(value) and 0.0 <= value <= SPEED_MAX_KMH):
        raise ConfigError(f"{where}: speed must be within 0-{SPEED_MAX_KMH:g} km/h, found {value}")


def read_speed_track(path: Path) -> SpeedTrack:
    """A track from a CSV with columns t_s,kmh; ConfigError naming the file and line otherwise."""
    times: list[float] = []
    speeds: list[float] = []
    try:
        with path.open(newline="", encoding="utf-8") as stream:
            reader = csv.DictReader(stream)
            if not {"t_s", "kmh"} <= set(reader.fieldnames or []):
                raise ConfigError(f"{path}: needs the columns t_s,kmh")
            for line, row in enumerate(reader, start=2):
                try:
                    t_s, kmh = float(row["t_s"]), float(row["kmh"])
                except (TypeError, ValueError):
                    raise ConfigError(f"{path}:{line}: t_s and kmh must be numbers") from None
                _check_kmh(kmh, f"{path}:{line}")
                if not math.isfinite(t_s) or t_s < 0 or (times and t_s < times[-1]):
                    raise ConfigError(f"{path}:{line}: t_s must be >= 0 and non-decreasing")
                times.append(t_s)
                speeds.append(kmh)
    except OSError as exc:
        raise ConfigError(f"cannot read speed track {path}: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not a UTF-8 CSV") from None
    if not times:
        raise ConfigError(f"{path}: no rows")
    return SpeedTrack(tuple(times), tuple(speeds))


def speed_payload(kmh: float) -> bytes:
    """The speed message the daemon reads: `{"kmh": 57.5}`."""
    return json.dumps({"kmh": round(kmh, 3)}).encode()


def publish_track(
    track: SpeedTrack,
    put: Callable[[bytes], None],
    wait: Callable[[float], bool],
    clock: Callable[[], float],
    rate_hz: float = SPEED_RATE_HZ,
    loop: bool = False,
    duration_s: float | None = None,
) -> Iterator[float]:
    """Put the track's speed every 1/rate_hz s on an absolute schedule (no drift), yielding
    each speed put. Ends when `wait(seconds)` returns True (a stop), after `duration_s`, or at
    the track's end (a constant never ends); with `loop` the track starts again instead."""
    period_s = 1.0 / rate_hz
    started = clock()
    tick = 0
    ends = track.duration_s > 0 and not loop
    while True:
        elapsed_s = tick * period_s
        if duration_s is not None and elapsed_s > duration_s + 1e-9:
            return
        if ends and elapsed_s > track.duration_s + 1e-9:
            return
        t_s = elapsed_s % track.duration_s if loop and track.duration_s > 0 else elapsed_s
        kmh = track.kmh_at(t_s)
        put(speed_payload(kmh))
        yield kmh
        tick += 1
        if wait(max(0.0, started + tick * period_s - clock())):
            return
