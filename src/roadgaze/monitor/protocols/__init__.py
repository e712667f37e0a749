"""The protocols the monitor warns by: their rules (one module each) and the table of behaviours
they run. Pure.

`[monitor] protocol` picks `addw` (EU 2023/2590), `euroncap` (Euro NCAP driver state monitoring)
or `both` (default: the earlier warning of the two). `TABLE` says which behaviours run
(roadgaze.monitor.behaviours), with which rules, for which protocol, in the order they run;
`distraction_trigger` says when the configured protocols ask for a distraction warning at the
current speed. Every rule names its `[monitor]` setting, unit and source (docs/monitor.md,
"Protocols").
"""

from __future__ import annotations

from functools import cache
from typing import Any

from roadgaze.config import MonitorConfig
from roadgaze.monitor.behaviours import (
    Clearing,
    Degraded,
    Distraction,
    Drowsy,
    EyeClosure,
    NonFunctional,
    PhoneUse,
    Support,
    TemporaryFailure,
    Unavailable,
    Unresponsive,
    Vats,
)
from roadgaze.monitor.context import Behaviour
from roadgaze.monitor.events import Rule, Trigger
from roadgaze.monitor.protocols import addw, euroncap, roadgaze, support

__all__ = [
    "ALL_RULES",
    "TABLE",
    "Rule",
    "Trigger",
    "addw",
    "behaviours",
    "configured",
    "distraction_trigger",
    "euroncap",
    "moving_at",
    "roadgaze",
    "support",
    "uses",
]

ALL_RULES: tuple[Rule, ...] = (*addw.RULES, *euroncap.RULES, *roadgaze.RULES, *support.RULES)
"""Every rule, for the documentation's table and conformance reports."""

TABLE: tuple[tuple[str, Behaviour[Any]], ...] = (
    ("roadgaze", Distraction(critical=roadgaze.CRITICAL)),
    ("euroncap", Vats(euroncap.VATS, rearm=euroncap.VATS_REARM)),
    ("roadgaze", Unavailable(roadgaze.UNAVAILABLE)),
    ("roadgaze", EyeClosure(euroncap.MICROSLEEP, euroncap.SLEEP, euroncap.UNRESPONSIVE_CLOSED)),
    ("roadgaze", Drowsy(roadgaze.DROWSY, euroncap.DROWSINESS, euroncap.DROWSINESS_SPEED)),
    ("roadgaze", Degraded(euroncap.IMPAIRED)),
    ("euroncap", Unresponsive(euroncap.UNRESPONSIVE_AWAY, euroncap.UNRESPONSIVE_AFTER_WARNING)),
    # --- phone use (docs/phone.md) ---
    ("euroncap", PhoneUse(euroncap.PHONE_USE, euroncap.PHONE_GAP)),
    # Non-functional notices (Euro NCAP general requirements).
    (
        "euroncap",
        NonFunctional(
            euroncap.NON_FUNCTIONAL, euroncap.NON_FUNCTIONAL_REPEAT, euroncap.NON_FUNCTIONAL_CLEAR
        ),
    ),
    (
        "roadgaze",
        TemporaryFailure(
            frames=addw.FAILURE_TEMPORARY,
            frozen=roadgaze.FROZEN,
            no_face=roadgaze.NO_FACE,
            eyes=addw.FAILURE_TEMPORARY,
            eyes_needed_by="euroncap",
        ),
    ),
    # Forward and lane support: after every behaviour that raises alerts (it reads their
    # impairment alerts), before clearing.
    *(("roadgaze", Support(c, support.support_rules(c))) for c in support.CHANNELS),
    ("roadgaze", Clearing(roadgaze.CLEAR)),
)
"""Which behaviour runs for which protocol, configured with which rules, in the order they run
(a sample's alerts come in this order; a behaviour sees the events of those before it). The
`roadgaze` rows run under every protocol: the long distraction's warning time comes from the
configured protocols' triggers (`distraction_trigger`), the eye rules cite Euro NCAP's rows."""


@cache
def configured(protocol: str) -> frozenset[str]:
    """The protocols `[monitor] protocol` (`addw`, `euroncap` or `both`) stands for."""
    return frozenset({"addw", "euroncap"} if protocol == "both" else {protocol})


@cache
def behaviours(protocol: str) -> tuple[Behaviour[Any], ...]:
    """The behaviours `[monitor] protocol` runs, in order."""
    protocols = configured(protocol)
    return tuple(b for owner, b in TABLE if owner == "roadgaze" or owner in protocols)


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
