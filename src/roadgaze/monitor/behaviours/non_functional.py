"""The non-functional notice (Euro NCAP 2026, DSM general requirements): the service tells the
driver that it cannot monitor them, although the camera itself works. Pure.

Monitoring is not functional while, with a picture the camera check finds sound (not black,
blocked or saturated: those are the camera's failures, `temporary_failure`):
- **the eyes are hidden**: a face is found and faces the road (its head pose in the road zone,
  so a turn away does not count), yet its measured eyes cannot be judged
  (`roadgaze.monitor.eyes`: unavailable: a dark lens or a flat eye opening, strands across
  both eyes (a fringe), a hand found in front of them (a fist gripping the top of the wheel in
  front of the camera, on which MediaPipe still places a face), low landmark quality); a source
  that measures no eyes at all is not this; or
- **the face is hidden**: no face is found and its loss is not explained by a turn away (a hand
  in front of the camera that leaves no face at all).
Timed while moving: held `after` (`non_functional_after_s`), `non_functional` is raised with the
reason, and published at every sample while in force (`non_functional` = `eyes_hidden` or
`face_hidden`: the state message shows it permanently); raised again every `repeat` while the
condition lasts; resolved (a `cleared` alert) once the eyes have been judged again (open or
closed) for `clear`: a glance away with the lenses still on ends nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import run_since
from roadgaze.monitor.events import Event, Publish, Raise, Resolve, Rule
from roadgaze.monitor.zones import ROAD
from roadgaze.types import AlertKind, AlertLevel, EyeStatus, Gaze, Output

__all__ = ["OUTPUT", "NonFunctional", "NonFunctionalState", "hidden", "notice_in"]

OUTPUT = "non_functional"
"""The per-frame output's name (`Verdict.outputs`) while a notice is in force."""


def notice_in(outputs: tuple[Output, ...]) -> str:
    """The notice in force among a frame's outputs, as `value: reason` ('' for none)."""
    shown = next((o for o in outputs if o.name == OUTPUT), None)
    return "" if shown is None else f"{shown.value}: {shown.reason}"


@dataclass(frozen=True, slots=True)
class NonFunctionalState:
    """The notice's timers between samples; replace, never mutate."""

    since_s: float | None = None
    """When the condition started, moving (None: it does not hold)."""
    gone_since_s: float | None = None
    """When the condition ended while a notice is in force (None: it still holds)."""
    told_s: float | None = None
    """When the notice in force was first raised (None: none is in force)."""
    repeated_s: float | None = None
    """When it was last raised."""
    value: str = ""
    """`eyes_hidden` or `face_hidden` ('' for none)."""
    reason: str = ""


def hidden(context: Context) -> tuple[str, str]:
    """What hides the driver at this sample: (`eyes_hidden` | `face_hidden`, why), or ('', '')."""
    if context.frame_issue:
        return "", ""
    if not context.sample.face:
        if context.look.gaze is Gaze.UNKNOWN:
            return "face_hidden", "face hidden: no face found, not turned away"
        return "", ""
    eyes = context.eyes
    if context.sample.eyes is None:  # not measured (a pose-only source): nothing hides them
        return "", ""
    if context.look.zone != ROAD or eyes.status is not EyeStatus.UNAVAILABLE:
        return "", ""
    return "eyes_hidden", f"eyes hidden facing the road ({eyes.reason or 'unavailable'})"


@dataclass(frozen=True, slots=True)
class NonFunctional:
    """`non_functional` by `after`, again every `repeat`, ended after `clear`."""

    after: Rule
    repeat: Rule
    clear: Rule

    def initial(self) -> NonFunctionalState:
        return NonFunctionalState()

    def step(
        self, context: Context, state: NonFunctionalState
    ) -> tuple[NonFunctionalState, tuple[Event, ...]]:
        config, t_s = context.config, context.t_s
        value, reason = hidden(context)
        since_s = run_since(bool(value) and context.moving, state.since_s, t_s)
        if state.told_s is None:
            if since_s is None or not context.held(since_s, self.after.limit(config)):
                return NonFunctionalState(since_s), ()
            why = f"{reason} {t_s - since_s:.1f} s"
            told = NonFunctionalState(since_s, None, t_s, t_s, value, why)
            return told, (
                Raise(AlertKind.NON_FUNCTIONAL, AlertLevel.WARNING, self.after, why),
                Publish(OUTPUT, value, self.after, why, t_s),
            )
        # Ended only by eyes judged again: a glance away with the lenses on ends nothing.
        seen = context.eyes.status is not EyeStatus.UNAVAILABLE
        gone_s = run_since(seen, state.gone_since_s, t_s)
        if gone_s is not None and context.held(gone_s, self.clear.limit(config)):
            ended: tuple[Event, ...] = ()
            if AlertKind.NON_FUNCTIONAL in context.active:
                ended = (Resolve((AlertKind.NON_FUNCTIONAL,)),)
            return NonFunctionalState(since_s), ended
        kept = NonFunctionalState(
            since_s, gone_s, state.told_s, state.repeated_s, state.value, state.reason
        )
        shown = Publish(OUTPUT, state.value, self.after, state.reason, state.told_s)
        if not value or not context.held(state.repeated_s, self.repeat.limit(config)):
            return kept, (shown,)
        why = f"{reason}, still ({t_s - state.told_s:.0f} s since told)"
        again = NonFunctionalState(since_s, None, state.told_s, t_s, state.value, state.reason)
        return again, (Raise(AlertKind.NON_FUNCTIONAL, AlertLevel.WARNING, self.repeat, why), shown)
