"""The conformance suite's data: segments of a scripted drive, scenarios, requirements, results.

A `Scenario` is a drive scripted in the driver's frame (`Segment`s of head pose, eyes and what
the camera delivers), at one vehicle speed (None: no speed track, unknown), seen by a camera at
one mounting preset. Each of its `Requirement`s names the alert kinds it is about, the segment
whose start is time zero (`from_label`: "the look starts") and the window in which the first of
those alerts must come, or None when none may come at all. The window is computed from the
protocol rule tables (`roadgaze.conformance.expect`), never written down here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

from roadgaze.synth.timeline import Keyframe, Timeline

CameraState = Literal["face", "no_face", "covered", "frozen"]
"""What the camera delivers during a segment: the driver, the cabin without a face, a covered
lens, or the last frame again (frozen)."""


@dataclass(frozen=True, slots=True)
class Segment:
    """A stretch of the drive: the head turns to `yaw_deg`/`pitch_deg` (driver's frame, degrees;
    over the timeline's transition at the start) and holds; the eyes turn (eye-in-head degrees)
    and open to `openness`; the mouth opens to `mouth_open` (a yawn); `label` marks the segment
    so a requirement can start its clock."""

    duration_s: float
    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    eye_yaw_deg: float = 0.0
    eye_pitch_deg: float = 0.0
    openness: float = 1.0
    camera: CameraState = "face"
    label: str = ""
    lean_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """The head moved from its driving place (driver's frame: forward, left, up; metres), over
    the same transition as the turn: a body lean."""
    mouth_open: float = 0.0
    """The jaw's opening held in the segment (a fraction of a wide yawn,
    `roadgaze.synth.mouth`), eased in and out over `MOUTH_RAMP_S` at its ends."""


@dataclass(frozen=True, slots=True)
class Requirement:
    """One checked requirement of a scenario.

    `kinds` are alert kinds (`AlertKind` values); the first alert of any of them, measured from
    the start of the segment labelled `from_label`, must fall within `window_s` (seconds,
    inclusive); with `window_s` None no such alert may be raised anywhere in the drive. A
    requirement of a protocol that is not configured does not apply: it is measured and shown,
    not judged."""

    key: str
    text: str
    source: str
    kinds: tuple[str, ...]
    window_s: tuple[float, float] | None
    from_label: str = "look"
    applies: bool = True
    held_until: str = ""
    """For a support requirement (`kinds` are support outputs, `support_forward` ...): the
    segment label until whose start the output must stay heightened once raised (`end`: to
    the end of the drive); '' for an alert requirement. A support requirement measures the
    first change to `heightened` at or after the start, and passes only when the output was
    `normal` just before the start (roadgaze.conformance.support)."""
    from_alert: str = ""
    """For a support requirement that follows a warning (drowsiness): its clock starts at the
    first alert of this kind instead of `from_label` and is held to the end of the drive; the
    output may already be heightened then (raised earlier by the same driver's closures); no
    such alert: not met."""


@dataclass(frozen=True, slots=True)
class Scenario:
    """A scripted drive and what it must (not) raise."""

    name: str
    what: str
    segments: tuple[Segment, ...]
    speed_kmh: float | None
    """The vehicle speed written to the scenario's speed track; None: no track (unknown)."""
    requirements: tuple[Requirement, ...]
    mounting: str = "front"
    conditions: tuple[str, ...] = ()
    """What the driver wears and the camera meets, from the first frame: names of
    `roadgaze.synth.outfit.CONDITIONS` (`dark_sunglasses`, `night`, `mask`, `talking`, ...)."""
    worn_from: str = ""
    """The label of the segment from whose start the worn conditions (and the hand on the
    wheel) are put on ('': from the first frame); `night` and `talking` hold throughout."""
    worn_until: str = ""
    """The label of the segment from whose start the worn conditions are taken off again ('':
    worn to the end): a phone put down."""
    fast: bool = False
    """Part of the `--fast` subset (the test suite's)."""
    zoom: float = 1.0
    """The camera's picture scaled about its centre (< 1: a wider lens, the face smaller, so a
    leaning head stays in view)."""

    @property
    def sunglasses(self) -> bool:
        """The driver wears dark sunglasses."""
        return "dark_sunglasses" in self.conditions

    @property
    def duration_s(self) -> float:
        return sum(segment.duration_s for segment in self.segments)

    def start_of(self, label: str) -> float:
        """When the first segment labelled `label` starts (seconds); KeyError when none is."""
        start = 0.0
        for segment in self.segments:
            if segment.label == label:
                return start
            start += segment.duration_s
        raise KeyError(f"scenario {self.name} has no segment labelled {label!r}")


@dataclass(frozen=True, slots=True)
class Outcome:
    """One requirement checked on one scenario's run."""

    scenario: str
    requirement: Requirement
    measured_s: float | None
    """When the first alert of the requirement's kinds came, from the labelled start (None:
    none came)."""
    passed: bool
    alerts: tuple[str, ...] = field(default=())
    """Every alert of the drive as `kind:level@t` (for the report's detail)."""

    @property
    def result(self) -> str:
        """PASS, FAIL, or N/A for a requirement that does not apply."""
        if not self.requirement.applies:
            return "N/A"
        return "PASS" if self.passed else "FAIL"

    def to_json(self) -> dict[str, Any]:
        window = self.requirement.window_s
        return {
            "scenario": self.scenario,
            "requirement": self.requirement.key,
            "text": self.requirement.text,
            "source": self.requirement.source,
            "kinds": list(self.requirement.kinds),
            "expected_window_s": None if window is None else [round(w, 3) for w in window],
            "measured_s": None if self.measured_s is None else round(self.measured_s, 3),
            "result": self.result,
            "alerts": list(self.alerts),
        }


def judge(
    requirement: Requirement, start_s: float, alerts: list[tuple[str, str, float]]
) -> tuple[float | None, bool]:
    """(measured, passed) for `alerts` (kind, level, t_s) against `requirement`, whose clock
    starts at `start_s`; a requirement that does not apply passes."""
    times = [t_s for kind, _, t_s in alerts if kind in requirement.kinds]
    measured = min(times) - start_s if times else None
    window = requirement.window_s
    if not requirement.applies:
        return measured, True
    if window is None:
        return measured, measured is None
    if measured is None or not math.isfinite(measured):
        return measured, False
    return measured, window[0] - 1e-9 <= measured <= window[1] + 1e-9


def segments_timeline(segments: Sequence[Segment]) -> Timeline:
    """The segments' head and eye poses (driver's frame) as a synth timeline: what is rendered,
    and what the expected windows follow (`roadgaze.conformance.expect.off_road_reached_s`)."""
    return Timeline(
        tuple(
            Keyframe(
                s.yaw_deg, s.pitch_deg, s.duration_s, s.eye_yaw_deg, s.eye_pitch_deg, s.openness
            )
            for s in segments
        )
    )
