"""Clearing: one `cleared` alert for the active alerts whose cause ended at this sample. Pure.

The distraction alerts (`long_distraction`, `vats`, `driver_unavailable`, `unresponsive`) end
once the driver has looked at the road, with a face and the eyes not closed, for the rule's time
(`clear_on_road_s`; 0: at once); the other behaviours say when theirs end (`Resolve` events). The
alert lists the kinds in the order they were raised, then the failures that recovered. Runs last.
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.events import Event, Raise, Rule
from roadgaze.types import AlertKind, AlertLevel

__all__ = ["DISTRACTION_KINDS", "Clearing"]

DISTRACTION_KINDS = frozenset(
    {
        AlertKind.LONG_DISTRACTION,
        AlertKind.VATS,
        AlertKind.DRIVER_UNAVAILABLE,
        AlertKind.UNRESPONSIVE,
    }
)
"""Cleared by looking at the road for the rule's time."""


@dataclass(frozen=True, slots=True)
class Clearing:
    """`cleared` by `rule`; no state of its own."""

    rule: Rule

    def initial(self) -> None:
        return None

    def step(self, context: Context, state: None) -> tuple[None, tuple[Event, ...]]:
        if not context.active:
            return None, ()
        back = context.back_on_road
        ended = context.resolved(recovery=False) | (DISTRACTION_KINDS if back else frozenset())
        recovered = context.resolved(recovery=True)
        clears = (
            *(kind for kind in context.active if kind in ended),
            *(kind for kind in context.active if kind in recovered and kind not in ended),
        )
        if not clears:
            return None, ()
        return None, (Raise(AlertKind.CLEARED, AlertLevel.INFO, self.rule, clears=clears),)
