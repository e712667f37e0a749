"""Drowsiness: `drowsy` at the `level` rule's drowsiness level (`roadgaze.monitor.drowsiness`: a
KSS-like scale from PERCLOS, blinks, yawns and nods). Pure.

Under the `euroncap` protocol it warns only at `drowsiness_min_speed_kmh` (50 km/h) or above; at
an unknown speed it warns and says so (fail-safe); otherwise while moving. Fires once, re-armed
(and cleared) once the level is below the warning level and PERCLOS below `perclos_rearm`.
The `rule` (PERCLOS at `perclos_drowsy`, `roadgaze.drowsy`) is the strongest of its signs and
keeps its settings; the alert names the level's rule, whose support is held to the trip's end.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from roadgaze.monitor.context import Context
from roadgaze.monitor.drowsiness import (
    BASE_LEVEL,
    DrowsinessSigns,
    Level,
    level_of,
    mouth_opening,
    track_signs,
)
from roadgaze.monitor.events import Event, Raise, Resolve, Rule
from roadgaze.types import AlertKind, AlertLevel, EyeStatus

__all__ = ["Drowsy", "DrowsyState"]


@dataclass(frozen=True, slots=True)
class DrowsyState:
    armed: bool = True
    """It may fire."""
    signs: DrowsinessSigns = field(default_factory=DrowsinessSigns)
    """The mouth's and the head's signs (yawns, nods) within the window."""
    level: Level = field(default_factory=lambda: Level(BASE_LEVEL, ()))
    """The level after the last sample."""


@dataclass(frozen=True, slots=True)
class Drowsy:
    """`drowsy` by `level` (its setting: the warning level), gated by `speed` under Euro NCAP;
    `rule` is the PERCLOS sign's (`perclos_drowsy`)."""

    rule: Rule
    level: Rule
    speed: Rule

    def initial(self) -> DrowsyState:
        return DrowsyState()

    def gate(self, context: Context) -> tuple[bool, str]:
        """Whether the level may warn at this sample, and what the reason adds."""
        if not context.moving:
            return False, ""
        if context.speed_kmh is None:
            return True, "; speed unknown"
        if context.uses("euroncap") and context.speed_kmh < self.speed.limit(context.config):
            return False, ""
        return True, ""

    def step(self, context: Context, state: DrowsyState) -> tuple[DrowsyState, tuple[Event, ...]]:
        config, eyes = context.config, context.eyes
        pitch = context.look.pitch_deg if context.sample.face else None
        below = None if pitch is None else context.neutral_pitch_deg - pitch
        opening = mouth_opening(context.sample.features) if context.sample.face else None
        closed = eyes.status is EyeStatus.CLOSED
        signs = track_signs(config, state.signs, context.t_s, opening, below, closed)
        level = level_of(config, eyes, signs)
        drowsy = level.level >= self.level.limit(config)
        active, note = self.gate(context)
        if active and state.armed and drowsy:
            why = f"drowsiness level {level.level}: {level.why}{note}"
            return DrowsyState(False, signs, level), (
                Raise(AlertKind.DROWSY, AlertLevel.WARNING, self.level, why),
            )
        perclos = eyes.verdict.perclos
        rearmed = not drowsy and (perclos is None or perclos < config.perclos_rearm)
        if not state.armed and not rearmed:
            return DrowsyState(False, signs, level), ()
        events = (Resolve((AlertKind.DROWSY,)),) if AlertKind.DROWSY in context.active else ()
        return DrowsyState(True, signs, level), events
