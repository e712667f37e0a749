"""Drowsiness: PERCLOS at or above `perclos_drowsy`, or `long_blinks_drowsy` long blinks within
the PERCLOS window (while moving). Pure. Fires once, re-armed (and cleared) once PERCLOS is below
`perclos_rearm` and the long blinks fewer."""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import EPS_S
from roadgaze.monitor.events import Event, Raise, Resolve, Rule
from roadgaze.types import AlertKind, AlertLevel

__all__ = ["Drowsy", "DrowsyState"]


@dataclass(frozen=True, slots=True)
class DrowsyState:
    armed: bool = True
    """It may fire."""


@dataclass(frozen=True, slots=True)
class Drowsy:
    """`drowsy` by `rule` (its PERCLOS level)."""

    rule: Rule

    def initial(self) -> DrowsyState:
        return DrowsyState()

    def step(self, context: Context, state: DrowsyState) -> tuple[DrowsyState, tuple[Event, ...]]:
        config, verdict = context.config, context.eyes.verdict
        perclos = verdict.perclos
        by_perclos = perclos is not None and perclos >= self.rule.limit(config) - EPS_S
        by_blinks = verdict.long_blinks >= config.long_blinks_drowsy
        if context.moving and state.armed and (by_perclos or by_blinks):
            why = f"PERCLOS {perclos:.2f}" if by_perclos and perclos is not None else "long blinks"
            return DrowsyState(False), (
                Raise(AlertKind.DROWSY, AlertLevel.WARNING, self.rule, why),
            )
        rearmed = not by_blinks and (perclos is None or perclos < config.perclos_rearm)
        if not state.armed and not rearmed:
            return state, ()
        events = (Resolve((AlertKind.DROWSY,)),) if AlertKind.DROWSY in context.active else ()
        return (state if state.armed else DrowsyState(True)), events
