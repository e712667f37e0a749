"""Inattention monitor: glance zones and a pure time-based state machine, samples to verdicts."""

from roadgaze.monitor.context import Behaviour, Context
from roadgaze.monitor.events import Publish, Raise, Resolve, Rule
from roadgaze.monitor.eye_rules import classify_eyes, eye_zone_map, gaze_deg, soft_threshold
from roadgaze.monitor.eyes import EyeMonitorState
from roadgaze.monitor.eyes_alone import step_eyes
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
    "Behaviour",
    "Context",
    "EyeMonitorState",
    "Gaze",
    "Monitor",
    "MonitorState",
    "Publish",
    "Raise",
    "Resolve",
    "Rule",
    "Verdict",
    "Zone",
    "ZoneMap",
    "classify_eyes",
    "classify_zone",
    "distraction_s",
    "eye_zone_map",
    "gaze_deg",
    "initial_state",
    "soft_threshold",
    "step",
    "step_eyes",
    "verdict_of",
]
