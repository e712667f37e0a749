"""EU ADDW (Commission Delegated Regulation (EU) 2023/2590) as data. Pure.

The numbers are the regulation's Annex I as summarised by the type-approval services UTAC and
ATIC (the regulation's own text was not reachable from here; its table of contents places the
warning triggers in Annex I 3.3.2 and the failure warnings in 3.5). Each rule's value is a
`[monitor]` setting.
"""

from __future__ import annotations

from roadgaze.config import MonitorConfig
from roadgaze.monitor.events import Rule, Trigger

__all__ = [
    "ACTIVE",
    "AREA_ROOF",
    "AREA_YAW",
    "BAND",
    "DISTRACTION_HIGH",
    "DISTRACTION_LOW",
    "FAILURE_PERMANENT",
    "FAILURE_TEMPORARY",
    "NON_NOMINAL",
    "RULES",
    "active",
    "distraction_trigger",
]

_REG = "EU 2023/2590 Annex I"
ACTIVE = Rule(
    "addw.active", "addw_min_speed_kmh", "km/h", f"{_REG} 3.3.2", "warns only above this speed"
)
BAND = Rule("addw.band", "addw_band_kmh", "km/h", f"{_REG} 3.3.2", "the two speed bands meet here")
DISTRACTION_LOW = Rule(
    "addw.distraction.20_50kmh",
    "addw_distraction_low_s",
    "s",
    f"{_REG} 3.3.2",
    "warn by this much distraction at 20-50 km/h",
)
DISTRACTION_HIGH = Rule(
    "addw.distraction.above_50kmh",
    "addw_distraction_high_s",
    "s",
    f"{_REG} 3.3.2",
    "warn within this much distraction above 50 km/h (and at unknown speed)",
)
NON_NOMINAL = Rule(
    "addw.non_nominal",
    "addw_non_nominal_s",
    "s",
    f"{_REG} 3.3.2",
    "added under non-nominal conditions the service knows of (eyes hidden, dark frame)",
)
AREA_YAW = Rule(
    "addw.area1.side",
    "distraction_yaw_deg",
    "deg",
    f"{_REG} 1 (distraction area 1: beyond two vertical planes at +-55 deg)",
    "beyond +-this yaw from the forward direction is always distraction",
)
AREA_ROOF = Rule(
    "addw.area1.roof",
    "roof_pitch_deg",
    "deg",
    f"{_REG} 1 (distraction area 1: the roof); the angle is roadgaze's estimate",
    "above this pitch is always distraction",
)
FAILURE_TEMPORARY = Rule(
    "addw.failure.temporary",
    "frame_failure_s",
    "s",
    f"{_REG} 3.5.2",
    "temporary failure (blocked, black, saturated frames) warned after this long",
)
FAILURE_PERMANENT = Rule(
    "addw.failure.permanent",
    "permanent_failure_s",
    "s",
    f"{_REG} 3.5.1",
    "permanent failure (camera gone, model unusable) warned",
)
_DISTRACTION = (ACTIVE, BAND, DISTRACTION_LOW, DISTRACTION_HIGH, NON_NOMINAL)
RULES = (*_DISTRACTION, AREA_YAW, AREA_ROOF, FAILURE_TEMPORARY, FAILURE_PERMANENT)


def active(config: MonitorConfig, speed_kmh: float | None) -> bool:
    """ADDW is active above its speed; an unknown speed counts as moving (fail-safe)."""
    return speed_kmh is None or speed_kmh > config.addw_min_speed_kmh


def distraction_trigger(
    config: MonitorConfig, speed_kmh: float | None, non_nominal: bool
) -> Trigger | None:
    """ADDW's distraction warning time at this speed (None below its speed); an unknown speed
    is the highest band."""
    if not active(config, speed_kmh):
        return None
    high = speed_kmh is None or speed_kmh > config.addw_band_kmh
    rule = DISTRACTION_HIGH if high else DISTRACTION_LOW
    allowance_s = config.addw_non_nominal_s if non_nominal else 0.0
    base_s = config.addw_distraction_high_s if high else config.addw_distraction_low_s
    return Trigger(base_s + allowance_s, rule, allowance_s)
