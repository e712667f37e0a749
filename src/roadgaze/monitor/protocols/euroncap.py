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
    "IMPAIRED",
    "LONG_DISTRACTION",
    "MICROSLEEP",
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
_DISTRACTION = (ACTIVE, LONG_DISTRACTION, VATS, VATS_WINDOW, VATS_REARM)
_UNRESPONSIVE = (UNRESPONSIVE_AFTER_WARNING, UNRESPONSIVE_AWAY, UNRESPONSIVE_CLOSED)
RULES = (*_DISTRACTION, *_UNRESPONSIVE, MICROSLEEP, SLEEP, IMPAIRED)


def active(config: MonitorConfig, speed_kmh: float | None) -> bool:
    """Active above `min_speed_kmh`; an unknown speed counts as moving (fail-safe)."""
    return speed_kmh is None or speed_kmh > config.min_speed_kmh


def distraction_trigger(config: MonitorConfig, speed_kmh: float | None) -> Trigger | None:
    """The long-distraction warning time (one at every speed above the active one)."""
    if not active(config, speed_kmh):
        return None
    return Trigger(config.long_distraction_s, LONG_DISTRACTION)
