"""Escalation and clearing: Euro NCAP's unresponsive driver on the distraction path, and which
active alerts a sample ends. Pure; part of `roadgaze.monitor.inattention.step`."""

from __future__ import annotations

from roadgaze.config import MonitorConfig
from roadgaze.monitor.eyes import EyeMonitorState, clearable_eye_kinds
from roadgaze.monitor.state import EPS_S, MonitorState
from roadgaze.types import Alert, AlertKind, AlertLevel

__all__ = ["DISTRACTION_KINDS", "split_cleared", "unresponsive_check"]

DISTRACTION_KINDS = frozenset(
    {
        AlertKind.LONG_DISTRACTION,
        AlertKind.VATS,
        AlertKind.DRIVER_UNAVAILABLE,
        AlertKind.UNRESPONSIVE,
    }
)
"""Cleared by the first on-road sample with a face whose eyes are not closed."""


def unresponsive_check(
    config: MonitorConfig,
    state: MonitorState,
    alerts: list[Alert],
    t_s: float,
    moving: bool,
    looking: bool,
    distraction_now_s: float,
    away_raised: bool,
) -> tuple[float | None, bool, str]:
    """Euro NCAP's unresponsive driver on the distraction path: away `unresponsive_away_s`, or
    not back on the road `unresponsive_after_warning_s` after a distraction warning. Returns
    the warning's time still waiting for a look back, whether the away rule fired in this
    episode, and the reason to raise `unresponsive` now ('' for none)."""
    warned = any(
        a.kind in (AlertKind.LONG_DISTRACTION, AlertKind.VATS) and a.level is AlertLevel.WARNING
        for a in alerts
    )
    warned_since = state.warned_since_s if state.warned_since_s is not None or not warned else t_s
    if looking:
        warned_since = None
    already = AlertKind.UNRESPONSIVE in state.active or any(
        a.kind is AlertKind.UNRESPONSIVE for a in alerts
    )
    if not moving or already:
        return warned_since, away_raised, ""
    if not away_raised and distraction_now_s >= config.unresponsive_away_s - EPS_S:
        return None, True, f"away {distraction_now_s:.1f} s"
    if (
        warned_since is not None
        and t_s - warned_since >= config.unresponsive_after_warning_s - EPS_S
    ):
        return None, away_raised, "not back on road after a warning"
    return warned_since, away_raised, ""


def split_cleared(
    active: list[AlertKind], eyes: EyeMonitorState, looking: bool
) -> tuple[tuple[AlertKind, ...], list[AlertKind]]:
    """The active alerts this sample clears, and those that stay. `looking`: on the road with a
    face and the eyes not closed. Distraction alerts clear when looking; a closure's alerts once
    the eyes are open on the road; `drowsy` once re-armed; `degraded` once the eyes are back."""
    clearable = set(clearable_eye_kinds(eyes, on_road=looking))
    if looking:
        clearable.update(DISTRACTION_KINDS)
    cleared = tuple(kind for kind in active if kind in clearable)
    return cleared, [kind for kind in active if kind not in clearable]
