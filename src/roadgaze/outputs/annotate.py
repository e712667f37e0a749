"""The annotated video: face boundaries, centre line, a yaw gauge, the numbers and the verdict.

Boundaries and centre are vertical lines in the roll-removed frame, drawn rotated back into the
image. Everything drawn comes from the frame's `FrameRecord`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.outputs.annotate_eyes import draw_eyes, eyes_text
from roadgaze.outputs.video import FOURCC_BY_SUFFIX, open_video_writer
from roadgaze.types import ClosesOnExit, FaceFeatures, Frame, FrameRecord, PoseSample


class AnnotatedVideoWriter(ClosesOnExit):
    """Pipeline sink writing each frame with its record drawn on it (codec from the suffix)."""

    def __init__(self, path: str | Path, fps: float) -> None:
        self.path = Path(path)
        self.fps = fps if math.isfinite(fps) and fps > 0 else 30.0
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
        canvas = annotate(image, record)
        if (width, height) != self._size:
            assert self._size is not None
            canvas = np.asarray(cv2.resize(canvas, self._size), dtype=np.uint8)
        self._writer.write(canvas)
        self.frames += 1

    def close(self) -> None:
        if self._writer is not None:
            self._writer.release()
            self._writer = None


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


def annotate(image: npt.NDArray[np.uint8], record: FrameRecord) -> npt.NDArray[np.uint8]:
    """A copy of `image` with the face geometry, a yaw gauge, the numbers and verdict drawn."""
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
        margin = 0.15 * (y_max - y_min)
        top, bottom = y_min - margin, y_max + margin
        roll_frame = _roll_frame(features)
        lines = (
            (features.x_left_px, (0, 200, 255)),
            (features.x_right_px, (0, 200, 255)),
            (features.x_center_px, (0, 255, 0)),
        )
        for x_px, colour in lines:
            ends = roll_frame.to_image(np.array([[x_px, top], [x_px, bottom]]))
            (x0, y0), (x1, y1) = ends
            cv2.line(canvas, (round(x0), round(y0)), (round(x1), round(y1)), colour, thickness)
    draw_eyes(canvas, record, scale)
    _draw_gauge(canvas, sample, scale)
    lines_text = [_yaw_text(sample), _state_text(sample), eyes_text(record), verdict_text(record)]
    _draw_text_panel(canvas, lines_text, scale, thickness)
    return canvas


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


def _yaw_text(sample: PoseSample) -> str:
    def number(value: float | None, unit: str) -> str:
        return "--" if value is None else f"{value:+.1f}{unit}"

    return (
        f"yaw {number(sample.yaw_deg, '')} (raw {number(sample.yaw_raw_deg, '')})  "
        f"pitch {number(sample.pitch_deg, '')}  roll {number(sample.roll_deg, '')} deg  "
        f"rate {number(sample.yaw_rate_dps, '')} dps"
    )


def _state_text(sample: PoseSample) -> str:
    if not sample.face:
        tracking = "predicting" if sample.yaw_deg is not None else "no track"
        return f"t {sample.t_s:.2f} s  frame {sample.frame}  NO FACE ({tracking})"
    faces = f"{sample.n_faces} faces" if sample.n_faces > 1 else "face"
    return f"t {sample.t_s:.2f} s  frame {sample.frame}  {faces}"


def _draw_gauge(canvas: npt.NDArray[np.uint8], sample: PoseSample, scale: float) -> None:
    """A half-dial, top right: up is straight ahead, right is yaw > 0 (nose to image right)."""
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
