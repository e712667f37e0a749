"""The protocols the monitor warns by, as tables of rules (one module each). Pure.

`[monitor] protocol` picks `addw` (EU 2023/2590), `euroncap` (Euro NCAP driver state monitoring)
or `both` (default: the earlier warning of the two). The state machine
(`roadgaze.monitor.inattention`) asks this module when a distraction warning is due at the
current speed and which rule an alert fired by; every rule names its `[monitor]` setting, unit
and source (docs/monitor.md, "Protocols").
"""

from __future__ import annotations

from roadgaze.config import MonitorConfig
from roadgaze.monitor.protocols import addw, euroncap, roadgaze
from roadgaze.monitor.protocols.rules import Rule, Trigger
from roadgaze.types import AlertKind, AlertLevel

__all__ = [
    "ALL_RULES",
    "Rule",
    "Trigger",
    "addw",
    "distraction_trigger",
    "euroncap",
    "moving_at",
    "roadgaze",
    "rule_of",
    "uses",
]

ALL_RULES: tuple[Rule, ...] = (*addw.RULES, *euroncap.RULES, *roadgaze.RULES)
"""Every rule, for the documentation's table and conformance reports."""


def uses(config: MonitorConfig, protocol: str) -> bool:
    """Whether `protocol` (`addw` or `euroncap`) is among the configured ones."""
    return config.protocol in (protocol, "both")


def moving_at(config: MonitorConfig, speed_kmh: float | None) -> bool:
    """Fast enough for a configured protocol to warn; an unknown speed counts as moving."""
    if speed_kmh is None:
        return True
    return (uses(config, "addw") and addw.active(config, speed_kmh)) or (
        uses(config, "euroncap") and euroncap.active(config, speed_kmh)
    )


def distraction_trigger(
    config: MonitorConfig, speed_kmh: float | None, non_nominal: bool = False
) -> Trigger | None:
    """The earliest distraction warning the configured protocols ask for at this speed (None:
    none is active). `non_nominal`: the service knows conditions are non-nominal (ADDW's
    allowance applies)."""
    triggers = []
    if uses(config, "euroncap"):
        triggers.append(euroncap.distraction_trigger(config, speed_kmh))
    if uses(config, "addw"):
        triggers.append(addw.distraction_trigger(config, speed_kmh, non_nominal))
    due = [t for t in triggers if t is not None]
    return min(due, key=lambda t: t.warn_s) if due else None


def rule_of(kind: AlertKind, level: AlertLevel, reason: str) -> Rule | None:
    """The rule an alert other than a long-distraction warning fired by."""
    if kind is AlertKind.LONG_DISTRACTION and level is AlertLevel.CRITICAL:
        return roadgaze.CRITICAL
    by_reason = _BY_REASON.get(kind)
    if by_reason is not None:
        return next((rule for start, rule in by_reason if reason.startswith(start)), None)
    return _BY_KIND.get(kind)


_BY_REASON: dict[AlertKind, tuple[tuple[str, Rule], ...]] = {
    AlertKind.UNRESPONSIVE: (
        ("eyes closed", euroncap.UNRESPONSIVE_CLOSED),
        ("away", euroncap.UNRESPONSIVE_AWAY),
        ("", euroncap.UNRESPONSIVE_AFTER_WARNING),
    ),
    AlertKind.TEMPORARY_FAILURE: (
        ("frames frozen", roadgaze.FROZEN),
        ("no face", roadgaze.NO_FACE),
        ("", addw.FAILURE_TEMPORARY),
    ),
}
"""Kinds whose rule depends on the reason: the first prefix that matches."""
_BY_KIND: dict[AlertKind, Rule] = {
    AlertKind.VATS: euroncap.VATS,
    AlertKind.DRIVER_UNAVAILABLE: roadgaze.UNAVAILABLE,
    AlertKind.MICROSLEEP: euroncap.MICROSLEEP,
    AlertKind.SLEEP: euroncap.SLEEP,
    AlertKind.DROWSY: roadgaze.DROWSY,
    AlertKind.DEGRADED: euroncap.IMPAIRED,
    AlertKind.PERMANENT_FAILURE: addw.FAILURE_PERMANENT,
    AlertKind.CLEARED: roadgaze.CLEAR,
}
