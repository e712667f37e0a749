"""Eye closures: `microsleep`, `sleep` and `unresponsive` as one closure lasts (while moving).
Pure. Each once per closure; cleared once the eyes are open and the driver is back on the road
(`clear_on_road_s`)."""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import EPS_S
from roadgaze.monitor.events import Event, Raise, Resolve, Rule
from roadgaze.types import AlertKind, AlertLevel, EyeStatus

__all__ = ["CLOSURE_ALERTS", "EyeClosure", "EyeClosureState"]

CLOSURE_ALERTS = (AlertKind.MICROSLEEP, AlertKind.SLEEP, AlertKind.UNRESPONSIVE)
"""What a closure raises, in the order its times come."""


@dataclass(frozen=True, slots=True)
class EyeClosureState:
    raised: tuple[AlertKind, ...] = ()
    """Alerts already raised for the current closure."""


@dataclass(frozen=True, slots=True)
class EyeClosure:
    """The closure ladder: each rule's setting is the closure time that raises its alert."""

    microsleep: Rule
    sleep: Rule
    unresponsive: Rule

    def initial(self) -> EyeClosureState:
        return EyeClosureState()

    def step(
        self, context: Context, state: EyeClosureState
    ) -> tuple[EyeClosureState, tuple[Event, ...]]:
        eyes = context.eyes
        raised = state.raised if eyes.closure_since_s is not None else ()
        events: list[Event] = []
        if context.moving and eyes.closure_since_s is not None:
            closure_s = eyes.closure_s()
            for kind, level, rule in (
                (AlertKind.MICROSLEEP, AlertLevel.WARNING, self.microsleep),
                (AlertKind.SLEEP, AlertLevel.CRITICAL, self.sleep),
                (AlertKind.UNRESPONSIVE, AlertLevel.CRITICAL, self.unresponsive),
            ):
                if closure_s >= rule.limit(context.config) - EPS_S and kind not in raised:
                    events.append(Raise(kind, level, rule, f"eyes closed {closure_s:.1f} s"))
                    raised = (*raised, kind)
        reopened = eyes.status is EyeStatus.OPEN and context.back_on_road
        if reopened and any(kind in context.active for kind in CLOSURE_ALERTS):
            events.append(Resolve(CLOSURE_ALERTS))
        return (state if raised == state.raised else EyeClosureState(raised)), tuple(events)
