"""Per-frame eye rules: open, closed or unavailable, and gaze = head + eyes. Pure.

Definitions and the evidence for each threshold: docs/monitor.md ("Eyes").
"""

from __future__ import annotations

import math
from dataclasses import replace

from roadgaze.config import MonitorConfig
from roadgaze.monitor.zones import Zone, ZoneMap
from roadgaze.types import EyesFeatures, EyeStatus

__all__ = [
    "HIDDEN",
    "POPULATION_OPEN",
    "classify_eyes",
    "eye_zone_map",
    "firm_threshold",
    "gaze_deg",
    "hidden_reason",
    "soft_threshold",
]

POPULATION_OPEN = 0.30
"""The open-eye openness the thresholds are set for (Pointing'04 median 0.31)."""


def soft_threshold(value_deg: float, deadband_deg: float) -> float:
    """sign(v) max(0, |v| - deadband): deviations inside the deadband count as none."""
    return math.copysign(max(0.0, abs(value_deg) - deadband_deg), value_deg)


def firm_threshold(value_deg: float, deadband_deg: float, full_factor: float) -> float:
    """Zero within the deadband T, all of the value beyond `full_factor` x T, and a straight ramp
    between them (Gao and Bruce's firm shrinkage): continuous like `soft_threshold`, but a large
    deviation is not shortened by T. `full_factor` must be >= 1 (1: a hard threshold; infinite:
    `soft_threshold`)."""
    size = abs(value_deg)
    if size <= deadband_deg:
        return 0.0
    full_deg = full_factor * deadband_deg
    if size >= full_deg:
        return value_deg
    if math.isinf(full_factor):
        return soft_threshold(value_deg, deadband_deg)
    return math.copysign(full_deg * (size - deadband_deg) / (full_deg - deadband_deg), value_deg)


def gaze_deg(
    head_yaw_deg: float,
    head_pitch_deg: float,
    eyes: EyesFeatures | None,
    deadband_deg: float,
    eye_neutral_deg: tuple[float, float] = (0.0, 0.0),
) -> tuple[float, float, bool]:
    """Gaze yaw and pitch (degrees) and whether the eyes contributed.

    gaze = head + soft_threshold(eye-in-head - eye neutral, deadband) per axis; the head pose
    alone when the eyes give no direction.
    """
    if eyes is None or eyes.yaw_deg is None or eyes.pitch_deg is None:
        return head_yaw_deg, head_pitch_deg, False
    yaw = head_yaw_deg + soft_threshold(eyes.yaw_deg - eye_neutral_deg[0], deadband_deg)
    pitch = head_pitch_deg + soft_threshold(eyes.pitch_deg - eye_neutral_deg[1], deadband_deg)
    return yaw, pitch, True


HIDDEN = "eyes hidden"
"""The start of every reason of eyes hidden (`hidden_reason`)."""
_HIDDEN_BY = {"strands": "by strands across them", "hand": "by a hand"}


def hidden_reason(eyes: EyesFeatures) -> str:
    """`eyes hidden` (a flat opening: a dark lens), or with what hides them: `eyes hidden by
    strands across them` (hair), `eyes hidden by a hand`."""
    by = _HIDDEN_BY.get(eyes.occluded_by, eyes.occluded_by)
    return f"{HIDDEN} {by}" if by else HIDDEN


def classify_eyes(
    config: MonitorConfig,
    eyes: EyesFeatures | None,
    head_below_road_deg: float | None,
    was_closed: bool | None = None,
    open_baseline: float | None = None,
    iris_aside: bool = False,
) -> tuple[EyeStatus, str]:
    """Open, closed or unavailable, and why (module docstring).

    `head_below_road_deg`: how far the head's MediaPipe pitch lies below its road pitch (> 0 =
    lowered; None unknown). `was_closed`: the previous decision (None: none yet).
    `open_baseline`: the driver's learned open-eye openness (None: the population's).
    `iris_aside`: the eyes read turned sideways off their rest and centre
    (`roadgaze.monitor.eye_calibration.iris_aside`): lids that begin to read closed then are
    narrowed for a glance ("looking aside").
    """
    if eyes is None:
        return EyeStatus.UNAVAILABLE, "no eyes measured"
    if eyes.occluded:
        return EyeStatus.UNAVAILABLE, hidden_reason(eyes)
    openness, blink = eyes.openness, eyes.blink
    if openness is None:
        reasons = [e.reason for e in (eyes.right, eyes.left) if e.reason]
        return EyeStatus.UNAVAILABLE, eyes.reason or (reasons[0] if reasons else "no eye")
    factor = 1.0
    if open_baseline is not None and math.isfinite(open_baseline) and open_baseline > 0:
        factor = min(1.3, max(0.7, open_baseline / POPULATION_OPEN))
    if was_closed:
        if openness > config.eyes_open_above * factor:
            return EyeStatus.OPEN, ""
        return EyeStatus.CLOSED, "eyes closed"
    closed = openness < config.eyes_hard_close_below * factor or (
        openness < config.eyes_close_below * factor
        and (blink is None or blink >= config.eyes_blink_min)
    )
    if not closed:
        return EyeStatus.OPEN, ""
    if head_below_road_deg is not None and head_below_road_deg > config.look_down_head_deg:
        return EyeStatus.OPEN, "looking down"
    if iris_aside:
        return EyeStatus.OPEN, "looking aside"
    return _judgeable_closure(config, eyes, factor)


def _judgeable_closure(
    config: MonitorConfig, eyes: EyesFeatures, factor: float
) -> tuple[EyeStatus, str]:
    """Lids that read closed, unless the image cannot show them (fail-safe: unavailable, never
    closed): no sharp edges around the eyes (motion blur, glare), or one judged eye while the
    other, not judged (the far eye of a turned head), still reads open. A closure shuts both."""
    if eyes.blurred:
        return EyeStatus.UNAVAILABLE, "eyes blurred"
    judged = [e for e in (eyes.right, eyes.left) if e.closure_usable]
    others = [e for e in (eyes.right, eyes.left) if not e.closure_usable]
    if len(judged) == 1 and any(
        math.isfinite(e.openness) and e.openness >= config.eyes_close_below * factor for e in others
    ):
        return EyeStatus.UNAVAILABLE, "eyes disagree"
    return EyeStatus.CLOSED, "eyes closed"


def eye_zone_map(zones: ZoneMap, margin_deg: float) -> ZoneMap:
    """The zones for a gaze measured with the eyes: the road (the first zone) narrower by
    `margin_deg` on both sides in yaw and at its lower edge (never inverted); the upper edge and
    the other zones as they are (MediaPipe's eye pitch does not register upward gaze)."""
    road = zones.road
    yaw_half = max(0.0, 0.5 * (road.yaw_max_deg - road.yaw_min_deg) - margin_deg)
    yaw_mid = 0.5 * (road.yaw_max_deg + road.yaw_min_deg)
    pitch_min = min(road.pitch_min_deg + margin_deg, road.pitch_max_deg)
    narrow = Zone(road.name, yaw_mid - yaw_half, yaw_mid + yaw_half, pitch_min, road.pitch_max_deg)
    return replace(zones, zones=(narrow, *zones.zones[1:]))
