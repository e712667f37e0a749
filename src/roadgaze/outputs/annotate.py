"""The annotated video: face boundaries, centre line, the eyes, the hands, a yaw gauge, the
numbers, the verdict, the off-road timers, the phone judgement and a banner per active alert.

Boundaries and centre are vertical lines in the roll-removed frame, drawn rotated back into the
image. Everything drawn comes from the frame's `FrameRecord`; the text lines at the bottom are
`PANEL_LINES`, one function each (a new record field is one more entry there). An alert stays on
screen as a banner (kind, level, seconds since raised) for as long as the record's
`verdict.active` lists it; `AlertBoard` remembers when each was raised.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.config import MonitorConfig
from roadgaze.outputs.annotate_eyes import draw_eyes, eyes_line
from roadgaze.outputs.annotate_hands import draw_hands, phone_line
from roadgaze.outputs.video import FOURCC_BY_SUFFIX, open_video_writer
from roadgaze.types import (
    AlertKind,
    AlertLevel,
    ClosesOnExit,
    FaceFeatures,
    Frame,
    FrameRecord,
    PoseSample,
    Sink,
)


class AnnotatedVideoWriter(ClosesOnExit, Sink):
    """Pipeline sink writing each frame with its record drawn on it (codec from the suffix); an
    alert raised outside the loop has no frame to be drawn on (the next frames show it active).

    `monitor`: the monitor's configuration, for the timers' thresholds (optional).
    """

    def __init__(self, path: str | Path, fps: float, monitor: MonitorConfig | None = None) -> None:
        self.path = Path(path)
        self.fps = fps if math.isfinite(fps) and fps > 0 else 30.0
        self.monitor = monitor
        self.board = AlertBoard()
        self._writer: Any = None
        self._size: tuple[int, int] | None = None
        self.frames = 0

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        import cv2

        image = frame.image
        height, width = image.shape[:2]
        if self._writer is None:
            fourcc = FOURCC_BY_SUFFIX.get(self.path.suffix.lower(), "mp4v")
            self._writer = open_video_writer(
                self.path, self.fps, (width, height), fourcc, "annotated video"
            )
            self._size = (width, height)
        canvas = annotate(image, record, self.monitor, self.board.update(record))
        if (width, height) != self._size:
            assert self._size is not None
            canvas = np.asarray(cv2.resize(canvas, self._size), dtype=np.uint8)
        self._writer.write(canvas)
        self.frames += 1

    def close(self) -> None:
        if self._writer is not None:
            self._writer.release()
            self._writer = None


@dataclass(frozen=True, slots=True)
class Banner:
    """One alert on screen."""

    kind: AlertKind
    level: AlertLevel
    elapsed_s: float
    """Seconds since it was raised (for `cleared`: since the clearing)."""

    @property
    def text(self) -> str:
        name = self.kind.value.replace("_", " ").upper()
        return f"{name}  {self.level.value}  {self.elapsed_s:.1f} s"


CLEARED_SHOWN_S = 1.0
"""How long a `cleared` banner stays on screen."""
BANNER_COLOURS_BGR = {
    AlertLevel.WARNING: (0, 130, 255),
    AlertLevel.CRITICAL: (0, 0, 210),
    AlertLevel.INFO: (40, 150, 40),
}


class AlertBoard:
    """The alerts on screen: raised and still active per the record's `verdict.active`, with the
    level they reached and when they were first raised; `cleared` for `CLEARED_SHOWN_S`."""

    def __init__(self) -> None:
        self._raised: dict[AlertKind, tuple[AlertLevel, float]] = {}
        self._cleared_t_s: float | None = None

    def update(self, record: FrameRecord) -> list[Banner]:
        """The banners for this record, in the order the alerts were raised."""
        t_s = record.t_s
        for alert in record.alerts:
            if alert.kind is AlertKind.CLEARED:
                self._cleared_t_s = t_s
                continue
            first_t_s = self._raised.get(alert.kind, (alert.level, alert.t_s))[1]
            self._raised[alert.kind] = (alert.level, first_t_s)
        active = record.verdict.active
        for kind in list(self._raised):
            if kind not in active:
                del self._raised[kind]
        for kind in active:  # active before this writer saw it raised
            self._raised.setdefault(kind, (AlertLevel.WARNING, t_s))
        banners = [
            Banner(kind, level, t_s - raised_t_s)
            for kind, (level, raised_t_s) in self._raised.items()
        ]
        if self._cleared_t_s is not None and t_s - self._cleared_t_s < CLEARED_SHOWN_S:
            banners.append(Banner(AlertKind.CLEARED, AlertLevel.INFO, t_s - self._cleared_t_s))
        return banners


def verdict_text(record: FrameRecord) -> str:
    """One line: the zone (or gaze), the off-road times and the alerts raised on this frame."""
    verdict = record.verdict
    text = f"gaze {verdict.gaze.value}" if verdict.zone is None else f"zone {verdict.zone}"
    if round(verdict.off_road_s, 3):
        text += f"  off road {verdict.off_road_s:.1f} s"
    text += f"  in window {verdict.window_off_road_s:.1f} s"
    if record.alerts:
        text += "  ALERT " + " ".join(alert.label for alert in record.alerts)
    return text


@dataclass(frozen=True, slots=True)
class _RollFrame:
    """Image <-> roll-removed frame: q = R(angle) (p - pivot) + pivot + (offset, 0)."""

    angle_rad: float
    pivot: npt.NDArray[np.float64]
    offset_px: float

    def to_image(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        cos_a, sin_a = math.cos(self.angle_rad), math.sin(self.angle_rad)
        rotation = np.array([[cos_a, -sin_a], [sin_a, cos_a]])
        shifted = points - np.array([self.offset_px, 0.0]) - self.pivot
        result: npt.NDArray[np.float64] = shifted @ rotation + self.pivot
        return result


def _roll_frame(features: FaceFeatures) -> _RollFrame:
    """The roll-removed frame of `features` (see `roadgaze.landmarks.remove_roll`).

    With MediaPipe's 478 landmarks the frame is exact: rotation by the roll about the midpoint of
    the outer eye corners. With other landmark sets (a test's fake detector) it is rotation about
    the box centre, shifted so the rotated landmarks' extent is centred on the boundaries.
    """
    from roadgaze.landmarks.features import LEFT_EYE_OUTER, NUM_LANDMARKS, RIGHT_EYE_OUTER

    roll = math.radians(features.roll_deg)
    points = features.landmarks_px[:, :2].astype(np.float64)
    if len(points) == NUM_LANDMARKS:
        pivot = 0.5 * (points[RIGHT_EYE_OUTER] + points[LEFT_EYE_OUTER])
        return _RollFrame(angle_rad=roll, pivot=pivot, offset_px=0.0)
    x_min, y_min, x_max, y_max = features.box_px
    pivot = np.array([(x_min + x_max) / 2.0, (y_min + y_max) / 2.0])
    if len(points) == 0:
        return _RollFrame(angle_rad=roll, pivot=pivot, offset_px=0.0)
    cos_a, sin_a = math.cos(roll), math.sin(roll)
    rotated_x = (points - pivot) @ np.array([cos_a, -sin_a]) + pivot[0]
    mid_here = (float(rotated_x.min()) + float(rotated_x.max())) / 2.0
    mid_there = (features.x_left_px + features.x_right_px) / 2.0
    return _RollFrame(angle_rad=roll, pivot=pivot, offset_px=mid_there - mid_here)


def face_lines_px(features: FaceFeatures) -> tuple[tuple[str, npt.NDArray[np.float64]], ...]:
    """The face's two boundaries and its centre line in image pixels: (`left`, `right` or
    `centre`, their two ends as a 2x2 array of x, y). Each is vertical in the roll-removed frame
    and reaches 15 % of the face box's height beyond the box at both ends."""
    _, y_min, _, y_max = features.box_px
    margin = 0.15 * (y_max - y_min)
    top, bottom = y_min - margin, y_max + margin
    roll_frame = _roll_frame(features)
    lines = (
        ("left", features.x_left_px),
        ("right", features.x_right_px),
        ("centre", features.x_center_px),
    )
    return tuple(
        (name, roll_frame.to_image(np.array([[x_px, top], [x_px, bottom]]))) for name, x_px in lines
    )


def annotate(
    image: npt.NDArray[np.uint8],
    record: FrameRecord,
    monitor: MonitorConfig | None = None,
    banners: Sequence[Banner] = (),
) -> npt.NDArray[np.uint8]:
    """A copy of `image` with the face geometry, the eyes (a box per eye, the gaze arrow), the
    hands (each one's skeleton and side), a yaw gauge, the `PANEL_LINES` and the banners drawn."""
    import cv2

    canvas = image.copy()
    height, width = canvas.shape[:2]
    scale = max(0.45, min(width, height) / 720.0)
    thickness = max(1, round(2 * scale))
    sample = record.sample
    features = sample.features
    if features is not None:
        x_min, y_min, x_max, y_max = features.box_px
        cv2.rectangle(
            canvas, (round(x_min), round(y_min)), (round(x_max), round(y_max)), (90, 90, 90), 1
        )
        for name, ends in face_lines_px(features):
            (x0, y0), (x1, y1) = ends
            colour = (0, 255, 0) if name == "centre" else (0, 200, 255)
            cv2.line(canvas, (round(x0), round(y0)), (round(x1), round(y1)), colour, thickness)
    draw_eyes(canvas, record, scale)
    draw_hands(canvas, record, scale)
    gauge_width = _draw_gauge(canvas, sample, scale)
    _draw_banners(canvas, banners, scale, thickness, width - gauge_width)
    lines_text = [text for line in PANEL_LINES if (text := line(record, monitor))]
    _draw_text_panel(canvas, lines_text, scale, thickness)
    return canvas


def _draw_banners(
    canvas: npt.NDArray[np.uint8],
    banners: Sequence[Banner],
    scale: float,
    thickness: int,
    right_px: int,
) -> None:
    """One coloured bar per banner at the top left, stacked, left of the gauge."""
    import cv2

    font, font_scale = cv2.FONT_HERSHEY_SIMPLEX, 0.75 * scale
    height_px = round(30 * scale)
    margin = round(8 * scale)
    for row, banner in enumerate(banners):
        top = margin + row * (height_px + margin // 2)
        colour = BANNER_COLOURS_BGR.get(banner.level, (120, 120, 120))
        cv2.rectangle(canvas, (margin, top), (max(margin, right_px - margin), top + height_px),
                      colour, -1)  # fmt: skip
        baseline = top + height_px - round(9 * scale)
        cv2.putText(canvas, banner.text, (2 * margin, baseline), font, font_scale,
                    (255, 255, 255), thickness, cv2.LINE_AA)  # fmt: skip


def _draw_text_panel(
    canvas: npt.NDArray[np.uint8], lines_text: list[str], scale: float, thickness: int
) -> None:
    """White text lines at the bottom left on a darkened panel, readable on any background.

    (A black outline drawn with a thicker pen does not work: in OpenCV 5 the glyph advance grows
    with the thickness, so outline and text drift apart.)
    """
    import cv2

    font, font_scale = cv2.FONT_HERSHEY_SIMPLEX, 0.7 * scale
    line_step = round(26 * scale)
    margin = round(10 * scale)
    text_width = max(cv2.getTextSize(t, font, font_scale, thickness)[0][0] for t in lines_text)
    height, width = canvas.shape[:2]
    top = max(0, height - margin - line_step * len(lines_text))
    right = min(width, 2 * margin + text_width)
    panel = canvas[top:height, 0:right]
    panel[:] = (panel.astype(np.uint16) * 2 // 5).astype(np.uint8)
    y = top + line_step - round(6 * scale)
    for text in lines_text:
        cv2.putText(canvas, text, (margin, y), font, font_scale, (255, 255, 255), thickness,
                    cv2.LINE_AA)  # fmt: skip
        y += line_step


def yaw_line(record: FrameRecord, monitor: MonitorConfig | None) -> str:
    """Smoothed and raw yaw, rate and standard deviation."""
    sample = record.sample

    def number(value: float | None, unit: str) -> str:
        return "--" if value is None else f"{value:+.1f}{unit}"

    return (
        f"yaw {number(sample.yaw_deg, '')} (raw {number(sample.yaw_raw_deg, '')})  "
        f"pitch {number(sample.pitch_deg, '')}  roll {number(sample.roll_deg, '')} deg  "
        f"rate {number(sample.yaw_rate_dps, '')} dps"
    )


def state_line(record: FrameRecord, monitor: MonitorConfig | None) -> str:
    """Time, frame and the faces found."""
    sample = record.sample
    if not sample.face:
        tracking = "predicting" if sample.yaw_deg is not None else "no track"
        return f"t {sample.t_s:.2f} s  frame {sample.frame}  NO FACE ({tracking})"
    faces = f"{sample.n_faces} faces" if sample.n_faces > 1 else "face"
    return f"t {sample.t_s:.2f} s  frame {sample.frame}  {faces}"


def gaze_line(record: FrameRecord, monitor: MonitorConfig | None) -> str:
    """Where the driver looks (the zone), against which neutral, and whether time counts."""
    verdict = record.verdict
    where = (
        f"gaze {verdict.gaze.value.upper()}"
        if verdict.zone is None
        else (f"zone {verdict.zone.upper()}")
    )
    speed = "speed unknown" if verdict.speed_kmh is None else f"{verdict.speed_kmh:.0f} km/h"
    counting = "counting" if verdict.moving else "not counting"
    return (
        f"{where}  neutral {verdict.neutral_yaw_deg:+.1f}/{verdict.neutral_pitch_deg:+.1f} deg  "
        f"{speed} ({counting})"
    )


def timers_line(record: FrameRecord, monitor: MonitorConfig | None) -> str:
    """The off-road timers, against their thresholds when the configuration is known: the
    distraction (long-distraction) timer and the time within the VATS window."""
    verdict = record.verdict

    def of(value_s: float, limit_s: float | None) -> str:
        return f"{value_s:.1f} s" if limit_s is None else f"{value_s:.1f}/{limit_s:g} s"

    # Against the protocol's warning time at this speed when the configuration is known.
    limit_s = None if monitor is None else verdict.distraction_warn_s or monitor.long_distraction_s
    glance = of(verdict.distraction_s, limit_s)
    window = of(verdict.window_off_road_s, None if monitor is None else monitor.vats_threshold_s)
    return f"off road {verdict.off_road_s:.1f} s  distraction {glance}  VATS window {window}"


PanelLine = Callable[[FrameRecord, MonitorConfig | None], str]
PANEL_LINES: tuple[PanelLine, ...] = (
    yaw_line,
    state_line,
    gaze_line,
    timers_line,
    eyes_line,
    phone_line,
)
"""The text lines at the bottom of each frame, top to bottom (an empty one is left out)."""


def _draw_gauge(canvas: npt.NDArray[np.uint8], sample: PoseSample, scale: float) -> int:
    """A half-dial, top right: up is straight ahead, right is yaw > 0 (nose to image right).
    Returns the width it takes from the right edge, in pixels."""
    import cv2

    width = canvas.shape[1]
    radius = round(55 * scale)
    centre = (width - radius - round(12 * scale), radius + round(14 * scale))
    cv2.ellipse(canvas, centre, (radius, radius), 0, 180, 360, (40, 40, 40), -1)
    cv2.ellipse(canvas, centre, (radius, radius), 0, 180, 360, (220, 220, 220), 1)
    for tick_deg in (-90, -60, -30, 0, 30, 60, 90):
        angle = math.radians(tick_deg)
        outer = (
            round(centre[0] + radius * math.sin(angle)),
            round(centre[1] - radius * math.cos(angle)),
        )
        inner = (
            round(centre[0] + 0.85 * radius * math.sin(angle)),
            round(centre[1] - 0.85 * radius * math.cos(angle)),
        )
        cv2.line(canvas, inner, outer, (220, 220, 220), 1)
    needles = ((sample.yaw_raw_deg, (160, 160, 160), 1), (sample.yaw_deg, (0, 255, 255), 3))
    for value, colour, width_px in needles:
        if value is None:
            continue
        angle = math.radians(max(-90.0, min(90.0, value)))
        tip = (
            round(centre[0] + 0.95 * radius * math.sin(angle)),
            round(centre[1] - 0.95 * radius * math.cos(angle)),
        )
        cv2.line(canvas, centre, tip, colour, max(1, round(width_px * scale)), cv2.LINE_AA)
    return 2 * radius + round(12 * scale)
