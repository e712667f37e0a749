"""Expected windows from the protocol rule tables (`roadgaze.monitor.protocols`), never copied.

A requirement's window is the rule's configured time, widened by what the measurement itself
adds or takes (both constants below, with their reasons). A rule that does not apply (ADDW below
its speed) gives a requirement that no alert comes at all.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from roadgaze.config import MonitorConfig
from roadgaze.conformance.model import Requirement, Segment, segments_timeline
from roadgaze.monitor.protocols import Rule, Trigger, addw, distraction_trigger, euroncap, uses
from roadgaze.monitor.zones import ROAD, ZoneMap

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
PATH_STEP_S = 1.0 / 150.0
"""The step at which `off_road_reached_s` follows the rendered head (ten per 15 fps frame)."""
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


def off_road_reached_s(
    config: MonitorConfig, segments: Sequence[Segment], from_label: str, total_s: float
) -> float | None:
    """When, after the labelled segment starts, the rendered head has been off the road
    `total_s` in all (None: never): its eased path (`roadgaze.synth.timeline`) classified
    through the configured zones (`ZoneMap`, with its hysteresis) every `PATH_STEP_S`.

    The expected time of a glance-counting rule (VATS): a glance's off-road time is not its
    segment's length but the time the head spends beyond the road's edge, turn in and out
    included, which the target's distance from that edge sets (a far target leaves the road early
    in the turn and comes back late). For looks that move the head only: the eyes' share of a
    lizard look passes the gaze's calibration and dead band first."""
    timeline = segments_timeline(segments)
    start_s = 0.0
    for segment in segments:
        if segment.label == from_label:
            break
        start_s += segment.duration_s
    t = np.arange(0.0, timeline.duration_s, PATH_STEP_S)
    yaw, pitch = timeline.pose_at(t)
    zones = ZoneMap.from_config(config)
    zone: str | None = None
    off_s = 0.0
    for t_s, yaw_deg, pitch_deg in zip(t, yaw, pitch, strict=True):
        zone = zones.classify(float(yaw_deg), float(pitch_deg), zone)
        if zone != ROAD:
            off_s += PATH_STEP_S
            if off_s >= total_s - 1e-9:
                return float(t_s) - start_s
    return None


def vats(
    config: MonitorConfig,
    key: str,
    text: str,
    segments: Sequence[Segment],
    nominal_offset_s: float,
    from_label: str = "look",
) -> Requirement:
    """VATS within the distraction warnings' margins (`EARLY_S`, `LATENCY_S`) of when the
    glances' off-road time reaches its threshold: the rendered head's (`off_road_reached_s`) for
    glances of the head alone; for glances that move the eyes, each glance's off-road time taken
    as its length, plus `nominal_offset_s` (the road between the glances).

    The early margin is the long distraction's, not a sharp event's (`TIMER_EARLY_S`): VATS adds
    up the measured edges of five glances, and each edge the pose crosses a frame or two apart
    from the rendered head (more so under a cap or a mask); that four glances stay below the
    threshold is checked on its own (`vats_below_70`)."""
    rule = euroncap.VATS
    threshold_s = rule.value(config)
    if threshold_s is None:
        raise ValueError(f"rule {rule.key}: {rule.config_key} is not set")
    eyes_move = any((s.eye_yaw_deg, s.eye_pitch_deg) != (0.0, 0.0) for s in segments)
    reached_s = None if eyes_move else off_road_reached_s(config, segments, from_label, threshold_s)
    expected_s = threshold_s + nominal_offset_s if reached_s is None else reached_s
    window = (expected_s - EARLY_S, expected_s + LATENCY_S)
    return Requirement(
        key, text, source_of(rule), ("vats",), window, from_label, applies(config, rule)
    )
