"""The rules of MediaPipe's hand landmarker graph around its two models, in numpy (no I/O, no cv2).

Each function is one of MediaPipe's calculators with the options its hand landmarker sets
(`mediapipe/tasks/cc/vision/hand_detector/hand_detector_graph.cc`,
`hand_landmarker/hand_landmarks_detector_graph.cc`, `hand_landmarker_graph.cc`,
`modules/hand_landmark/calculators/hand_landmarks_to_rect_calculator.cc`); coordinates are
MediaPipe's (image fractions, x right, y down, rotations in radians, clockwise on the image).

- **Palm detector** (192x192, letterboxed, values 0..1): SSD anchors (strides 8/16/16/16, 2016),
  boxes and 7 keypoints over 192, sigmoid scores clipped at +-100, kept >= the detection
  confidence, weighted non-maximum suppression at IoU 0.3.
- **Hand region from a palm**: the box rotated so that wrist (keypoint 0) -> middle-finger base
  (keypoint 2) points up, shifted by half its height towards the fingers, squared on its long side
  and scaled by 2.6.
- **Hand landmarks** (224x224, values 0..1): 21 x, y, z over 224 (z also over 0.4), projected
  through the region; presence and handedness are the model's own 0..1 scores.
- **Next frame's region**: from the wrist and the finger bases (12 of the 21 points), rotated
  so that the wrist -> finger-base line points up, shifted by a tenth, squared, scaled by 2.
- **Tracking** (VIDEO mode): the detector runs while fewer hands are tracked than asked for; a
  detection overlapping a tracked region (IoU > the tracking confidence) is dropped. Hands
  whose landmarks duplicate another's (10 of 21 points within a fifth of its size, boxes with
  IoU > 0.2) are removed.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from roadgaze.landmarks.engines.graph import (
    FaceDetection,
    FloatArray,
    Rect,
    normalize_radians,
    rotation_of,
)

PALM_SIZE = 192
PALM_STRIDES = (8, 16, 16, 16)
PALM_NMS_IOU = 0.3
PALM_WRIST, PALM_MIDDLE_BASE = 0, 2
PALM_ROI_SCALE, PALM_ROI_SHIFT_Y = 2.6, -0.5
LANDMARKS_SIZE = 224
LANDMARKS_Z_SCALE = 0.4
"""TensorsToLandmarks' `normalize_z`: the model's z over the input size and over this."""
HAND_ROI_SCALE, HAND_ROI_SHIFT_Y = 2.0, -0.1
ROI_POINTS = (0, 1, 2, 3, 5, 6, 9, 10, 13, 14, 17, 18)
"""The landmarks the next frame's region is made from (wrist, thumb, the finger bases)."""
NUM_POINTS = 21
UP = math.pi / 2


def palm_rect(palm: FaceDetection, size: tuple[int, int]) -> Rect:
    """The hand landmark model's region for a detected palm (`DetectionsToRects` wrist ->
    middle-finger base at 90 degrees, then `RectTransformation` scale 2.6, shift -0.5)."""
    x0, y0, x1, y1 = palm.box
    toward_fingers = rotation_of(palm.keypoints, PALM_WRIST, PALM_MIDDLE_BASE, size)
    rotation = normalize_radians(UP + toward_fingers)
    rect = Rect(x0 + (x1 - x0) / 2, y0 + (y1 - y0) / 2, x1 - x0, y1 - y0, rotation)
    return transform_rect(rect, size, PALM_ROI_SCALE, PALM_ROI_SHIFT_Y)


def transform_rect(rect: Rect, size: tuple[int, int], scale: float, shift_y: float) -> Rect:
    """`RectTransformationCalculator` with `square_long`: shifted by `shift_y` of its height
    along its own up axis, the long side (in pixels) squared, both sides scaled."""
    width_px, height_px = size
    x, y = rect.x_center, rect.y_center
    if rect.rotation == 0.0:
        y += rect.height * shift_y
    else:
        x -= height_px * rect.height * shift_y * math.sin(rect.rotation) / width_px
        y += height_px * rect.height * shift_y * math.cos(rect.rotation) / height_px
    long_side_px = max(rect.width * width_px, rect.height * height_px)
    return Rect(
        x,
        y,
        long_side_px / width_px * scale,
        long_side_px / height_px * scale,
        rect.rotation,
    )


def landmarks_rect(points: npt.NDArray[np.floating], size: tuple[int, int]) -> Rect:
    """The next frame's region for a hand with these (21, 2+) normalised landmarks
    (`HandLandmarksToRectCalculator` on the 12 `ROI_POINTS`, then scale 2, shift -0.1)."""
    width_px, height_px = size
    subset = np.asarray(points, np.float64)[list(ROI_POINTS), :2]
    x0, y0 = subset[0, 0] * width_px, subset[0, 1] * height_px
    # Partial indices 4, 6, 8: the index, middle and ring finger bases (landmarks 5, 9, 13).
    x1 = ((subset[4, 0] + subset[8, 0]) / 2 + subset[6, 0]) / 2 * width_px
    y1 = ((subset[4, 1] + subset[8, 1]) / 2 + subset[6, 1]) / 2 * height_px
    rotation = normalize_radians(UP - math.atan2(-(y1 - y0), x1 - x0))
    reverse = normalize_radians(-rotation)
    low, high = subset.min(axis=0), subset.max(axis=0)
    center = (low + high) / 2
    offsets = (subset - center) * np.array([width_px, height_px])
    cos_r, sin_r = math.cos(reverse), math.sin(reverse)
    projected_x = offsets[:, 0] * cos_r - offsets[:, 1] * sin_r
    projected_y = offsets[:, 0] * sin_r + offsets[:, 1] * cos_r
    mid_x = (projected_x.max() + projected_x.min()) / 2
    mid_y = (projected_y.max() + projected_y.min()) / 2
    cos_f, sin_f = math.cos(rotation), math.sin(rotation)
    rect = Rect(
        (mid_x * cos_f - mid_y * sin_f + width_px * center[0]) / width_px,
        (mid_x * sin_f + mid_y * cos_f + height_px * center[1]) / height_px,
        float(projected_x.max() - projected_x.min()) / width_px,
        float(projected_y.max() - projected_y.min()) / height_px,
        rotation,
    )
    return transform_rect(rect, size, HAND_ROI_SCALE, HAND_ROI_SHIFT_Y)


def _box(points: FloatArray) -> FloatArray:
    return np.concatenate([points[:, :2].min(axis=0), points[:, :2].max(axis=0)])


def _box_iou(a: FloatArray, b: FloatArray) -> float:
    width = min(a[2], b[2]) - max(a[0], b[0])
    height = min(a[3], b[3]) - max(a[1], b[1])
    if width <= 0 or height <= 0:
        return 0.0
    inter = width * height
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return float(inter / union) if union > 0 else 0.0


def duplicates(hands: list[npt.NDArray[np.float32]], size: tuple[int, int]) -> set[int]:
    """Indices of hands that repeat an earlier kept one (`HandLandmarksDeduplicationCalculator`:
    at least 10 of 21 landmarks closer than a fifth of the larger hand's size, the larger of
    wrist-index base, index-pinky base and pinky base-wrist, and boxes with IoU > 0.2)."""
    scale = np.array(size, np.float64)
    pixels = [np.asarray(hand, np.float64)[:, :2] * scale for hand in hands]
    baselines = [
        max(
            float(np.linalg.norm(p[0] - p[5])),
            float(np.linalg.norm(p[5] - p[17])),
            float(np.linalg.norm(p[17] - p[0])),
        )
        for p in pixels
    ]
    boxes = [_box(np.asarray(hand, np.float64)) for hand in hands]
    kept: list[int] = []
    removed: set[int] = set()
    for i in range(len(hands)):
        for j in kept:
            threshold = max(baselines[i], baselines[j]) * 0.2
            apart = np.linalg.norm(pixels[i] - pixels[j], axis=1)
            matched = int(np.count_nonzero(apart < threshold))
            if matched >= 10 and _box_iou(boxes[i], boxes[j]) > 0.2:
                removed.add(i)
                break
        else:
            kept.append(i)
    return removed


def add_detections(tracked: list[Rect], detected: list[Rect], min_iou: float) -> list[Rect]:
    """Tracked regions first, then each detection that overlaps none of those kept so far by
    more than `min_iou` (`HandAssociationCalculator`; IoU of the unrotated boxes)."""
    result = list(tracked)
    for rect in detected:
        box = np.asarray(rect.corners_box())
        if all(_box_iou(box, np.asarray(other.corners_box())) <= min_iou for other in result):
            result.append(rect)
    return result
