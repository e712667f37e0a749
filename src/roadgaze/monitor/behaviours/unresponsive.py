"""Euro NCAP's unresponsive driver on the distraction path: away (outside the road and the
driving-related zones) for the `away` rule's time, or not back on the road the `after_warning`
rule's time after a `long_distraction` or `vats` warning. Pure.

Once per episode, not while `unresponsive` is active (a closure may have raised it:
`eye_closure`); cleared by `clearing`.
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import EPS_S
from roadgaze.monitor.events import Event, Raise, Rule
from roadgaze.types import AlertKind, AlertLevel

__all__ = ["Unresponsive", "UnresponsiveState"]


@dataclass(frozen=True, slots=True)
class UnresponsiveState:
    warned_since_s: float | None = None
    """When a distraction warning asked the driver to look back and they have not yet."""
    away_raised: bool = False
    """Raised by the away rule in the current off-road episode."""


@dataclass(frozen=True, slots=True)
class Unresponsive:
    """`unresponsive` by `away` or `after_warning` (each rule's setting is its time)."""

    away: Rule
    after_warning: Rule

    def initial(self) -> UnresponsiveState:
        return UnresponsiveState()

    def step(
        self, context: Context, state: UnresponsiveState
    ) -> tuple[UnresponsiveState, tuple[Event, ...]]:
        config = context.config
        away_raised = state.away_raised and context.episode.off_road
        warned = context.raised(AlertKind.LONG_DISTRACTION, AlertLevel.WARNING) or context.raised(
            AlertKind.VATS, AlertLevel.WARNING
        )
        warned_since = state.warned_since_s
        if warned_since is None and warned:
            warned_since = context.t_s
        if context.looking:
            warned_since = None
        kind = AlertKind.UNRESPONSIVE
        if not context.moving or kind in context.active or context.raised(kind):
            return UnresponsiveState(warned_since, away_raised), ()
        distraction_s = context.episode.distraction_s(config, context.t_s)
        if not away_raised and distraction_s >= self.away.limit(config) - EPS_S:
            why = f"away {distraction_s:.1f} s"
            return UnresponsiveState(None, True), (
                Raise(kind, AlertLevel.CRITICAL, self.away, why),
            )
        if context.held(warned_since, self.after_warning.limit(config)):
            why = "not back on road after a warning"
            return UnresponsiveState(None, away_raised), (
                Raise(kind, AlertLevel.CRITICAL, self.after_warning, why),
            )
        return UnresponsiveState(warned_since, away_raised), ()
