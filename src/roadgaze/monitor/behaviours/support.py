"""Forward and lane support: a level another system acts on, `normal` or `heightened`. Pure.

One behaviour per channel (`support_forward`, `support_lane`), published at every sample with
its rule, reason and since when (`Publish`). Heightened once the driver has not been watching
the road for `support_raise_s` (0: at the first such sample): any zone but the road, driving-task
glances (mirrors, cluster) included, the head past the road's entry bound while the zone is still
the road by hysteresis (`support_road_edge`), the eyes closed, or a phone in use (the `phone_use`
alert in force); and, fail-safe, whenever the service
cannot tell (no face, two faces, the eyes unavailable, no speed, a bad frame). Normal again once
the driver has watched the road, everything known, for `support_clear_s`. An alert whose rule is
an impairment (`Rule.impairment`: drowsy, microsleep, sleep) holds it heightened to the end of
the trip. Runs after every behaviour that raises alerts (it reads their `Raise` events).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import run_since
from roadgaze.monitor.events import Event, Publish, Raise, Rule
from roadgaze.types import AlertKind, EyeStatus, Gaze, Output, Verdict

if TYPE_CHECKING:  # the protocols import the behaviours
    from roadgaze.monitor.protocols.support import SupportRules

__all__ = ["HEIGHTENED", "NORMAL", "Support", "SupportState", "output_name", "support_output"]

NORMAL, HEIGHTENED = "normal", "heightened"


def output_name(channel: str) -> str:
    """The output's name in `Verdict.outputs` (and the record's column): `support_<channel>`."""
    return f"support_{channel}"


def support_output(verdict: Verdict, channel: str) -> Output | None:
    """The channel's output on this verdict (None: the behaviour did not run)."""
    name = output_name(channel)
    return next((output for output in verdict.outputs if output.name == name), None)


@dataclass(frozen=True, slots=True)
class SupportState:
    heightened: bool = True
    """The level; heightened before the driver was first seen watching the road."""
    since_s: float | None = None
    """When the level took its value (None: before the first sample)."""
    watching_since_s: float | None = None
    """When the driver began watching the road with everything known (None: not now)."""
    away_since_s: float | None = None
    """When the driver stopped watching the road, or the service stopped knowing (None: not)."""
    impaired: str = ""
    """The impairment holding support to the end of the trip ('' for none)."""


@dataclass(frozen=True, slots=True)
class Support:
    """`support_<channel>` by `rules`."""

    channel: str
    rules: SupportRules

    def initial(self) -> SupportState:
        return SupportState()

    def step(self, context: Context, state: SupportState) -> tuple[SupportState, tuple[Event, ...]]:
        config, t_s = context.config, context.t_s
        impaired = state.impaired or (_impairment(context) if config.support_hold_impaired else "")
        away = ("" if context.looking else _away(context)) or _past_edge(context) or _phone(context)
        unknown = _unknown(context) if context.looking or not away else ""
        watching = not (away or unknown)
        watching_since = run_since(watching, state.watching_since_s, t_s)
        away_since = run_since(not watching, state.away_since_s, t_s)
        since_s = t_s if state.since_s is None else state.since_s
        rule: Rule
        if impaired:
            heightened, rule, why = True, self.rules.impaired, f"{impaired}: to the end of the trip"
        elif not watching:
            rule = self.rules.off_road if away else self.rules.unknown
            why = away or unknown
            heightened = state.heightened or context.held(away_since, rule.limit(config))
        else:
            clear_s = self.rules.clear.limit(config)
            heightened = state.heightened and not context.held(watching_since, clear_s)
            watched_s = t_s - (t_s if watching_since is None else watching_since)
            rule = self.rules.clear
            why = (
                f"watching the road {watched_s:.1f} s of {clear_s:g}"
                if heightened
                else f"watching the road {clear_s:g} s"
            )
        if heightened != state.heightened:
            since_s = t_s
        value = HEIGHTENED if heightened else NORMAL
        new = SupportState(heightened, since_s, watching_since, away_since, impaired)
        return new, (Publish(output_name(self.channel), value, rule, why, since_s),)


def _impairment(context: Context) -> str:
    """The first alert raised at this sample by a rule marked as an impairment ('' for none)."""
    for event in context.events:
        if isinstance(event, Raise) and event.rule.impairment:
            return f"{event.kind.value} ({event.rule.key})"
    return ""


def _phone(context: Context) -> str:
    """A phone in use, by the `phone_use` alert in force or raised now ('' for none): the eyes of
    a driver with a phone held up may stay near the road, the mind is not on it. The alert, not
    the per-frame judgement, so a frame's false judgement does not raise support."""
    raised = any(
        isinstance(event, Raise) and event.kind is AlertKind.PHONE_USE for event in context.events
    )
    return "phone in use" if raised or AlertKind.PHONE_USE in context.active else ""


def _unknown(context: Context) -> str:
    """Why the service cannot tell whether the driver watches the road ('' when it can)."""
    sample = context.sample
    if not sample.face:
        return "no face"
    if sample.driver_ambiguous:
        return f"two faces: {sample.driver_ambiguous}"
    if context.frame_issue:
        return f"frames {context.frame_issue}"
    if context.eyes.status is EyeStatus.UNAVAILABLE:
        reason = context.eyes.verdict.reason
        return f"eyes unavailable ({reason})" if reason else "eyes unavailable"
    if context.speed_kmh is None:
        return "speed unknown"
    return ""


def _away(context: Context) -> str:
    """Where the driver looks instead of the road ('' when not known to look away)."""
    look = context.look
    if look.gaze is Gaze.OFF_ROAD:
        where = f"{'eyes' if look.by_eyes else 'head'} in {look.zone}"
        return where if context.sample.face else f"face out of view, last seen in {look.zone}"
    if look.gaze is Gaze.ON_ROAD and context.eyes.status is EyeStatus.CLOSED:
        return "eyes closed"
    return ""


def _past_edge(context: Context) -> str:
    """The head past the road's entry bound, the zone still the road by hysteresis ('' when
    not, or `support_road_edge` is off)."""
    if context.config.support_road_edge and context.look.past_road_edge:
        return "head past the road's edge"
    return ""
