"""Expected windows from the protocol rule tables (`roadgaze.monitor.protocols`), never copied.

A requirement's window is the rule's configured time, widened by what the measurement itself
adds or takes (both constants below, with their reasons). A rule that does not apply (ADDW below
its speed) gives a requirement that no alert comes at all.
"""

from __future__ import annotations

from roadgaze.config import MonitorConfig
from roadgaze.conformance.model import Requirement
from roadgaze.monitor.protocols import Rule, Trigger, addw, distraction_trigger, euroncap, uses

LATENCY_S = 0.6
"""How much later than the rule's time a warning may come, measured from the start of the look:
the head's turn (the renderer's 0.5 s eased transition) crosses the road zone's edge about a
quarter of a second in, the smoother's outlier gate takes one or two frames to follow a fast
turn, and alerts fire on the first frame at or after their time (1/15 s). The issue's acceptance
(1.5-3.6 s for a 3 s trigger) allows the same 0.6 s."""
EARLY_S = 1.5
"""How much earlier than the protocol's trigger a distraction warning may come before it counts
as early (a warning that early would also come on glances the protocol lets pass)."""
TIMER_EARLY_S = 0.5
"""The same for timers that start at a sharp event (eyes closing, the lens covered, the face
gone, the frames frozen)."""
BELOW_TRIGGER_S = 0.75
"""A glance "just below" a trigger lasts this much less than the trigger time (the turn in and
out adds about as much off-road time as it takes: the glance's off-road time is its duration)."""
DISTRACTION = ("long_distraction",)


def source_of(rule: Rule) -> str:
    return f"{rule.key} ({rule.config_key}): {rule.source}"


def applies(config: MonitorConfig, rule: Rule) -> bool:
    """Whether the configured protocols ask for `rule` (roadgaze's own rules always apply)."""
    return rule.protocol not in ("addw", "euroncap") or uses(config, rule.protocol)


def trigger_at(config: MonitorConfig, speed_kmh: float | None) -> Trigger | None:
    """The distraction trigger the configured protocols ask for at this speed (nominal)."""
    return distraction_trigger(config, speed_kmh, False)


def distraction(
    config: MonitorConfig,
    speed_kmh: float | None,
    key: str,
    text: str,
    *,
    non_nominal: bool = False,
    from_label: str = "look",
) -> Requirement:
    """A distraction warning within the trigger's window at this speed, or none below the
    protocols' speed. `non_nominal`: the window's end may take ADDW's allowance (the service may
    or may not know the conditions are non-nominal; either is conformant)."""
    trigger = trigger_at(config, speed_kmh)
    if trigger is None:
        sources = f"{source_of(addw.ACTIVE)}; {source_of(euroncap.ACTIVE)}"
        return Requirement(key, text, sources, DISTRACTION, None, from_label)
    latest = distraction_trigger(config, speed_kmh, True) if non_nominal else trigger
    latest_s = (latest or trigger).warn_s
    window = (trigger.warn_s - EARLY_S, latest_s + LATENCY_S)
    return Requirement(key, text, source_of(trigger.rule), DISTRACTION, window, from_label)


def no_distraction(
    config: MonitorConfig, speed_kmh: float | None, key: str, text: str, source: str = ""
) -> Requirement:
    """No distraction warning at all (a glance below the trigger, a mirror glance)."""
    trigger = trigger_at(config, speed_kmh)
    rule_source = source or (source_of(trigger.rule) if trigger else source_of(addw.ACTIVE))
    return Requirement(key, text, rule_source, DISTRACTION, None)


def below_trigger_s(config: MonitorConfig, speed_kmh: float | None) -> float:
    """A glance just below the trigger at this speed (seconds)."""
    trigger = trigger_at(config, speed_kmh)
    return (trigger.warn_s if trigger else config.long_distraction_s) - BELOW_TRIGGER_S


def timer(
    config: MonitorConfig,
    rule: Rule,
    kinds: tuple[str, ...],
    key: str,
    text: str,
    from_label: str = "event",
    offset_s: float = 0.0,
) -> Requirement:
    """An alert `rule.value` (+ `offset_s`) seconds after the labelled event, within the
    measurement's margins."""
    value = rule.value(config)
    if value is None:
        raise ValueError(f"rule {rule.key}: {rule.config_key} is not set")
    expected_s = value + offset_s
    window = (expected_s - TIMER_EARLY_S, expected_s + LATENCY_S)
    return Requirement(key, text, source_of(rule), kinds, window, from_label, applies(config, rule))
