"""Forward and lane support in the conformance suite: the support a drive's frames carried, the
requirements on it and how they are judged.

The drive's sink logs each change of the support outputs (`support_forward`, `support_lane`:
roadgaze.monitor.behaviours.support) beside the alerts, as (output, level, t_s). A support
requirement is met when the output was `normal` just before its clock starts (so the raise is
the glance's, not left over), turns `heightened` within `support_raise_max_s` of the start (the
look's first frame: the head's turn is inside that time), and stays heightened until the
segment it names starts (`end`: to the end of the drive, for an impairment).
"""

from __future__ import annotations

from dataclasses import replace

from roadgaze.config import MonitorConfig
from roadgaze.config.support import SUPPORT_RAISE_MAX_S
from roadgaze.conformance.driving_task import DRIVING_TASK_ROWS, driving_task_scenarios
from roadgaze.conformance.locations import PHONE_LOOKS, look_name
from roadgaze.conformance.model import Requirement, Scenario, Segment
from roadgaze.monitor.behaviours.support import HEIGHTENED, NORMAL, output_name
from roadgaze.monitor.protocols.support import CHANNELS, support_rules
from roadgaze.types import FrameRecord, Verdict

__all__ = [
    "AFTER_WARNING",
    "SHEET_ROWS",
    "SUPPORTED",
    "SUPPORT_OUTPUTS",
    "SupportLog",
    "judge_support",
    "support_requirements",
    "support_scenarios",
    "with_support",
]

SUPPORT_OUTPUTS = frozenset(output_name(channel) for channel in CHANNELS)
"""The outputs logged beside the alerts."""

SUPPORTED: dict[str, tuple[str, str]] = {
    "lap_70": ("look", "back"),
    "side_left_70": ("look", "back"),
    "side_right_70": ("look", "back"),
    "centre_stack_70": ("look", "back"),
    "mirror_left_70": ("look", "back"),
    "mirror_right_70": ("look", "back"),
    "vats_70": ("look", "glance1"),
    "microsleep_70": ("event", "end"),
    "sleep_70": ("event", "end"),
    # The gaze locations (roadgaze.conformance.locations): owl, lizard and body lean.
    "owl_passenger_footwell_70": ("look", "back"),
    "owl_passenger_face_70": ("look", "back"),
    "lizard_infotainment_70": ("look", "back"),
    "lizard_glovebox_70": ("look", "back"),
    "lean_passenger_footwell_70": ("look", "back"),
    "lean_rear_passenger_70": ("look", "back"),
    "vats_owl_passenger_footwell_70": ("look", "glance1"),
    "vats_lizard_infotainment_70": ("look", "glance1"),
    "vats_lizard_passenger_footwell_70": ("look", "glance1"),
    "vats_lizard_multi_target_70": ("look", "glance1"),
} | {look_name(*look): ("look", "back") for look in PHONE_LOOKS.values()}
"""Scenarios of the matrix whose support is judged: (the label its clock starts at, the label
until which support must hold; `end`: the end of the drive, after an impairment). The looks at
a phone (roadgaze.conformance.locations.PHONE_LOOKS) too."""

AFTER_WARNING: dict[str, str] = {"drowsy_70": "drowsy"}
"""Scenarios whose support follows a warning, not a look: it must be heightened within the
bound of the first alert of this kind and held to the end of the trip (drowsiness: the
driver's long blinks may have raised it before, as closures). Their requirements name the
impaired part's start, the segment labelled `event`."""


class SupportLog:
    """Each change of the frame records' support outputs, as (output, level, t_s)."""

    def __init__(self, changes: list[tuple[str, str, float]] | None = None) -> None:
        self.changes: list[tuple[str, str, float]] = [] if changes is None else changes
        self._last: dict[str, str] = {}

    def on_verdict(self, verdict: Verdict, t_s: float) -> None:
        for output in verdict.outputs:
            if output.name.startswith("support_") and self._last.get(output.name) != output.value:
                self._last[output.name] = output.value
                self.changes.append((output.name, output.value, t_s))

    def on_record(self, record: FrameRecord) -> None:
        self.on_verdict(record.verdict, record.t_s)


def support_requirements(
    config: MonitorConfig, scenario: str, from_label: str, held_until: str, from_alert: str = ""
) -> tuple[Requirement, ...]:
    """Forward and lane support raised within the bound of the labelled start (or of the first
    `from_alert` alert), held until `held_until`."""
    requirements = []
    for channel in CHANNELS:
        rules = support_rules(channel)
        rule = rules.impaired if held_until == "end" else rules.off_road
        held = "to the end of the trip" if held_until == "end" else f"until {held_until}"
        since = f" of the {from_alert} warning" if from_alert else ""
        text = f"{channel} support heightened within {SUPPORT_RAISE_MAX_S:g} s{since}, held {held}"
        source = f"{rule.key}: {rule.source}"
        window = (0.0, SUPPORT_RAISE_MAX_S)
        requirements.append(
            Requirement(
                f"{scenario}.{output_name(channel)}",
                text,
                source,
                (output_name(channel),),
                window,
                from_label,
                held_until=held_until,
                from_alert=from_alert,
            )
        )
    return tuple(requirements)


SHEET_ROWS: dict[int, str] = {
    17: "side_{driver}_70",
    18: "centre_stack_70",
    19: "owl_passenger_footwell_70",
    20: "owl_passenger_face_70",
    21: "side_{passenger}_70",
    22: "lizard_infotainment_70",
    23: "lizard_glovebox_70",
    24: "lean_passenger_footwell_70",
    25: "lean_rear_passenger_70",
    26: "mirror_{driver}_4s_70",
    28: "mirror_{passenger}_4s_70",
    35: "vats_70",
    36: "vats_owl_passenger_footwell_70",
    37: "vats_lizard_infotainment_70",
    38: "vats_lizard_passenger_footwell_70",
    39: "mirror_{driver}_70",
    41: "mirror_{passenger}_70",
    47: "vats_lizard_multi_target_70",
    **{row: look_name(*look) for row, look in PHONE_LOOKS.items()},
    62: "phone_wheel_70",
    63: "phone_windscreen_70",
    64: "phone_cluster_70",
    68: "drowsy_70",
    70: "microsleep_70",
    71: "sleep_70",
} | {row: look.scenario for row, look in DRIVING_TASK_ROWS.items()}
"""The dossier's rows whose support cells are judged, each by one scenario's `support_forward`
and `support_lane` (`{driver}` and `{passenger}`: the side by the cabin; the driving-task looks
of `roadgaze.conformance.driving_task` included)."""


def with_support(config: MonitorConfig, scenarios: list[Scenario]) -> list[Scenario]:
    """`scenarios` with the support requirements of those in `SUPPORTED` added."""
    added = []
    for scenario in scenarios:
        warning = AFTER_WARNING.get(scenario.name, "")
        labels = SUPPORTED.get(scenario.name) or (("event", "end") if warning else None)
        if labels is not None:
            extra = support_requirements(config, scenario.name, *labels, warning)
            scenario = replace(scenario, requirements=(*scenario.requirements, *extra))
        added.append(scenario)
    return added


def support_scenarios(config: MonitorConfig) -> list[Scenario]:
    """A 4 s look at each side mirror at 70 km/h: a long driving-task glance, support only; then
    the other driving-task looks (`roadgaze.conformance.driving_task`)."""
    from roadgaze.conformance.matrix import FAST_KMH, LOOK_S, ahead, back, look, zone_target

    scenarios = []
    for side in ("left", "right"):
        name = f"mirror_{side}_4s_70"
        text = f"{LOOK_S:g} s {side} mirror look at {FAST_KMH:g} km/h: forward and lane support"
        target = zone_target(config, f"{side}_mirror")
        segments: tuple[Segment, ...] = (ahead(), look(target, LOOK_S), back())
        requirements = support_requirements(config, name, "look", "back")
        scenarios.append(Scenario(name, text, segments, FAST_KMH, requirements))
    return [*scenarios, *driving_task_scenarios(config)]


def judge_support(
    requirement: Requirement,
    start_s: float,
    until_s: float,
    changes: list[tuple[str, str, float]],
    from_normal: bool = True,
) -> tuple[float | None, bool]:
    """(measured, passed): when the output turned heightened after `start_s` (0 when it already
    was), and whether it did so in the window and held until `until_s`. With `from_normal`
    (a glance's support) an output already heightened at the start fails: the raise was not
    the scenario's; without (support that follows a warning) it counts from the start."""
    mine = [(level, t_s) for name, level, t_s in changes if name in requirement.kinds]
    before = [level for level, t_s in mine if t_s < start_s - 1e-9]
    was_normal = bool(before) and before[-1] == NORMAL
    raised = [t_s for level, t_s in mine if level == HEIGHTENED and t_s >= start_s - 1e-9]
    if not from_normal and before and before[-1] == HEIGHTENED:
        raised = [start_s]
    if not raised:
        return (0.0 if not was_normal and before else None), False
    measured = raised[0] - start_s
    dropped = [t_s for level, t_s in mine if level == NORMAL and raised[0] < t_s < until_s - 1e-9]
    window = requirement.window_s or (0.0, SUPPORT_RAISE_MAX_S)
    in_window = window[0] - 1e-9 <= measured <= window[1] + 1e-9
    return measured, (was_normal or not from_normal) and in_window and not dropped
