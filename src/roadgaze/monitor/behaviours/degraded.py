"""Monitoring degraded: the eyes unavailable for `degraded_after_s` while moving (the eyes'
measurement, roadgaze.monitor.eyes), so the head pose alone judges the driver. Pure. Raised when
it starts; cleared once the eyes are judged again."""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.events import Event, Raise, Resolve, Rule
from roadgaze.types import AlertKind, AlertLevel

__all__ = ["Degraded", "DegradedState"]


@dataclass(frozen=True, slots=True)
class DegradedState:
    degraded: bool = False
    """Degraded at the last sample (told already)."""


@dataclass(frozen=True, slots=True)
class Degraded:
    """`degraded` by `rule`."""

    rule: Rule

    def initial(self) -> DegradedState:
        return DegradedState()

    def step(
        self, context: Context, state: DegradedState
    ) -> tuple[DegradedState, tuple[Event, ...]]:
        eyes = context.eyes
        if eyes.degraded and not state.degraded:
            why = f"eyes unavailable: {eyes.reason}"
            return DegradedState(True), (
                Raise(AlertKind.DEGRADED, AlertLevel.WARNING, self.rule, why),
            )
        events: tuple[Event, ...] = ()
        if not eyes.degraded and AlertKind.DEGRADED in context.active:
            events = (Resolve((AlertKind.DEGRADED,)),)
        return (state if eyes.degraded is state.degraded else DegradedState(eyes.degraded)), events
