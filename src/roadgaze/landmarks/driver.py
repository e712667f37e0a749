"""Which face is the driver, and averaging a face with its measurement in the mirrored image."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from roadgaze.landmarks.eyes import swap_sides
from roadgaze.landmarks.seat import (
    DRIVER_SWITCH_AREA_RATIO,
    Box,
    Boxed,
    area,
    centre_x,
    seat_pick,
)
from roadgaze.types import FaceFeatures

__all__ = [
    "DRIVER_MATCH_IOU",
    "DRIVER_RULES",
    "DRIVER_SWITCH_AREA_RATIO",
    "Box",
    "Boxed",
    "box_iou",
    "choose_driver",
    "merge_mirrored",
    "rule_side",
    "unmirror",
]

DRIVER_MATCH_IOU = 0.3
"""Box overlap above which a face in a new frame is taken to be the previous frame's driver."""
DRIVER_RULES = ("seat", "largest", "left", "right")
"""The values of `landmarks.driver` (docs/landmarks.md, "Which face is the driver")."""


def choose_driver(
    faces: Sequence[Boxed],
    rule: str,
    previous_box_px: Box | None = None,
    side: int = 1,
) -> int | None:
    """Index of the driver among `faces` under `rule`, None when there is no face.

    "seat" (default): the face in the driver's seat, `side` +1 (image right) or -1 (left) as
    `roadgaze.landmarks.seat.driver_image_side` gives it for the cabin and camera mounting, 0
    unknown (`seat_pick`: the larger face then); a stream holds that face by identity
    (`roadgaze.landmarks.driver_track`). "largest": the face with the largest bounding-box
    area. "left" / "right": the face whose box centre is furthest to the image's left / right.
    `previous_box_px` (streams, "largest" only): the previous frame's driver box; that face
    stays the driver unless another is `DRIVER_SWITCH_AREA_RATIO` times larger.
    """
    if not faces:
        return None
    if rule == "seat":
        return seat_pick(faces, side)
    if rule == "largest":
        areas = [area(f.box_px) for f in faces]
        best = int(np.argmax(areas))
        if previous_box_px is not None:
            overlaps = [box_iou(f.box_px, previous_box_px) for f in faces]
            kept = int(np.argmax(overlaps))
            if (
                overlaps[kept] >= DRIVER_MATCH_IOU
                and areas[best] < DRIVER_SWITCH_AREA_RATIO * areas[kept]
            ):
                return kept
        return best
    centers = [centre_x(f.box_px) for f in faces]
    if rule == "left":
        return int(np.argmin(centers))
    if rule == "right":
        return int(np.argmax(centers))
    raise ValueError(f"unknown driver rule '{rule}'; choose {', '.join(DRIVER_RULES)}")


def rule_side(rule: str, seat_side: int) -> int:
    """The image side the driver is looked for on under `rule` (0: by size, or unknown)."""
    return {"seat": seat_side, "left": -1, "right": 1}.get(rule, 0)


def box_iou(a: Box, b: Box) -> float:
    width = min(a[2], b[2]) - max(a[0], b[0])
    height = min(a[3], b[3]) - max(a[1], b[1])
    if width <= 0 or height <= 0:
        return 0.0
    inter = width * height
    area_a = (a[2] - a[0]) * (a[3] - a[1])
    area_b = (b[2] - b[0]) * (b[3] - b[1])
    return inter / (area_a + area_b - inter)


def unmirror(face: FaceFeatures, image_width_px: int) -> FaceFeatures:
    """A face measured in the horizontally flipped image, expressed in the original image.

    x becomes width - x (so left and right boundaries swap), roll and yaw change sign. The
    landmark array is flipped in x but keeps MediaPipe's indices of the flipped face.
    """
    width = float(image_width_px)
    points = face.landmarks_px.copy()
    points[:, 0] = width - points[:, 0]
    x_min, y_min, x_max, y_max = face.box_px
    return FaceFeatures(
        x_left_px=width - face.x_right_px,
        x_right_px=width - face.x_left_px,
        x_center_px=width - face.x_center_px,
        roll_deg=-face.roll_deg,
        box_px=(width - x_max, y_min, width - x_min, y_max),
        quality=face.quality,
        landmarks_px=points,
        mediapipe_yaw_deg=None if face.mediapipe_yaw_deg is None else -face.mediapipe_yaw_deg,
        mediapipe_pitch_deg=face.mediapipe_pitch_deg,
        y_top_px=face.y_top_px,
        y_bottom_px=face.y_bottom_px,
        y_center_px=face.y_center_px,
        blendshapes=None if face.blendshapes is None else swap_sides(face.blendshapes),
        eye_contrast=None if face.eye_contrast is None else face.eye_contrast[::-1],
        eye_sharpness=None if face.eye_sharpness is None else face.eye_sharpness[::-1],
        eye_lid_share=None if face.eye_lid_share is None else face.eye_lid_share[::-1],
    )


def _mean(a: float | None, b: float | None) -> float | None:
    return None if a is None or b is None else 0.5 * (a + b)


def _mean_scores(
    a: Mapping[str, float] | None, b: Mapping[str, float] | None
) -> Mapping[str, float] | None:
    if a is None or b is None:
        return a if b is None else b
    return {name: 0.5 * (score + b.get(name, score)) for name, score in a.items()}


def merge_mirrored(
    faces: Sequence[FaceFeatures], mirrored_faces: Sequence[FaceFeatures], image_width_px: int
) -> list[FaceFeatures]:
    """Average each face with its measurement in the flipped image (matched by box overlap).

    The result is exactly mirror-symmetric: flipping the input negates every yaw. A face found in
    only one of the two images is kept as found there. Blendshape scores are averaged (the
    mirrored face's Left and Right swapped); landmarks and eye contrast stay the original's.
    """
    candidates = [unmirror(face, image_width_px) for face in mirrored_faces]
    merged: list[FaceFeatures] = []
    for face in faces:
        overlaps = [box_iou(face.box_px, other.box_px) for other in candidates]
        best = int(np.argmax(overlaps)) if overlaps else -1
        if best < 0 or overlaps[best] < 0.3:
            merged.append(face)
            continue
        other = candidates.pop(best)
        merged.append(
            FaceFeatures(
                x_left_px=0.5 * (face.x_left_px + other.x_left_px),
                x_right_px=0.5 * (face.x_right_px + other.x_right_px),
                x_center_px=0.5 * (face.x_center_px + other.x_center_px),
                roll_deg=0.5 * (face.roll_deg + other.roll_deg),
                box_px=tuple(0.5 * (p + q) for p, q in zip(face.box_px, other.box_px, strict=True)),  # type: ignore[arg-type]
                quality=0.5 * (face.quality + other.quality),
                landmarks_px=face.landmarks_px,
                mediapipe_yaw_deg=_mean(face.mediapipe_yaw_deg, other.mediapipe_yaw_deg),
                mediapipe_pitch_deg=_mean(face.mediapipe_pitch_deg, other.mediapipe_pitch_deg),
                y_top_px=_mean(face.y_top_px, other.y_top_px),
                y_bottom_px=_mean(face.y_bottom_px, other.y_bottom_px),
                y_center_px=_mean(face.y_center_px, other.y_center_px),
                blendshapes=_mean_scores(face.blendshapes, other.blendshapes),
                eye_contrast=face.eye_contrast,
                eye_sharpness=face.eye_sharpness,
                eye_lid_share=face.eye_lid_share,
            )
        )
    return merged + candidates
