"""Inattention monitor: a pure time-based state machine from pose samples to verdicts."""

from roadgaze.monitor.inattention import (
    Monitor,
    MonitorState,
    initial_state,
    step,
    verdict_of,
)
from roadgaze.types import Alert, AlertKind, AlertLevel, Gaze, Verdict

__all__ = [
    "Alert",
    "AlertKind",
    "AlertLevel",
    "Gaze",
    "Monitor",
    "MonitorState",
    "Verdict",
    "initial_state",
    "step",
    "verdict_of",
]
