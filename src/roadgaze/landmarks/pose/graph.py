"""The rules of MediaPipe's pose landmark graph (BlazePose) around its two models, in numpy (no
I/O, no cv2).

Each function is one of MediaPipe's calculators with the options its pose graph sets
(`mediapipe/modules/pose_detection/pose_detection_cpu.pbtxt`,
`modules/pose_landmark/pose_detection_to_roi.pbtxt`, `pose_landmark_by_roi_cpu.pbtxt`,
`tensors_to_pose_landmarks_and_segmentation.pbtxt`, `pose_landmarks_to_roi.pbtxt`); coordinates
are MediaPipe's (image fractions, x right, y down, rotations in radians, clockwise on the image).

- **Pose detector** (224x224, letterboxed with zeros, values -1..1): SSD anchors (strides
  8/16/32/32/32, two per cell and layer: 2254), a box (the face's) and 4 keypoints over 224
  (0 the hips' centre, 1 a point whose distance from it gives the body's size and whose
  direction its rotation, 2 and 3 the same for the upper body), sigmoid scores clipped at
  +-100, kept >= the detection confidence, weighted non-maximum suppression at IoU 0.3; the
  first (best) detection is the body.
- **Body region from a detection**: centred on keypoint 0, a square of twice the distance to
  keypoint 1, turned so that 0 -> 1 points up, scaled by 1.25 (`AlignmentPointsRects`,
  `RectTransformation` square long side).
- **Body landmarks** (256x256, the region's borders replicated, values 0..1): 39 points of
  x, y, z over 256 and visibility and presence logits (sigmoid); the pose flag (0..1) kept at
  >= the presence confidence; each point moved to the sigmoid-weighted mean of a 9x9 window
  of its own 64x64 heatmap when that window's peak is >= 0.5
  (`RefineLandmarksFromHeatmap`); projected through the region. Points 0-32 are the body,
  33 and 34 the two auxiliary points of the next region.
- **Next frame's region**: the detection's rule applied to the auxiliary points 33 -> 34.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from roadgaze.landmarks.engines.graph import FaceDetection, FloatArray, Rect, normalize_radians
from roadgaze.landmarks.hands.graph import transform_rect

DETECTOR_SIZE = 224
DETECTOR_STRIDES = (8, 16, 32, 32, 32)
DETECTOR_NMS_IOU = 0.3
LANDMARKS_SIZE = 256
ROI_SCALE = 1.25
NUM_POINTS = 39
NUM_BODY = 33
AUX_CENTRE, AUX_SCALE = 33, 34
HEATMAP_KERNEL = 9
"""The refinement window MediaPipe 0.10.14 uses (its landmarks match a 9x9 window to 0.002
heatmap cells; the pbtxt in MediaPipe's current source says 7)."""
HEATMAP_MIN_CONFIDENCE = 0.5
UP = math.pi / 2


def alignment_rect(centre: FloatArray, scale_point: FloatArray, size: tuple[int, int]) -> Rect:
    """The body's region from a centre point and a scale point in image fractions
    (`AlignmentPointsRectsCalculator` with a target angle of 90 degrees, then
    `RectTransformation` scale 1.25, long side squared)."""
    width_px, height_px = size
    x0, y0 = float(centre[0]) * width_px, float(centre[1]) * height_px
    x1, y1 = float(scale_point[0]) * width_px, float(scale_point[1]) * height_px
    box_px = 2.0 * math.hypot(x1 - x0, y1 - y0)
    rotation = normalize_radians(UP - math.atan2(-(y1 - y0), x1 - x0))
    rect = Rect(x0 / width_px, y0 / height_px, box_px / width_px, box_px / height_px, rotation)
    return transform_rect(rect, size, ROI_SCALE, 0.0)


def detection_rect(detection: FaceDetection, size: tuple[int, int]) -> Rect:
    """The landmark model's region for a detected body (keypoints 0 -> 1)."""
    return alignment_rect(detection.keypoints[0], detection.keypoints[1], size)


def landmarks_rect(points: FloatArray, size: tuple[int, int]) -> Rect:
    """The next frame's region from a body's (39, 2+) normalised points (33 -> 34)."""
    return alignment_rect(points[AUX_CENTRE, :2], points[AUX_SCALE, :2], size)


def _sigmoid(values: FloatArray) -> FloatArray:
    result: FloatArray = 1.0 / (1.0 + np.exp(-values))
    return result


def refine_from_heatmap(points: FloatArray, heatmap: npt.NDArray[np.float32]) -> FloatArray:
    """`RefineLandmarksFromHeatmapCalculator` (kernel 9, min confidence 0.5) on (39, 2+)
    points in the model input's fractions; heatmap (64, 64, 39) of logits. A point whose column
    or row falls off the map is kept (MediaPipe compares the column with the height, as here:
    the map is square)."""
    height, width = heatmap.shape[0], heatmap.shape[1]
    refined = np.array(points, np.float64)
    offset = (HEATMAP_KERNEL - 1) // 2
    for index in range(refined.shape[0]):
        column = int(refined[index, 0] * width)  # C++'s float -> int: towards zero
        row = int(refined[index, 1] * height)
        if column < 0 or column >= width or row < 0 or column >= height:
            continue
        rows = slice(max(0, row - offset), min(height, row + offset + 1))
        columns = slice(max(0, column - offset), min(width, column + offset + 1))
        window = _sigmoid(heatmap[rows, columns, index].astype(np.float64))
        total = float(window.sum())
        if window.size == 0 or float(window.max()) < HEATMAP_MIN_CONFIDENCE or total <= 0:
            continue
        row_index = np.arange(rows.start, rows.stop, dtype=np.float64)[:, None]
        column_index = np.arange(columns.start, columns.stop, dtype=np.float64)[None, :]
        refined[index, 0] = float((window * column_index).sum()) / width / total
        refined[index, 1] = float((window * row_index).sum()) / height / total
    return refined


def decode_landmarks(
    raw: npt.NDArray[np.float32], heatmap: npt.NDArray[np.float32], rect: Rect
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The model's (195,) output and its heatmap as image landmarks: (39, 3) x, y in image
    fractions and z in the scale of x, (39,) visibility and (39,) presence, 0..1
    (`TensorsToLandmarks`, the heatmap refinement, `LandmarkProjection` through the region,
    which is square in pixels: no letterbox)."""
    values = raw.reshape(NUM_POINTS, 5).astype(np.float64)
    points = values[:, :3] / LANDMARKS_SIZE
    points[:, :2] = refine_from_heatmap(points[:, :2], heatmap)[:, :2]
    x, y = points[:, 0] - 0.5, points[:, 1] - 0.5
    cos_r, sin_r = math.cos(rect.rotation), math.sin(rect.rotation)
    projected = np.empty_like(points)
    projected[:, 0] = (cos_r * x - sin_r * y) * rect.width + rect.x_center
    projected[:, 1] = (sin_r * x + cos_r * y) * rect.height + rect.y_center
    projected[:, 2] = points[:, 2] * rect.width
    return projected, _sigmoid(values[:, 3]), _sigmoid(values[:, 4])
