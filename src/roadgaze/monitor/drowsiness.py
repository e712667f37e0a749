"""The drowsiness level: a KSS-like scale from the eyes, the mouth and the head's pitch. Pure.

The level is 5 ("neither alert nor sleepy" on the Karolinska Sleepiness Scale) with no sign of
sleepiness, plus the points of each sign present within the last `perclos_window_s`, at most 9:

- PERCLOS at or above `perclos_drowsy` (0.15): 2 points (Wierwille et al. 1994; Dinges et
  al. 1998).
- `long_blinks_drowsy` (3) blinks of `long_blink_s` (0.5 s) or longer: 2 points (Caffier et
  al. 2003: the share of long closures rises with drowsiness; the counts are roadgaze's).
- `nods_drowsy` (1) nods: the head dropped `nod_drop_deg` below its road pitch with the eyes
  closed and came back up within `nod_max_s`: 2 points (roadgaze's choice).
- A mean duration of 3 or more blinks at or above `blink_duration_drowsy_s` (0.15 s): 1 point
  (Anund et al. 2017: blinks longer than 0.15 s with sleepiness).
- Blinks per minute at or above `blink_rate_drowsy_per_min`: 1 point, off by default (the rate
  rises, Barbato et al. 2007, or falls, De Gennaro et al. 2005, with sleep loss).
- `yawns_drowsy` (2) yawns: the mouth open beyond `yawn_opening` for `yawn_min_s`: 1 point
  (roadgaze's choice; a yawn lasts about 6 s, Provine 1986).

So one strong sign (PERCLOS, long blinks or a nod) reaches 7, Euro NCAP's "KSS 7 or more
equivalent"; the weak signs (blink duration, rate, yawns) reach it only together or beside
another. The points and the base are roadgaze's choice: the level is not a validated KSS
estimate, it orders the evidence on KSS's scale.

The mouth's opening is the inner lips' gap over the inner mouth's width (landmarks 13-14 over
78-308 of MediaPipe's face mesh, in 3-D so a turned head does not widen it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from roadgaze.config import MonitorConfig
from roadgaze.monitor.eyes import EyeMonitorState
from roadgaze.types import FaceFeatures

__all__ = [
    "BASE_LEVEL",
    "MAX_LEVEL",
    "POINTS",
    "DrowsinessSigns",
    "Level",
    "level_of",
    "mouth_opening",
    "track_signs",
]

BASE_LEVEL = 5
"""No sign of sleepiness: KSS 5, "neither alert nor sleepy"."""
MAX_LEVEL = 9
"""KSS 9: "very sleepy, great effort to keep awake, fighting sleep"."""
POINTS = {
    "perclos": 2,
    "long_blinks": 2,
    "nods": 2,
    "blink_duration": 1,
    "blink_rate": 1,
    "yawns": 1,
}
"""Each sign's points (roadgaze's choice: one strong sign reaches 7)."""
MIN_BLINKS_FOR_MEAN = 3
"""A mean blink duration is judged over at least this many blinks."""
UPPER_LIP, LOWER_LIP, INNER_RIGHT, INNER_LEFT = 13, 14, 78, 308
_EPS = 1e-6


def mouth_opening(features: FaceFeatures | None) -> float | None:
    """The inner lips' gap over the inner mouth's width (3-D landmarks); None without them."""
    if features is None:
        return None
    points = features.landmarks_px
    if points.ndim != 2 or points.shape[0] <= INNER_LEFT or points.shape[1] < 3:
        return None
    gap = math.dist(points[UPPER_LIP].tolist(), points[LOWER_LIP].tolist())
    width = math.dist(points[INNER_RIGHT].tolist(), points[INNER_LEFT].tolist())
    if not (math.isfinite(gap) and math.isfinite(width)) or width <= _EPS:
        return None
    return gap / width


@dataclass(frozen=True, slots=True)
class DrowsinessSigns:
    """The mouth and head signs seen so far (the eyes' are measured by `roadgaze.monitor.eyes`);
    replace, never mutate. Bounded: only the window's yawns and nods are kept."""

    open_since_s: float | None = None
    """Since when the mouth has been open beyond `yawn_opening`."""
    yawns: tuple[float, ...] = ()
    """When each yawn within the window started."""
    drop_since_s: float | None = None
    """Since when the head has been `nod_drop_deg` below its road pitch."""
    drop_closed: bool = False
    """The eyes were closed during the current drop."""
    nods: tuple[float, ...] = ()
    """When each nod within the window came back up."""


def track_signs(
    config: MonitorConfig,
    signs: DrowsinessSigns,
    t_s: float,
    opening: float | None,
    pitch_below_road_deg: float | None,
    eyes_closed: bool,
) -> DrowsinessSigns:
    """The signs after one more sample at `t_s`: the mouth's `opening` (None: not seen, closed),
    the head's pitch below its road pitch (> 0 = lower; None: not known, the drop goes on)."""
    oldest = t_s - config.perclos_window_s
    yawns = tuple(t for t in signs.yawns if t > oldest)
    open_since = signs.open_since_s
    if opening is not None and opening >= config.yawn_opening - _EPS:
        open_since = t_s if open_since is None else open_since
        held = t_s - open_since >= config.yawn_min_s - _EPS
        if held and (not yawns or yawns[-1] != open_since):
            yawns = (*yawns, open_since)
    else:
        open_since = None
    nods = tuple(t for t in signs.nods if t > oldest)
    drop_since, drop_closed = signs.drop_since_s, signs.drop_closed
    if pitch_below_road_deg is None:
        drop_closed = drop_closed or (drop_since is not None and eyes_closed)
    elif pitch_below_road_deg >= config.nod_drop_deg - _EPS:
        drop_since = t_s if drop_since is None else drop_since
        drop_closed = drop_closed or eyes_closed
    elif drop_since is not None:
        if drop_closed and t_s - drop_since <= config.nod_max_s + _EPS:
            nods = (*nods, t_s)
        drop_since, drop_closed = None, False
    return DrowsinessSigns(open_since, yawns, drop_since, drop_closed, nods)


@dataclass(frozen=True, slots=True)
class Level:
    """The drowsiness level and the signs that raised it (each as a few words)."""

    level: int
    signs: tuple[str, ...]

    @property
    def why(self) -> str:
        return ", ".join(self.signs) if self.signs else "no sign"


def level_of(config: MonitorConfig, eyes: EyeMonitorState, signs: DrowsinessSigns) -> Level:
    """The level from the eyes' measures (PERCLOS, blinks in the window) and the signs."""
    verdict = eyes.verdict
    found: list[tuple[str, str]] = []
    if verdict.perclos is not None and verdict.perclos >= config.perclos_drowsy - _EPS:
        found.append(("perclos", f"PERCLOS {verdict.perclos:.2f}"))
    if verdict.long_blinks >= config.long_blinks_drowsy:
        found.append(("long_blinks", _count(verdict.long_blinks, "long blink")))
    if len(signs.nods) >= config.nods_drowsy:
        found.append(("nods", _count(len(signs.nods), "nod")))
    durations = [duration for _, duration in eyes.blinks]
    if len(durations) >= MIN_BLINKS_FOR_MEAN:
        mean_s = sum(durations) / len(durations)
        if mean_s >= config.blink_duration_drowsy_s - _EPS:
            found.append(("blink_duration", f"blinks of {mean_s:.2f} s"))
    rate = blinks_per_minute(config, eyes)
    limit = config.blink_rate_drowsy_per_min
    if rate is not None and limit is not None and rate >= limit - _EPS:
        found.append(("blink_rate", f"{rate:.0f} blinks/min"))
    if len(signs.yawns) >= config.yawns_drowsy:
        found.append(("yawns", _count(len(signs.yawns), "yawn")))
    level = min(MAX_LEVEL, BASE_LEVEL + sum(POINTS[name] for name, _ in found))
    return Level(level, tuple(text for _, text in found))


def blinks_per_minute(config: MonitorConfig, eyes: EyeMonitorState) -> float | None:
    """Blinks per minute of judged time in the window (None until `perclos_min_judged_s`)."""
    judged_s = sum(judged for _, _, judged in eyes.bins)
    if judged_s <= 0 or judged_s < config.perclos_min_judged_s - _EPS:
        return None
    return 60.0 * len(eyes.blinks) / judged_s


def _count(count: int, what: str) -> str:
    return f"{count} {what}" if count == 1 else f"{count} {what}s"
