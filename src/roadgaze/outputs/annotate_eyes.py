"""The eyes on the annotated video: a box per eye coloured by open/closed, the gaze arrow, a line
of numbers. Everything drawn comes from the frame's `FrameRecord`."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from roadgaze.config import MonitorConfig
from roadgaze.landmarks.eyes import EYES
from roadgaze.types import EyeCalibrationStatus, EyeStatus, FrameRecord

EYE_COLOURS_BGR = {
    EyeStatus.OPEN: (80, 220, 80),
    EyeStatus.CLOSED: (40, 40, 235),
    EyeStatus.UNAVAILABLE: (150, 150, 150),
}


def draw_eyes(canvas: npt.NDArray[np.uint8], record: FrameRecord, scale: float) -> None:
    """A box around each eye (green open, red closed, grey unavailable) and, when the gaze is
    known, an arrow from between the eyes: right for yaw > 0 (the driver's left), up for pitch
    > 0, as long as the gaze is far from straight ahead (relative to the road-ahead pose)."""
    import cv2

    features = record.sample.features
    if features is None or len(features.landmarks_px) < 478:
        return
    eyes = record.verdict.eyes
    colour = EYE_COLOURS_BGR[eyes.status]
    points = features.landmarks_px[:, :2].astype(np.float64)
    centres = []
    for eye in EYES:
        outline = points[list(eye.contour)]
        width = float(np.ptp(outline[:, 0]))
        pad = 0.25 * width
        x0, y0 = outline.min(axis=0) - pad
        x1, y1 = outline.max(axis=0) + pad
        cv2.rectangle(canvas, (round(x0), round(y0)), (round(x1), round(y1)), colour, 1)
        centres.append(outline.mean(axis=0))
    if eyes.gaze_yaw_deg is None or eyes.gaze_pitch_deg is None:
        return
    verdict = record.verdict
    yaw = math.radians(eyes.gaze_yaw_deg - verdict.neutral_yaw_deg)
    pitch = math.radians(eyes.gaze_pitch_deg - verdict.neutral_pitch_deg)
    start = 0.5 * (centres[0] + centres[1])
    reach = 2.5 * float(np.linalg.norm(centres[1] - centres[0]))
    end = start + reach * np.array([math.sin(yaw) * math.cos(pitch), -math.sin(pitch)])
    arrow = (80, 220, 80) if eyes.gaze_source == "eyes" else (0, 200, 255)
    cv2.arrowedLine(
        canvas,
        (round(start[0]), round(start[1])),
        (round(end[0]), round(end[1])),
        arrow,
        max(1, round(2 * scale)),
        cv2.LINE_AA,
        tipLength=0.2,
    )


def eyes_line(record: FrameRecord, monitor: MonitorConfig | None = None) -> str:
    """One line: eyes open/closed/unavailable, openness, gaze and its source, the eye calibration
    while not calibrated ("eyes learning": the gaze is the head pose), the closure (against the
    microsleep threshold when the configuration is known), PERCLOS."""
    eyes = record.verdict.eyes
    text = f"eyes {eyes.status.value.upper()}"
    if eyes.openness is not None:
        text += f" {eyes.openness:.2f}"
    if eyes.reason and eyes.status is not EyeStatus.CLOSED:
        text += f" ({eyes.reason})"
    if eyes.gaze_yaw_deg is not None and eyes.gaze_pitch_deg is not None:
        text += (
            f"  gaze {eyes.gaze_yaw_deg:+.0f}/{eyes.gaze_pitch_deg:+.0f} deg ({eyes.gaze_source})"
        )
    if eyes.calibration is not EyeCalibrationStatus.CALIBRATED:
        text += f"  eyes {eyes.calibration.value}"
    if eyes.closure_s:
        limit = "" if monitor is None else f"/{monitor.microsleep_s:g}"
        text += f"  closed {eyes.closure_s:.1f}{limit} s"
    if eyes.perclos is not None:
        text += f"  PERCLOS {100 * eyes.perclos:.0f}%"
    if eyes.degraded:
        text += "  MONITORING DEGRADED"
    return text
