"""The eye records carried inside the per-frame records: one eye, both eyes, the monitor's view.

`EyesFeatures` is what the landmark stage measures of the driver's eyes (roadgaze.landmarks.eyes),
`EyesVerdict` what the monitor makes of them (roadgaze.monitor.eyes). Angles are degrees in the
project convention: yaw > 0 toward the person's own left, pitch > 0 up. "Right" and "left" are
the person's own sides (MediaPipe's iris 468-472 and eyeBlinkRight are the person's right eye,
on the image's left for an unmirrored camera).

Part of the per-frame vocabulary: `roadgaze.types` re-exports these names (import them from
there) and `Verdict.eyes` builds an `EyesVerdict` at run time. The file sits beside types.py, not
in a stage folder, because every stage folder's `__init__` imports `roadgaze.types`: a home in
one of them makes `import roadgaze.types` circular.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum


class EyeStatus(StrEnum):
    """What the monitor makes of the eyes at one frame."""

    OPEN = "open"
    CLOSED = "closed"
    UNAVAILABLE = "unavailable"
    """Not measurable: no face, a turned head, sunglasses, eyes too small or low confidence."""


class EyeCalibrationStatus(StrEnum):
    """How far the driver's resting eye direction is learned (roadgaze.monitor.eye_calibration):
    the eyes may move the gaze only once it is `calibrated`."""

    NONE = "none"
    """Nothing learned yet: the gaze is the head pose."""
    LEARNING = "learning"
    """Learning from open-eyed samples on the road: the gaze is still the head pose."""
    CALIBRATED = "calibrated"
    """Learned: eye movements beyond the driver's measured noise move the gaze."""


@dataclass(frozen=True, slots=True)
class EyeMeasurement:
    """One eye at one frame (`side` is the person's own: "right" or "left").

    Angles are the eye's direction relative to the head, degrees, in the project convention (yaw
    > 0 toward the person's own left, pitch > 0 up). `openness` is the mean lid aperture divided
    by W, the width of the wider eye in the image (about 0.3 open, 0.1 closed).
    """

    side: str
    width_px: float
    openness: float
    gaze_usable: bool
    """The eye gives a direction (not the far eye of a turned head, not too small, ...)."""
    closure_usable: bool
    """The eye's openness can be judged."""
    reason: str = ""
    """Why the eye is not usable ('' when it is), e.g. 'far eye', 'eyes too small'."""
    yaw_deg: float | None = None
    pitch_deg: float | None = None
    blink: float | None = None
    """MediaPipe's eyeBlink score of this eye (0..1)."""
    look_down: float | None = None
    """eyeLookDown - eyeLookUp of this eye (-1..1; > 0 looking down)."""
    iris_yaw_deg: float | None = None
    """The iris (eyeball-centre) model's direction, kept for diagnostics."""
    iris_pitch_deg: float | None = None
    contrast: float | None = None


@dataclass(frozen=True, slots=True)
class EyesFeatures:
    """Both eyes of the driver at one frame, and the combined values the monitor uses."""

    right: EyeMeasurement
    left: EyeMeasurement
    method: str
    """Where the eye direction comes from: 'blendshapes' or 'iris'."""
    scale_px: float
    """W, the wider eye's width in the image (pixels)."""
    reason: str = ""
    """Why the eyes are unavailable for gaze ('' when at least one eye gives a direction)."""
    occluded: bool = False
    """The image check says the eyes cannot be seen (sunglasses, glare, a hand)."""
    occluded_by: str = ""
    """What hides them, when `occluded` and not a flat opening (a dark lens): `strands` (edges
    across both eyes: a hair fringe) or `hand` (a hand found in front of both eyes)."""
    blurred: bool = False
    """The image check finds no sharp edges around the measured eyes (motion blur, glare): lids
    that read closed cannot be judged."""

    @property
    def gaze_available(self) -> bool:
        return self.right.gaze_usable or self.left.gaze_usable

    @property
    def closure_available(self) -> bool:
        return self.right.closure_usable or self.left.closure_usable

    def _used(self, for_closure: bool) -> tuple[EyeMeasurement, ...]:
        eyes = (self.right, self.left)
        return tuple(e for e in eyes if (e.closure_usable if for_closure else e.gaze_usable))

    @property
    def openness(self) -> float | None:
        """The widest judged eye's openness (both eyes close together; a squint or a hidden
        far eye must not read as a closure); None when no eye can be judged."""
        used = self._used(for_closure=True)
        return max(e.openness for e in used) if used else None

    @property
    def blink(self) -> float | None:
        """The lowest eyeBlink score of the judged eyes; None without blendshapes."""
        scores = [e.blink for e in self._used(for_closure=True) if e.blink is not None]
        return min(scores) if scores else None

    @property
    def look_down(self) -> float | None:
        scores = [e.look_down for e in self._used(for_closure=True) if e.look_down is not None]
        return sum(scores) / len(scores) if scores else None

    @property
    def yaw_deg(self) -> float | None:
        """Eye-in-head yaw: the mean of the eyes that give a direction."""
        values = [e.yaw_deg for e in self._used(for_closure=False) if e.yaw_deg is not None]
        return sum(values) / len(values) if values else None

    @property
    def pitch_deg(self) -> float | None:
        values = [e.pitch_deg for e in self._used(for_closure=False) if e.pitch_deg is not None]
        return sum(values) / len(values) if values else None


@dataclass(frozen=True, slots=True)
class EyesVerdict:
    """The monitor's view of the eyes after one frame (definitions: docs/monitor.md)."""

    status: EyeStatus = EyeStatus.UNAVAILABLE
    reason: str = ""
    """Why the eyes are unavailable, or 'looking down' / 'looking aside' for narrowed lids read as
    a glance (the head lowered; the iris read turned sideways)."""
    openness: float | None = None
    """The judged openness (lid aperture / eye width); None when not judged."""
    eye_yaw_deg: float | None = None
    """Eye-in-head direction (both eyes combined), degrees; None when the eyes give none."""
    eye_pitch_deg: float | None = None
    gaze_yaw_deg: float | None = None
    """Where the driver looks: head yaw + eye yaw beyond the deadband (eyes), or the head yaw
    alone (head); None without either."""
    gaze_pitch_deg: float | None = None
    gaze_source: str = "none"
    """'eyes', 'head' (eyes unavailable or closed: head pose fallback) or 'none'."""
    closure_s: float = 0.0
    """Length of the current closure (0 when the eyes are not closed)."""
    perclos: float | None = None
    """Closed fraction of the judged time in the PERCLOS window; None until enough is judged."""
    blinks: int = 0
    """Blinks (closures shorter than the microsleep time) within the PERCLOS window."""
    long_blinks: int = 0
    last_blink_s: float | None = None
    """Duration of the most recent blink in the window."""
    unavailable_s: float = 0.0
    """How long the eyes have been unavailable while moving."""
    degraded: bool = False
    """Monitoring impaired: eyes unavailable for `degraded_after_s` (head pose only)."""
    calibration: EyeCalibrationStatus = EyeCalibrationStatus.NONE
    """How far the driver's resting eye direction is learned; the eyes move the gaze only once
    `calibrated`."""
