"""The frozen records that flow between the stages, one per frame, and the shared vocabulary.

Every per-frame object carries `t_s`, the time on the source's timeline (container time for a
video file, seconds since start for a live camera), so time-based logic counts seconds, not
frames. Image x grows to the right, y downwards. Yaw > 0: head turned to the driver's own left
(ISO 8855), which an unmirrored camera sees as the nose pointing to the image right.

A frame travels as: `Frame` (capture) -> `Detection` of `FaceFeatures` (landmarks) ->
`PoseSample` (pose: yaw, pitch, roll and the smoother) -> `FrameRecord` (the monitor adds its
`Verdict`, with the glance zone, and the `Alert`s raised on that frame). Writers, the annotator
and the Zenoh publisher read the `FrameRecord`; nothing travels beside it. Pitch > 0 = looking
up (the elevation of the face's forward direction).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from types import TracebackType
from typing import Protocol, Self

import numpy as np
import numpy.typing as npt

from roadgaze.eye_records import EyeCalibrationStatus as EyeCalibrationStatus
from roadgaze.eye_records import EyeMeasurement as EyeMeasurement
from roadgaze.eye_records import EyesFeatures as EyesFeatures
from roadgaze.eye_records import EyeStatus as EyeStatus
from roadgaze.eye_records import EyesVerdict as EyesVerdict
from roadgaze.hand_records import Hand as Hand
from roadgaze.hand_records import HandSide as HandSide
from roadgaze.hand_records import PhoneJudgement as PhoneJudgement
from roadgaze.hand_records import PhonePose as PhonePose

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class RecordedDriver:
    """The driver a recording chose on one of its frames (`roadgaze.capture.mcap`)."""

    box_px: tuple[float, float, float, float] | None
    """The driver's face box in the pixels of the recorded image (x_min, y_min, x_max, y_max);
    None: the recording had no driver on this frame."""


@dataclass(frozen=True, slots=True)
class Frame:
    """One image from a frame source."""

    index: int
    """0-based frame number at the source (gaps mean dropped frames on a live source)."""
    t_s: float
    """Seconds on the source timeline; strictly increasing within one source."""
    image: npt.NDArray[np.uint8]
    """BGR, uint8, shape (height, width, 3)."""
    recorded_driver: RecordedDriver | None = None
    """A recording's frame: the driver it chose, followed on replay; None: choose afresh."""


@dataclass(frozen=True, slots=True)
class FaceFeatures:
    """One face as the yaw models see it.

    `x_left_px`, `x_right_px` and `x_center_px` are measured in the roll-removed frame (the image
    rotated about the face so that the eye line is horizontal), in pixels; only their differences
    matter to the yaw models.
    """

    x_left_px: float
    x_right_px: float
    x_center_px: float
    roll_deg: float
    """In-plane head rotation removed before measuring, degrees (positive: counter-clockwise)."""
    box_px: tuple[float, float, float, float]
    """Face bounding box in the original image: x_min, y_min, x_max, y_max."""
    quality: float
    """0..1; low when the face is small, cut by the image edge or poorly fitted."""
    landmarks_px: npt.NDArray[np.float32]
    """(N, 3) landmark x, y in image pixels and z (depth) in the same pixel scale."""
    mediapipe_yaw_deg: float | None = None
    """MediaPipe's own yaw from its facial transformation matrix, project sign convention."""
    mediapipe_pitch_deg: float | None = None
    """MediaPipe's own pitch from the same matrix, > 0 = up."""
    y_top_px: float | None = None
    """Roll-removed y of the top of the face's mid-line (forehead, landmark 10), pixels, y down."""
    y_bottom_px: float | None = None
    """Roll-removed y of the bottom of the mid-line (chin, landmark 152)."""
    y_center_px: float | None = None
    """Roll-removed y of the mid-line's centre (nose tip, landmark 1): the pitch model's input."""
    blendshapes: Mapping[str, float] | None = None
    """MediaPipe's 52 blendshape scores (0..1) by their ARKit names, e.g. `eyeBlinkLeft`; the
    names give the person's own side. None when the landmarker was not asked for them."""
    eye_contrast: tuple[float, float] | None = None
    """Contrast inside the (right, left) eye opening relative to the skin below the eye
    (`roadgaze.landmarks.eyes.eye_contrast`; NaN where the eye is too small to measure); None
    when not measured. Low in both eyes while the lids look open: sunglasses or an occlusion."""
    eye_sharpness: tuple[float, float] | None = None
    """Edge strength around the (right, left) eye relative to the skin below it
    (`roadgaze.landmarks.eye_contrast.eye_sharpness`; NaN where too small); None when not
    measured. Low: motion blur or glare, lids that read closed cannot be judged."""
    eye_lid_share: tuple[float, float] | None = None
    """The share of the edge energy around the (right, left) eye running along it (`roadgaze.
    landmarks.eye_contrast.eye_lid_share`; NaN: too small, flat). Low in both: a fringe."""


@dataclass(frozen=True, slots=True)
class Detection:
    """All faces found in one image and which of them is the driver."""

    faces: tuple[FaceFeatures, ...]
    driver_index: int | None
    """Index into `faces` of the driver, None when no face was found (or none is the driver)."""
    driver_ambiguous: str = ""
    """Why the driver cannot be told from another face in view ('' when it can:
    `roadgaze.landmarks.seat.ambiguity`)."""

    @property
    def driver(self) -> FaceFeatures | None:
        return None if self.driver_index is None else self.faces[self.driver_index]


@dataclass(frozen=True, slots=True)
class SmoothedAngle:
    """The online smoother's estimate of one angle (yaw or pitch) after an update."""

    angle_deg: float
    rate_dps: float
    std_deg: float


@dataclass(frozen=True, slots=True)
class FrameCheck:
    """Cheap statistics of one frame's grey image, sampled every few pixels
    (`roadgaze.monitor.failures.check_frame`): what tells a failed camera from a driver."""

    mean_grey: float
    """Mean grey level, 0-255."""
    std_grey: float
    """Grey-level standard deviation: low for a covered lens or a flat image."""
    saturated_fraction: float
    """Fraction of the sampled pixels at 250 or more."""
    diff_grey: float | None
    """Largest absolute grey difference of a sample from the previous frame's; None for the
    first."""


@dataclass(frozen=True, slots=True)
class PoseSample:
    """What the landmark and pose stages made of one frame: the monitor's input."""

    t_s: float
    frame: int
    face: bool
    yaw_raw_deg: float | None
    """Yaw model output of this frame; None without a face or when the model cannot explain it."""
    yaw_deg: float | None
    """Smoothed yaw; None before the first face or after the track was dropped."""
    yaw_rate_dps: float | None
    yaw_std_deg: float | None
    features: FaceFeatures | None = None
    n_faces: int = 0
    pitch_raw_deg: float | None = None
    """Pitch model output of this frame (> 0 = up); None without a face or a usable pitch."""
    pitch_deg: float | None = None
    """Smoothed pitch; None before the first pitch or after the track was dropped."""
    roll_deg: float | None = None
    """Eye-line roll of this frame (> 0 = counter-clockwise in the image); None without a face."""
    eyes: EyesFeatures | None = None
    """The driver's eyes (roadgaze.landmarks.eyes); None without a face or eye measurement."""
    frame_check: FrameCheck | None = None
    """The image's cheap checks (dark, flat, saturated, repeated); None when not measured."""
    driver_ambiguous: str = ""
    """Why the driver cannot be told from another face in view ('' when it can)."""
    hands: tuple[Hand, ...] | None = None
    """The hands found (the hand stage); None when the stage is off (`[hands] enabled`, or its
    models missing: phone detection is off), () when it ran and found none."""
    phone: PhoneJudgement | None = None
    """The phone judgement of this frame; None when phone detection is off."""


class AlertKind(StrEnum):
    """What an alert is about (definitions: docs/monitor.md)."""

    LONG_DISTRACTION = "long_distraction"
    VATS = "vats"
    DRIVER_UNAVAILABLE = "driver_unavailable"
    MICROSLEEP = "microsleep"
    SLEEP = "sleep"
    DROWSY = "drowsy"
    UNRESPONSIVE = "unresponsive"
    DEGRADED = "degraded"
    """Monitoring impaired: the eyes have been unavailable too long (head pose only)."""
    TEMPORARY_FAILURE = "temporary_failure"
    """The camera cannot judge the driver for now (blocked, black, saturated or frozen frames, no
    judgeable face while moving); `reason` says which. Cleared once recovered."""
    PHONE_USE = "phone_use"
    """A phone in the driver's hand while moving (docs/phone.md); cleared once put down."""
    PERMANENT_FAILURE = "permanent_failure"
    """The service cannot monitor at all (camera gone past the reconnect limit, model unusable)."""
    NON_FUNCTIONAL = "non_functional"
    """The driver's monitoring is not functional: the eyes hidden (dark sunglasses, a brim, a
    fringe) or the face hidden (a hand on the wheel in front of the camera) while the camera
    itself works; `reason` says which. Raised again every `non_functional_repeat_s` while it
    lasts; cleared when it ends."""
    CLEARED = "cleared"


class AlertLevel(StrEnum):
    INFO = "info"
    WARNING = "warning"
    CRITICAL = "critical"


class Gaze(StrEnum):
    """Where the driver looks at one frame."""

    ON_ROAD = "on_road"
    OFF_ROAD = "off_road"
    UNKNOWN = "unknown"
    """No face, and the loss is not explained by a turn away."""


@dataclass(frozen=True, slots=True)
class Alert:
    """One monitor event, stamped on the source timeline."""

    kind: AlertKind
    level: AlertLevel
    t_s: float
    yaw_deg: float | None
    """Head yaw at the event in the driver's frame (the camera's, with the camera in front: see
    `[monitor] camera_mounting`), not relative to the neutral; None without a face."""
    off_road_s: float
    """Length of the current continuous off-road episode (for `cleared`: of the one just ended)."""
    window_off_road_s: float
    """Off-road time within the last `vats_window_s`."""
    unavailable_s: float = 0.0
    """How long the driver has been unavailable (face lost, not turned away)."""
    speed_kmh: float | None = None
    clears: tuple[AlertKind, ...] = ()
    """For `cleared`: the kinds of alert that were active."""
    closure_s: float = 0.0
    """Length of the current eye closure (for the closure alerts)."""
    perclos: float | None = None
    """Fraction of the last `perclos_window_s` with the eyes closed; None until enough is known."""
    reason: str = ""
    """Why the alert fired, in a few words (e.g. 'eyes closed', 'not back on road')."""
    rule: str = ""
    """The protocol rule it fired by (e.g. `addw.distraction.above_50kmh`, docs/monitor.md)."""
    source: str = ""
    """Where that rule comes from (e.g. `EU 2023/2590 Annex I 3.3.2`)."""

    @property
    def label(self) -> str:
        """`kind:level`, e.g. `long_distraction:warning`."""
        return f"{self.kind.value}:{self.level.value}"


@dataclass(frozen=True, slots=True)
class Output:
    """A per-frame output of a monitor behaviour that is not an alert (e.g. a support level for
    another system): `name` is `value` by the rule `rule` (its key) from `source`, since `since_s`
    (source timeline; None: not known)."""

    name: str
    value: str
    rule: str
    source: str = ""
    reason: str = ""
    since_s: float | None = None


@dataclass(frozen=True, slots=True)
class Verdict:
    """The monitor's view after one frame."""

    gaze: Gaze
    on_road: bool | None
    """Road ahead; None when the gaze is unknown (no face, not explained by a turn away)."""
    yaw_deg: float | None
    """The yaw judged (smoothed, else raw) in the driver's frame (the camera mounting applied;
    the camera's with the camera in front); None without a face or a usable yaw."""
    neutral_yaw_deg: float
    """The road-ahead yaw the monitor measures against (fixed or learned), driver's frame."""
    off_road_s: float
    """Length of the current counted (off road and moving) episode."""
    window_off_road_s: float
    """Counted off-road time within the VATS window."""
    unavailable_s: float
    vats_armed: bool
    moving: bool
    """Faster than the minimum speed, or speed unknown (fail-safe)."""
    speed_kmh: float | None
    """The speed used for this frame; None when unknown."""
    active: tuple[AlertKind, ...]
    """Alerts raised and not yet cleared, in the order they were raised."""
    alert_counts: tuple[tuple[str, int], ...] = ()
    """Alerts raised so far by `kind:level`, sorted."""
    zone: str | None = "road"
    """Glance zone (docs/monitor.md): `road`, a configured zone or `away`; None when the gaze is
    unknown. `on_road` is `zone == "road"`."""
    pitch_deg: float | None = None
    """The pitch judged (smoothed, else raw); None without a face or a usable pitch."""
    neutral_pitch_deg: float = 0.0
    """The road-ahead pitch the monitor measures against (fixed or learned)."""
    distraction_s: float = 0.0
    """Time of the current off-road episode spent outside driving-related zones: the
    long-distraction timer."""
    eyes: EyesVerdict = field(default_factory=EyesVerdict)
    """The eyes: open, closed or unavailable, gaze, closure, PERCLOS, blinks."""
    failure: str = ""
    """The temporary failure in force ('' for none), e.g. 'frames frozen 10.0 s'."""
    distraction_warn_s: float | None = None
    """The distraction time that warns at this speed under the configured protocol(s); None
    when none is active."""
    distraction_rule: str = ""
    """The rule giving `distraction_warn_s` (e.g. `euroncap.long_distraction`)."""
    camera_neutral_deg: tuple[float, float] | None = None
    """The road-ahead (yaw, pitch) as the camera sees it, for a camera not in front (the monitor's
    angles are in the driver's frame: roadgaze.mounting); None: the same as the neutral."""
    outputs: tuple[Output, ...] = ()
    """The monitor behaviours' per-frame outputs that are not alerts (roadgaze.monitor.events
    `Publish`), in the order the behaviours ran: `support_forward` and `support_lane`
    (roadgaze.monitor.behaviours.support)."""

    @property
    def eyes_on_road(self) -> bool | None:
        """Looking at the road with the eyes not closed; None when the gaze is unknown."""
        if self.on_road is None:
            return None
        return self.on_road and self.eyes.status is not EyeStatus.CLOSED


@dataclass(frozen=True, slots=True)
class FrameRecord:
    """One frame as every consumer sees it: the pose sample, the verdict, the alerts raised."""

    sample: PoseSample
    verdict: Verdict
    alerts: tuple[Alert, ...] = ()

    @property
    def t_s(self) -> float:
        return self.sample.t_s

    @property
    def frame(self) -> int:
        return self.sample.frame


class LandmarkDetector(Protocol):
    """Finds faces in one image; MediaPipe in production, a small fake in tests.

    `t_s` None means an independent still image (IMAGE mode); a float means one frame of a stream
    (VIDEO mode), and successive calls must pass strictly increasing `t_s`.
    """

    def detect(self, image: npt.NDArray[np.uint8], t_s: float | None = None) -> Detection: ...

    def close(self) -> None: ...


class ClosesOnExit:
    """Mixin for resources: `with resource:` returns it and calls `close()` on the way out."""

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()


class Sink(Protocol):
    """Where a run's results go: every frame record in order (`on_record`), every alert raised
    outside the frame loop (`on_alert`: a camera gone for good, a model that cannot be loaded,
    when no frame comes to carry it) and `close()` once at the end.

    Subclass it to inherit the no-op `on_alert` of a sink with nothing to do with such an alert
    (a progress bar); a sink that keeps, sends or counts alerts implements it. `on_alert` may be
    called from another thread, never during another call to the same run's sinks
    (`roadgaze.pipeline.build_run` holds one lock around both).
    """

    def on_record(self, record: FrameRecord, frame: Frame) -> None: ...

    def on_alert(self, alert: Alert) -> None:
        """An alert raised outside the frame loop; by default nothing to do."""
        del alert

    def close(self) -> None: ...
