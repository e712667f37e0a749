"""The rules of MediaPipe's face landmarker graph around its models, in numpy (no I/O, no cv2).

Each function is one of MediaPipe's calculators with the options its face landmarker graph sets
(`mediapipe/tasks/cc/vision/face_landmarker/*`, `face_detector/*`, `mediapipe/calculators/*`);
the docstrings name the calculator. Coordinates are MediaPipe's: normalised to the image width and
height (x right, y down), rotations in radians, positive clockwise on the image (y down).

- **Detector** (short-range BlazeFace, 128x128): SSD anchors (4 layers, strides 8/16/16/16, two
  fixed-size anchors per cell: 896), boxes and 6 keypoints decoded as x, y, w, h over 128,
  scores the sigmoid of the logit clipped to +-100, kept when >= `min_detection_confidence`;
  weighted non-maximum suppression (IoU > 0.5 merged, weighted by score); the box and keypoints
  projected from the letterboxed input to the image.
- **Region of interest**: a detection's box with the rotation of its eye keypoints (0 -> 1)
  scaled by 1.5; a face's landmarks give the next frame's: their bounding box, rotation of the
  eye corners 33 -> 263, the long side squared (in pixels), scaled by 1.5.
- **Landmarks**: the model's 478 x, y, z (pixels of its 256x256 input) projected through the
  region; z scaled like x (`LandmarkProjectionCalculator`).
- **Tracking** (VIDEO mode): the detector runs only while fewer faces are tracked than asked for;
  its regions replace tracked ones that overlap them (IoU > `min_tracking_confidence`).
- **Smoothing** (VIDEO mode, one face): a one-euro filter per coordinate (min cutoff 0.05,
  beta 80, derivative cutoff 1) on pixel coordinates, velocities scaled by the face size.
- **Mirrored crop** (roadgaze's own, not MediaPipe's): the landmarks the model finds in a crop
  flipped left to right, put back (`unmirror_landmarks`: x flipped, each landmark renumbered as
  its mirror image, `mirror_order`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

DETECTOR_SIZE = 128
DETECTOR_ANCHOR_STRIDES = (8, 16, 16, 16)
DETECTOR_MIN_SCALE, DETECTOR_MAX_SCALE = 0.1484375, 0.75
DETECTOR_SCORE_CLIP = 100.0
NMS_IOU = 0.5
"""Detections overlapping more than this are merged (FaceDetectorGraphOptions default)."""
DETECTION_ROI_SCALE = 1.5
LANDMARKS_ROI_SCALE = 1.5
ROI_EYES = (33, 263)
"""Landmarks whose line gives a tracked face's rotation (right then left outer eye corner)."""
DETECTION_EYES = (0, 1)
"""BlazeFace keypoints whose line gives a detected face's rotation."""
ONE_EURO_MIN_CUTOFF = 0.05
ONE_EURO_BETA = 80.0
ONE_EURO_DERIVATIVE_CUTOFF = 1.0
ONE_EURO_FREQUENCY = 30.0
"""The filter's rate (Hz) until two timestamps after time 0 give it one (the option's default)."""
FLOAT_MIN = float(np.finfo(np.float32).tiny)
IRIS_MIRROR = (473, 476, 475, 474, 477, 468, 471, 470, 469, 472)
"""The mirror images of the iris landmarks 468-477 (each iris's centre, then its four points;
matched on the landmark model's output for a face and its flipped crop, within 0.7 px)."""
MIRROR_TOLERANCE = 1e-3
"""How far (canonical face units, cm) a vertex's mirror image may lie from its partner."""


@dataclass(frozen=True, slots=True)
class Rect:
    """MediaPipe's `NormalizedRect`: centre and size in image fractions, rotation in radians."""

    x_center: float
    y_center: float
    width: float
    height: float
    rotation: float = 0.0

    def corners_box(self) -> tuple[float, float, float, float]:
        """(x_min, y_min, x_max, y_max) without the rotation (as the association compares)."""
        return (
            self.x_center - self.width / 2,
            self.y_center - self.height / 2,
            self.x_center + self.width / 2,
            self.y_center + self.height / 2,
        )


@dataclass(frozen=True, slots=True)
class FaceDetection:
    """One detected face: box (x_min, y_min, x_max, y_max) and 6 keypoints in image fractions."""

    box: tuple[float, float, float, float]
    keypoints: FloatArray
    score: float


def normalize_radians(angle: float) -> float:
    """The angle in [-pi, pi) (MediaPipe's `NormalizeRadians`)."""
    return angle - 2 * math.pi * math.floor((angle - (-math.pi)) / (2 * math.pi))


def ssd_anchors(
    input_size: int = DETECTOR_SIZE, strides: tuple[int, ...] = DETECTOR_ANCHOR_STRIDES
) -> FloatArray:
    """(896, 2) anchor centres (x, y) of the short-range detector (`SsdAnchorsCalculator`, fixed
    anchor size 1: two anchors per cell, interpolated scale aspect ratio 1); another input size
    and strides give another detector's (the palm detector: 192, the same strides, 2016)."""
    centers: list[tuple[float, float]] = []
    layer = 0
    while layer < len(strides):
        same = layer
        while same < len(strides) and strides[same] == strides[layer]:
            same += 1
        per_cell = 2 * (same - layer)  # aspect ratio 1 and its interpolated scale, per layer
        cells = math.ceil(input_size / strides[layer])
        for y in range(cells):
            for x in range(cells):
                centers.extend([((x + 0.5) / cells, (y + 0.5) / cells)] * per_cell)
        layer = same
    return np.asarray(centers, np.float64)


def decode_detections(
    raw_boxes: npt.NDArray[np.float32],
    raw_scores: npt.NDArray[np.float32],
    anchors: FloatArray,
    min_score: float,
    input_size: int = DETECTOR_SIZE,
    nms_iou: float = NMS_IOU,
) -> list[FaceDetection]:
    """The detections the model's (896, 16) boxes and (896,) logits hold, in the detector input's
    fractions, best first after weighted non-maximum suppression (`TensorsToDetections` +
    `NonMaxSuppression`); another detector's (N, 4 + 2 K) boxes give K keypoints each."""
    scores = 1.0 / (1.0 + np.exp(-np.clip(raw_scores.astype(np.float64), -100, 100)))
    keep = np.flatnonzero(scores >= min_score)
    if keep.size == 0:
        return []
    raw = raw_boxes[keep].astype(np.float64) / input_size
    centers = anchors[keep]
    x_c, y_c = raw[:, 0] + centers[:, 0], raw[:, 1] + centers[:, 1]
    boxes = np.stack(
        [x_c - raw[:, 2] / 2, y_c - raw[:, 3] / 2, x_c + raw[:, 2] / 2, y_c + raw[:, 3] / 2], axis=1
    )
    keypoints = raw[:, 4:].reshape(len(keep), -1, 2) + centers[:, None, :]
    valid = (boxes[:, 2] >= boxes[:, 0]) & (boxes[:, 3] >= boxes[:, 1])
    order = np.argsort(-scores[keep], kind="stable")
    return _weighted_nms(boxes, keypoints, scores[keep], order[valid[order]], nms_iou)


def _iou(box: FloatArray, boxes: FloatArray) -> FloatArray:
    width = np.minimum(box[2], boxes[:, 2]) - np.maximum(box[0], boxes[:, 0])
    height = np.minimum(box[3], boxes[:, 3]) - np.maximum(box[1], boxes[:, 1])
    inter = np.where((width > 0) & (height > 0), width * height, 0.0)
    areas = (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])
    union = (box[2] - box[0]) * (box[3] - box[1]) + areas - inter
    return np.where(union > 0, inter / np.where(union > 0, union, 1.0), 0.0)


def _weighted_nms(
    boxes: FloatArray,
    keypoints: FloatArray,
    scores: FloatArray,
    order: npt.NDArray[np.intp],
    nms_iou: float,
) -> list[FaceDetection]:
    remaining = order
    found: list[FaceDetection] = []
    while remaining.size:
        top = int(remaining[0])
        overlap = _iou(boxes[top], boxes[remaining]) > nms_iou
        members = remaining[overlap]
        weights = scores[members]
        total = weights.sum()
        box = (boxes[members] * weights[:, None]).sum(axis=0) / total
        points = (keypoints[members] * weights[:, None, None]).sum(axis=0) / total
        found.append(FaceDetection((box[0], box[1], box[2], box[3]), points, float(scores[top])))
        remaining = remaining[~overlap]
    return found


def letterbox_roi(width_px: int, height_px: int) -> tuple[float, float, float, float]:
    """The detector's input region (centre x, y, width, height in pixels): the whole image padded
    to a square about its centre (`ImageToTensorCalculator`, keep_aspect_ratio)."""
    side = float(max(width_px, height_px))
    return (0.5 * width_px, 0.5 * height_px, side, side)


def project_detection(
    detection: FaceDetection, roi: tuple[float, float, float, float], size: tuple[int, int]
) -> FaceDetection:
    """A detection in the input's fractions expressed in the image's (`DetectionProjection` with
    the letterbox matrix; no rotation)."""
    cx, cy, side_x, side_y = roi
    scale = np.array([side_x / size[0], side_y / size[1]])
    offset = np.array([(cx - 0.5 * side_x) / size[0], (cy - 0.5 * side_y) / size[1]])
    x0, y0, x1, y1 = detection.box
    low = np.array([x0, y0]) * scale + offset
    high = np.array([x1, y1]) * scale + offset
    points = detection.keypoints * scale + offset
    return FaceDetection((low[0], low[1], high[0], high[1]), points, detection.score)


def rotation_of(
    points: npt.NDArray[np.floating], start: int, end: int, size: tuple[int, int]
) -> float:
    """Rotation that makes the line `start` -> `end` horizontal (`DetectionsToRects`), radians;
    in doubles whatever the points' type."""
    (x0, y0), (x1, y1) = points[start, :2].tolist(), points[end, :2].tolist()
    x0, y0, x1, y1 = x0 * size[0], y0 * size[1], x1 * size[0], y1 * size[1]
    return normalize_radians(-math.atan2(-(y1 - y0), x1 - x0))


def detection_rect(detection: FaceDetection, size: tuple[int, int]) -> Rect:
    """The landmark model's region for a detected face (`DetectionsToRects` with the eye
    keypoints, then `RectTransformation` scale 1.5)."""
    x0, y0, x1, y1 = detection.box
    width, height = x1 - x0, y1 - y0
    rotation = rotation_of(detection.keypoints, *DETECTION_EYES, size)
    return Rect(
        x0 + width / 2,
        y0 + height / 2,
        width * DETECTION_ROI_SCALE,
        height * DETECTION_ROI_SCALE,
        rotation,
    )


def landmarks_rect(landmarks: npt.NDArray[np.floating], size: tuple[int, int]) -> Rect:
    """The next frame's region for a face with these normalised landmarks (`LandmarksToDetection`,
    `DetectionsToRects` with 33 -> 263, `RectTransformation` square long side, scale 1.5)."""
    # Extremes of 1-D columns (numpy reduces (N, 2) along axis 0 several times slower); exact
    # in any float type, so taken before the conversion to Python floats.
    x, y = landmarks[:, 0], landmarks[:, 1]
    x_min, y_min = float(x.min()), float(y.min())
    x_max, y_max = max(float(x.max()), FLOAT_MIN), max(float(y.max()), FLOAT_MIN)
    width, height = x_max - x_min, y_max - y_min
    rotation = rotation_of(landmarks, *ROI_EYES, size)
    long_side_px = max(width * size[0], height * size[1])
    return Rect(
        x_min + width / 2,
        y_min + height / 2,
        long_side_px / size[0] * LANDMARKS_ROI_SCALE,
        long_side_px / size[1] * LANDMARKS_ROI_SCALE,
        rotation,
    )


def roi_pixels(rect: Rect, size: tuple[int, int]) -> tuple[float, float, float, float, float]:
    """(centre x, centre y, width, height, rotation in degrees) of `rect` in pixels, as
    `ImageToTensorCalculator` hands it to OpenCV's `RotatedRect`."""
    return (
        rect.x_center * size[0],
        rect.y_center * size[1],
        rect.width * size[0],
        rect.height * size[1],
        rect.rotation * 180.0 / math.pi,
    )


def project_landmarks(
    raw: npt.NDArray[np.float32], input_size_px: int, rect: Rect, size: tuple[int, int]
) -> npt.NDArray[np.float32]:
    """(478, 3) normalised image landmarks from the model's raw output in input pixels
    (`TensorsToLandmarks` then `LandmarkProjection`; z in the scale of x)."""
    points = raw.reshape(-1, 3).astype(np.float64) / input_size_px
    a, b = rect.width * size[0], rect.height * size[1]
    c, d = math.cos(rect.rotation), math.sin(rect.rotation)
    e, f = rect.x_center * size[0], rect.y_center * size[1]
    x, y = points[:, 0], points[:, 1]
    out = np.empty_like(points)
    out[:, 0] = (a * c * x - b * d * y + (-0.5 * a * c + 0.5 * b * d + e)) / size[0]
    out[:, 1] = (a * d * x + b * c * y + (-0.5 * b * c - 0.5 * a * d + f)) / size[1]
    out[:, 2] = points[:, 2] * math.hypot(a * c / size[0], a * d / size[1])
    return out.astype(np.float32)


def mirror_order(canonical: npt.NDArray[np.floating]) -> npt.NDArray[np.intp]:
    """(478,) the index of each landmark's mirror image (the face's left and right swapped): the
    mesh's from the canonical face's (3, 468) vertices, which are symmetric about x = 0, and the
    irises' (`IRIS_MIRROR`). ValueError when the canonical face is not symmetric."""
    points = np.asarray(canonical, np.float64).T
    mirrored = points * np.array([-1.0, 1.0, 1.0])
    distances = np.linalg.norm(points[:, None, :] - mirrored[None, :, :], axis=2)
    order = distances.argmin(axis=1)
    paired = np.array_equal(order[order], np.arange(order.size))
    if distances.min(axis=1).max() > MIRROR_TOLERANCE or not paired:
        raise ValueError("the canonical face is not mirror-symmetric")
    return np.concatenate([order, np.asarray(IRIS_MIRROR, np.intp)]).astype(np.intp)


def unmirror_landmarks(
    raw: npt.NDArray[np.float32], input_size_px: int, order: npt.NDArray[np.intp]
) -> npt.NDArray[np.float32]:
    """The model's raw landmarks (input pixels, x, y, z) of a crop flipped left to right, as
    landmarks of the crop itself: x mirrored about the crop's middle and each landmark taken from
    its mirror image (z, depth, unchanged)."""
    points = raw.reshape(-1, 3)[order]
    points[:, 0] = np.float32(input_size_px) - points[:, 0]
    return points


def associate(tracked: list[Rect], detected: list[Rect], min_iou: float) -> list[Rect]:
    """Tracked regions and fresh detections merged (`AssociationNormRectCalculator`): a detection
    replaces every region it overlaps by more than `min_iou`; order: survivors, then additions."""
    result: list[Rect] = []
    for rect in [*tracked, *detected]:
        box = np.asarray(rect.corners_box())
        if result:
            others = np.asarray([r.corners_box() for r in result])
            result = [r for r, iou in zip(result, _iou(box, others), strict=True) if iou <= min_iou]
        result.append(rect)
    return result


class OneEuroSmoother:
    """MediaPipe's `LandmarksSmoothingCalculator` with the face landmarker's one-euro filter, on
    all landmarks at once. `apply(t_us, pixels)` filters (N, 3) pixel coordinates (z in the
    scale of x) taken at `t_us` microseconds; `reset()` forgets the face."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self._last_ns = -1
        self._frequency = ONE_EURO_FREQUENCY
        self._raw: npt.NDArray[np.float32] | None = None
        self._value: npt.NDArray[np.float32] | None = None
        self._derivative: npt.NDArray[np.float32] | None = None

    @staticmethod
    def _alpha(cutoff: FloatArray | float, frequency: float) -> FloatArray | float:
        """The smoothing factor, in doubles, for cutoffs (Hz) at `frequency` (Hz); MediaPipe
        rounds it to a float. A number stays a number (as a 0-d array it cost 4 us)."""
        tau = 1.0 / (2 * math.pi * cutoff)
        return 1.0 / (1.0 + tau * frequency)

    def apply(self, t_us: int, pixels: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
        """The filtered pixels; the input unchanged for a face too small to scale (< 1e-6 px)."""
        t_ns = t_us * 1000
        xy = pixels[:, :2]
        scale = ((xy[:, 0].max() - xy[:, 0].min()) + (xy[:, 1].max() - xy[:, 1].min())) / 2.0
        if scale < 1e-6 or self._last_ns >= t_ns:
            return pixels
        if self._last_ns != 0 and t_ns != 0:  # MediaPipe keeps its rate after a time of 0
            self._frequency = 1.0 / ((t_ns - self._last_ns) * 1e-9)
        self._last_ns = t_ns
        frequency = self._frequency
        values = pixels.astype(np.float32)
        if self._raw is None or self._value is None or self._derivative is None:
            self._raw, self._value = values.copy(), values.copy()
            self._derivative = np.zeros_like(values)
            return values
        speed = (values.astype(np.float64) - self._raw) * (1.0 / float(scale)) * frequency
        alpha_d = np.float32(self._alpha(ONE_EURO_DERIVATIVE_CUTOFF, frequency))
        derivative = alpha_d * speed.astype(np.float32) + (1.0 - alpha_d) * self._derivative
        cutoff = ONE_EURO_MIN_CUTOFF + ONE_EURO_BETA * np.abs(derivative.astype(np.float64))
        alpha = np.asarray(self._alpha(cutoff, frequency), np.float32).astype(np.float64)
        smoothed = (alpha * values + (1.0 - alpha) * self._value).astype(np.float32)
        self._raw, self._value, self._derivative = values, smoothed, derivative
        return smoothed
