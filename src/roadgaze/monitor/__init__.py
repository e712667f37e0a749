"""Inattention monitor: glance zones and a pure time-based state machine, samples to verdicts."""

from roadgaze.monitor.inattention import Monitor, step, verdict_of
from roadgaze.monitor.state import MonitorState, distraction_s, initial_state
from roadgaze.monitor.zones import (
    AWAY,
    DEFAULT_DRIVING_RELATED,
    DEFAULT_ZONES,
    ROAD,
    Zone,
    ZoneMap,
    classify_zone,
)
from roadgaze.types import Alert, AlertKind, AlertLevel, Gaze, Verdict

__all__ = [
    "AWAY",
    "DEFAULT_DRIVING_RELATED",
    "DEFAULT_ZONES",
    "ROAD",
    "Alert",
    "AlertKind",
    "AlertLevel",
    "Gaze",
    "Monitor",
    "MonitorState",
    "Verdict",
    "Zone",
    "ZoneMap",
    "classify_zone",
    "distraction_s",
    "initial_state",
    "step",
    "verdict_of",
]
