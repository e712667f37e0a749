"""Long distraction: a warning once the off-road episode has spent the protocols' distraction time
outside the driving-related zones, raised to critical later. Pure.

The warning time is the context's trigger (the earliest of the configured protocols' at this
speed: `roadgaze.monitor.protocols`); critical comes `critical_after_warning_s` after it, not
before `critical_distraction_s`. Once per level and episode; cleared by `clearing`.
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import EPS_S
from roadgaze.monitor.events import Event, Raise, Rule
from roadgaze.types import AlertKind, AlertLevel

__all__ = ["Distraction", "DistractionState"]


@dataclass(frozen=True, slots=True)
class DistractionState:
    level: AlertLevel | None = None
    """The level already raised in the current off-road episode."""


@dataclass(frozen=True, slots=True)
class Distraction:
    """`long_distraction`: the warning by the trigger's rule, the escalation by `critical`."""

    critical: Rule

    def initial(self) -> DistractionState:
        return DistractionState()

    def step(
        self, context: Context, state: DistractionState
    ) -> tuple[DistractionState, tuple[Event, ...]]:
        episode, trigger, config = context.episode, context.trigger, context.config
        if not episode.off_road:
            return (state if state.level is None else DistractionState()), ()
        if trigger is None:
            return state, ()
        distraction_s = episode.distraction_s(config, context.t_s)
        critical_s = max(
            config.critical_distraction_s, trigger.warn_s + self.critical.limit(config)
        )
        if distraction_s >= critical_s - EPS_S and state.level is not AlertLevel.CRITICAL:
            raised = Raise(
                AlertKind.LONG_DISTRACTION, AlertLevel.CRITICAL, self.critical, context.look.why
            )
            return DistractionState(AlertLevel.CRITICAL), (raised,)
        if distraction_s >= trigger.warn_s - EPS_S and state.level is None:
            raised = Raise(
                AlertKind.LONG_DISTRACTION, AlertLevel.WARNING, trigger.rule, context.look.why
            )
            return DistractionState(AlertLevel.WARNING), (raised,)
        return state, ()
