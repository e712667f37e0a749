"""Temporary failure (EU 2023/2590 Annex I 3.5.2): the camera cannot judge the driver for now.
Pure; the frame checks are roadgaze.monitor.failures.

Each condition is timed while moving, by its rule's setting: black, blocked or saturated frames
with no judgeable face (`frames`), frozen frames (`frozen`), no judgeable face (`no_face`); and
the eyes degraded while a protocol that needs them (`eyes_needed_by`) is configured (`eyes`).
Raised once with the reason; cleared (a recovery) at the first sample where none holds, moving
or not.
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import run_since
from roadgaze.monitor.events import Event, Raise, Resolve, Rule
from roadgaze.types import AlertKind, AlertLevel

__all__ = ["FailureState", "TemporaryFailure"]

_WORDS = {"black": "frames black", "saturated": "frames saturated"}


@dataclass(frozen=True, slots=True)
class FailureState:
    """The failure timers between samples; replace, never mutate."""

    issue: str = ""
    """The image's issue at the last sample ('' for none)."""
    issue_since_s: float | None = None
    frozen_since_s: float | None = None
    no_face_since_s: float | None = None
    reason: str = ""
    """The temporary failure in force ('' for none)."""


@dataclass(frozen=True, slots=True)
class TemporaryFailure:
    """`temporary_failure` by the rule of the condition that holds (first match in this order)."""

    frames: Rule
    frozen: Rule
    no_face: Rule
    eyes: Rule
    eyes_needed_by: str = "euroncap"

    def initial(self) -> FailureState:
        return FailureState()

    def step(self, context: Context, state: FailureState) -> tuple[FailureState, tuple[Event, ...]]:
        check = context.sample.frame_check
        diff = None if check is None else check.diff_grey
        frozen = diff is not None and diff <= context.config.frozen_max_diff
        no_face = _no_face(context)
        timers = _timers(context, state, frozen, no_face)
        eyes_bad = context.uses(self.eyes_needed_by) and context.eyes.degraded
        reason, rule = self._cause(context, timers, eyes_bad)
        if reason and not state.reason:
            raised = Raise(AlertKind.TEMPORARY_FAILURE, AlertLevel.WARNING, rule, reason)
            return _with(timers, reason), (raised,)
        if reason or not state.reason:
            return _with(timers, reason), ()
        # Recovered only once nothing is wrong any more, moving or not.
        if timers.issue or frozen or no_face or eyes_bad:
            return timers, ()
        ended: tuple[Event, ...] = ()
        if AlertKind.TEMPORARY_FAILURE in context.active:
            ended = (Resolve((AlertKind.TEMPORARY_FAILURE,), recovery=True),)
        return _with(timers, ""), ended

    def _cause(self, context: Context, timers: FailureState, eyes_bad: bool) -> tuple[str, Rule]:
        """The failure that holds at this sample and its rule ('': none)."""
        for since_s, rule, words in (
            (timers.issue_since_s, self.frames, _WORDS.get(timers.issue, "camera blocked")),
            (timers.frozen_since_s, self.frozen, "frames frozen"),
            (timers.no_face_since_s, self.no_face, "no face"),
        ):
            if since_s is not None and context.held(since_s, rule.limit(context.config)):
                return f"{words} {context.t_s - since_s:.1f} s", rule
        if eyes_bad:
            return "eyes unjudgeable", self.eyes
        return "", self.frames


def _no_face(context: Context) -> bool:
    """No judgeable face: none, or one whose yaw the model cannot explain."""
    sample = context.sample
    return not sample.face or (sample.yaw_raw_deg is None and sample.yaw_deg is None)


def _timers(context: Context, state: FailureState, frozen: bool, no_face: bool) -> FailureState:
    """The failure timers after this sample (the reason kept from `state`)."""
    t_s, moving = context.t_s, context.moving
    # A dark or flat image that still shows a judgeable face (night, infrared) is working.
    issue = context.frame_issue if no_face else ""
    issue_since = run_since(moving and bool(issue), state.issue_since_s, t_s)
    if issue != state.issue:
        issue_since = t_s if moving and issue else None
    return FailureState(
        issue=issue,
        issue_since_s=issue_since,
        frozen_since_s=run_since(moving and frozen, state.frozen_since_s, t_s),
        no_face_since_s=run_since(moving and no_face, state.no_face_since_s, t_s),
        reason=state.reason,
    )


def _with(timers: FailureState, reason: str) -> FailureState:
    return (
        timers
        if reason == timers.reason
        else FailureState(
            timers.issue,
            timers.issue_since_s,
            timers.frozen_since_s,
            timers.no_face_since_s,
            reason,
        )
    )
