"""Euro NCAP driver state monitoring (Assessment Protocol - Safety Assist, Safe Driving, 2023,
carried into the 2026 protocols) as data. Pure.

The numbers are the protocol's definitions as summarised in published secondary sources (Forster
et al., Accid. Anal. Prev. 205 (2024) 107684; the protocol's own PDF was not reachable from
here). The protocol's lowest operating speed was not found in a readable source: `min_speed_kmh`
(20 km/h, ADDW's) is roadgaze's choice. Each rule's value is a `[monitor]` setting.
"""

from __future__ import annotations

from roadgaze.config import MonitorConfig
from roadgaze.monitor.events import Rule, Trigger

__all__ = [
    "ACTIVE",
    "DROWSINESS",
    "DROWSINESS_SPEED",
    "IMPAIRED",
    "LONG_DISTRACTION",
    "MICROSLEEP",
    "NON_FUNCTIONAL",
    "NON_FUNCTIONAL_CLEAR",
    "NON_FUNCTIONAL_REPEAT",
    "PHONE_GAP",
    "PHONE_USE",
    "RULES",
    "SLEEP",
    "UNRESPONSIVE_AFTER_WARNING",
    "UNRESPONSIVE_AWAY",
    "UNRESPONSIVE_CLOSED",
    "VATS",
    "VATS_REARM",
    "VATS_WINDOW",
    "active",
    "distraction_trigger",
]

_DSM = "Euro NCAP SA Safe Driving, Driver State Monitoring"
ACTIVE = Rule(
    "euroncap.active",
    "min_speed_kmh",
    "km/h",
    "roadgaze's choice (ADDW's 20 km/h; the protocol's own figure not read here)",
    "warns only above this speed",
)
LONG_DISTRACTION = Rule(
    "euroncap.long_distraction",
    "long_distraction_s",
    "s",
    f"{_DSM}: long distraction, a single glance away of 3 s or more",
    "warn after this much distraction in one glance",
)
VATS = Rule(
    "euroncap.vats",
    "vats_threshold_s",
    "s",
    f"{_DSM}: visual attention time sharing, 10 s within 30 s",
    "off-road time within the window that warns",
)
VATS_WINDOW = Rule("euroncap.vats.window", "vats_window_s", "s", VATS.source, "the VATS window")
VATS_REARM = Rule(
    "euroncap.vats.rearm",
    "vats_rearm_s",
    "s",
    f"{_DSM}: re-armed after 2 s on the road",
    "VATS warns again after this long on the road",
)
UNRESPONSIVE_AFTER_WARNING = Rule(
    "euroncap.unresponsive.after_warning",
    "unresponsive_after_warning_s",
    "s",
    f"{_DSM}: unresponsive driver, not back on the road within 3 s of a warning",
    "not back on the road this long after a distraction warning",
)
UNRESPONSIVE_AWAY = Rule(
    "euroncap.unresponsive.away",
    "unresponsive_away_s",
    "s",
    f"{_DSM}: unresponsive driver, looking away 6 s or more",
    "away this long",
)
UNRESPONSIVE_CLOSED = Rule(
    "euroncap.unresponsive.eyes_closed",
    "unresponsive_closed_s",
    "s",
    f"{_DSM}: unresponsive driver, eyes closed 6 s or more",
    "eyes closed this long",
)
MICROSLEEP = Rule(
    "euroncap.microsleep",
    "microsleep_s",
    "s",
    f"{_DSM}: microsleep, a closure shorter than 3 s (roadgaze warns from 1 s)",
    "eyes closed this long",
    impairment=True,
)
SLEEP = Rule(
    "euroncap.sleep",
    "sleep_s",
    "s",
    f"{_DSM}: sleep, a closure longer than 3 s",
    "closed",
    impairment=True,
)
IMPAIRED = Rule(
    "euroncap.impaired_monitoring",
    "degraded_after_s",
    "s",
    f"{_DSM}: impaired monitoring told to the driver within 10 s",
    "eyes unavailable this long: monitoring degraded",
)
# Drowsiness (impairment by fatigue): the level and its speed.
_SD_2026 = "Euro NCAP 2026 Safe Driving, Driver Engagement"
DROWSINESS = Rule(
    "euroncap.drowsiness",
    "drowsiness_warn_level",
    "level",
    f"{_SD_2026}: drowsiness at a level equivalent to KSS 7 or more (smarteye.se's summary of "
    "the 2026 protocol); the level is roadgaze's KSS-like scale of sourced signs",
    "warn at this drowsiness level or above",
    impairment=True,
)
DROWSINESS_SPEED = Rule(
    "euroncap.drowsiness.min_speed",
    "drowsiness_min_speed_kmh",
    "km/h",
    f"{_SD_2026}: impairment driver states active when moving forward at at least 50 km/h "
    "(the rating calculator's general requirement)",
    "drowsiness warns only at this speed or above",
)
# Non-functional notices (roadgaze.monitor.behaviours.non_functional).
_GENERAL = "Euro NCAP 2026 Safe Driving, Driver Engagement, DSM general requirements"
NON_FUNCTIONAL = Rule(
    "euroncap.non_functional",
    "non_functional_after_s",
    "s",
    f"{_GENERAL}: inform of a non-functional system within 10 s (dark sunglasses, a cap, a hat, "
    "a hair fringe, thick eyelash makeup, the sensor obstructed by a hand on the wheel); the "
    "5 s default is roadgaze's choice",
    "the eyes or the face hidden this long while facing the road: not functional",
)
NON_FUNCTIONAL_REPEAT = Rule(
    "euroncap.non_functional.repeat",
    "non_functional_repeat_s",
    "s",
    f"{_GENERAL}: visual information about a non-functional system shown permanently or every "
    "10 minutes",
    "a notice in force is raised again this often",
)
NON_FUNCTIONAL_CLEAR = Rule(
    "euroncap.non_functional.clear",
    "non_functional_clear_s",
    "s",
    "roadgaze's choice",
    "the notice ends once the condition has been gone this long",
)
_NOTICES = (NON_FUNCTIONAL, NON_FUNCTIONAL_REPEAT, NON_FUNCTIONAL_CLEAR)

_DISTRACTION = (ACTIVE, LONG_DISTRACTION, VATS, VATS_WINDOW, VATS_REARM)
_UNRESPONSIVE = (UNRESPONSIVE_AFTER_WARNING, UNRESPONSIVE_AWAY, UNRESPONSIVE_CLOSED)
# --- phone use ---
PHONE_USE = Rule(
    "euroncap.phone_use",
    "phone_use_s",
    "s",
    "Euro NCAP 2026 Safe Driving, Driver Engagement: phone use (basic: a phone in a known "
    "place, advanced: held up at the wheel or in view) is a transient distraction of the "
    "dossier's rows 51-64; the 2026 text's own time was not readable here, so roadgaze warns "
    "after the long distraction's 3 s (roadgaze's choice)",
    "a phone judged in hand this long while moving",
)
PHONE_GAP = Rule(
    "euroncap.phone_use.gap",
    "phone_gap_s",
    "s",
    "roadgaze's choice (the hand stage misses a held phone on some frames)",
    "a phone out of sight this long ends the phone use",
)
_PHONE = (PHONE_USE, PHONE_GAP)

RULES = (
    *_DISTRACTION,
    *_UNRESPONSIVE,
    MICROSLEEP,
    SLEEP,
    IMPAIRED,
    DROWSINESS,
    DROWSINESS_SPEED,
    *_PHONE,
    *_NOTICES,
)


def active(config: MonitorConfig, speed_kmh: float | None) -> bool:
    """Active above `min_speed_kmh`; an unknown speed counts as moving (fail-safe)."""
    return speed_kmh is None or speed_kmh > config.min_speed_kmh


def distraction_trigger(config: MonitorConfig, speed_kmh: float | None) -> Trigger | None:
    """The long-distraction warning time (one at every speed above the active one)."""
    if not active(config, speed_kmh):
        return None
    return Trigger(config.long_distraction_s, LONG_DISTRACTION)
