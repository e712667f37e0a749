"""Driver unavailable: no face while moving, not explained by a turn away, for the rule's time.
Pure. Once per loss (again after a face was seen); cleared by `clearing`."""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.events import Event, Raise, Rule
from roadgaze.types import AlertKind, AlertLevel, Gaze

__all__ = ["Unavailable", "UnavailableState"]


@dataclass(frozen=True, slots=True)
class UnavailableState:
    alerted: bool = False
    """Raised for the current loss."""


@dataclass(frozen=True, slots=True)
class Unavailable:
    """`driver_unavailable` by `rule` (its time)."""

    rule: Rule

    def initial(self) -> UnavailableState:
        return UnavailableState()

    def step(
        self, context: Context, state: UnavailableState
    ) -> tuple[UnavailableState, tuple[Event, ...]]:
        unknown = context.look.gaze is Gaze.UNKNOWN and context.moving
        if not unknown:
            return (UnavailableState() if context.sample.face else state), ()
        since_s = context.episode.unavailable_since_s
        if state.alerted or not context.held(since_s, self.rule.limit(context.config)):
            return state, ()
        raised = Raise(AlertKind.DRIVER_UNAVAILABLE, AlertLevel.WARNING, self.rule)
        return UnavailableState(True), (raised,)
