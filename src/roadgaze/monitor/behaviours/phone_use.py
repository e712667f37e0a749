"""Phone use: the per-frame phone judgement (`PoseSample.phone`, docs/phone.md) held while
moving. Pure.

`phone_use` (a warning) once the judgement has said "phone in hand" for `phone_use_s` while the
vehicle moves; a judgement that drops out (no phone, or it cannot judge) for less than
`phone_gap_s` does not restart the time, since the hand stage misses a held phone on some
frames. Cleared once the judgement has said "no phone" (or cannot judge) for `phone_gap_s`, or
the vehicle stops. Without phone detection (`[hands]` off or its models missing: the sample's
`phone` is None) nothing is raised: the state says phone detection is off.
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import EPS_S
from roadgaze.monitor.events import Event, Raise, Resolve, Rule
from roadgaze.types import AlertKind, AlertLevel

__all__ = ["PhoneUse", "PhoneUseState"]


@dataclass(frozen=True, slots=True)
class PhoneUseState:
    since_s: float | None = None
    """When the phone was first judged in hand in this run (None: not in hand, or stopped)."""
    last_seen_s: float | None = None
    """The last sample judged "phone in hand" in this run."""
    raised: bool = False
    """`phone_use` raised for this run."""


@dataclass(frozen=True, slots=True)
class PhoneUse:
    """`phone_use` by `time` (how long in hand), runs bridged over gaps shorter than `gap`."""

    time: Rule
    gap: Rule

    def initial(self) -> PhoneUseState:
        return PhoneUseState()

    def step(
        self, context: Context, state: PhoneUseState
    ) -> tuple[PhoneUseState, tuple[Event, ...]]:
        config, t_s, phone = context.config, context.t_s, context.sample.phone
        in_hand = phone is not None and phone.phone_use is True
        last_s = state.last_seen_s
        ended = last_s is not None and t_s - last_s >= self.gap.limit(config) - EPS_S
        events: tuple[Event, ...] = ()
        if not context.moving or ended:
            if AlertKind.PHONE_USE in context.active:
                events = (Resolve((AlertKind.PHONE_USE,)),)
            state = PhoneUseState()
        if in_hand and context.moving:
            start_s = t_s if state.since_s is None else state.since_s
            state = PhoneUseState(start_s, t_s, state.raised)
        since_s = state.since_s
        if state.raised or since_s is None or not context.held(since_s, self.time.limit(config)):
            return state, events
        where = "" if phone is None or phone.pose is None else f" {phone.pose.value}"
        hand = "" if phone is None or phone.hand is None else f", {phone.hand.value} hand"
        why = f"phone{where}{hand} for {t_s - since_s:.1f} s"
        return PhoneUseState(since_s, state.last_seen_s, True), (
            *events,
            Raise(AlertKind.PHONE_USE, AlertLevel.WARNING, self.time, why),
        )
