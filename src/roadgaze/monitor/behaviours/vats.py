"""Visual attention time sharing (Euro NCAP's short distraction): off-road time within the last
`vats_window_s` reaches the rule's threshold. Pure.

Judged at every counted off-road sample and at the sample that ends an episode (an episode that
ends exactly at the threshold counts when the driver looks back). Fires once, then re-armed
after `vats_rearm_s` continuously on the road with a face; cleared by `clearing`.
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import EPS_S
from roadgaze.monitor.events import Event, Raise, Rule
from roadgaze.types import AlertKind, AlertLevel

__all__ = ["Vats", "VatsState"]


@dataclass(frozen=True, slots=True)
class VatsState:
    armed: bool = True
    """It may fire (the verdict's `vats_armed`)."""


@dataclass(frozen=True, slots=True)
class Vats:
    """`vats` by `rule` (its threshold), re-armed by `rearm` (its time on the road)."""

    rule: Rule
    rearm: Rule

    def initial(self) -> VatsState:
        return VatsState()

    def step(self, context: Context, state: VatsState) -> tuple[VatsState, tuple[Event, ...]]:
        config, episode = context.config, context.episode
        armed = state.armed or context.held(episode.on_since_s, self.rearm.limit(config))
        due = episode.off_road or (context.episode_ended and context.moving)
        window_s = episode.window_s(context.t_s, config.vats_window_s)
        if due and armed and window_s >= self.rule.limit(config) - EPS_S:
            return VatsState(False), (Raise(AlertKind.VATS, AlertLevel.WARNING, self.rule),)
        return (state if armed is state.armed else VatsState(armed)), ()
