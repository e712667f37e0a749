"""MediaPipe's pose landmarker (BlazePose: pose detector + full pose landmark model) on LiteRT.

The two models are MediaPipe's own `.tflite` files (`roadgaze.landmarks.pose.models`); the graph
around them is `roadgaze.landmarks.pose.graph`, the crops are the face engine's `Warper`
(MediaPipe's OpenCV converter: the detector's input letterboxed with zeros, the body's region
with its borders replicated). `PoseLandmarker.run(rgb, timestamp_ms)` gives what MediaPipe's
legacy pose graph gives without smoothing: one body's 33 landmarks with their visibility and
presence, or None. In VIDEO mode (`timestamp_ms` given) the body is tracked from the previous
frame's auxiliary points and the detector runs only while no body is tracked, at most every
`detect_interval_ms` (0: whenever MediaPipe's graph would).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from roadgaze.errors import ModelError
from roadgaze.landmarks.engines import graph as face_graph
from roadgaze.landmarks.engines.litert import Warper, _Model
from roadgaze.landmarks.pose import graph
from roadgaze.landmarks.ssd_detector import FETCH, SsdDetector, SsdSpec, read_model


@dataclass(frozen=True, slots=True)
class PoseArrays:
    """One body as the model gives it."""

    points: npt.NDArray[np.float64]
    """(33, 3) normalised landmarks: x, y in image fractions, z in the scale of x."""
    visibility: npt.NDArray[np.float64]
    """(33,) 0..1: how likely each point is in view and not hidden."""
    presence: npt.NDArray[np.float64]
    """(33,) 0..1: how likely each point is inside the image."""
    score: float
    """The model's pose flag, 0..1."""


DETECTOR = SsdSpec(
    "pose", graph.DETECTOR_SIZE, graph.DETECTOR_STRIDES, graph.DETECTOR_NMS_IOU, 2.0 / 255.0, -1.0
)
"""MediaPipe's pose detector (inputs -1..1)."""


@dataclass(frozen=True, slots=True)
class PoseSettings:
    """MediaPipe's pose options (its defaults) and the detector's pace."""

    min_detection_confidence: float = 0.5
    min_presence_confidence: float = 0.5
    """The pose flag a body needs (the legacy graph's `min_tracking_confidence`)."""
    detect_interval_ms: int = 0
    threads: int = 1
    delegate: str = "xnnpack"


class PoseLandmarker:
    """MediaPipe's pose landmark graph on LiteRT (see the module docstring). ModelError (one
    line naming the file and the fix) when a model is missing or LiteRT cannot load it."""

    def __init__(self, detector_path: Path, landmark_path: Path, settings: PoseSettings) -> None:
        import cv2

        self._settings = settings
        self._detector = SsdDetector(
            DETECTOR,
            detector_path,
            settings.min_detection_confidence,
            settings.threads,
            settings.delegate,
        )
        self._model = _Model(
            read_model(landmark_path, "pose landmark"),
            landmark_path.name,
            settings.threads,
            settings.delegate,
        )
        if self._model.input_shape[1:3] != (graph.LANDMARKS_SIZE, graph.LANDMARKS_SIZE):
            raise ModelError(
                f"{landmark_path} takes {self._model.input_shape}, not a pose landmark model; "
                f"{FETCH} --force"
            )
        self._warper = Warper(graph.LANDMARKS_SIZE, cv2.BORDER_REPLICATE)
        self._tracked: face_graph.Rect | None = None
        self._last_detect_ms: int | None = None
        self.detector_runs = 0
        self.last_rect: face_graph.Rect | None = None
        """The region the landmark model last ran on (for checks against MediaPipe's graph)."""

    def run(self, rgb: npt.NDArray[np.uint8], timestamp_ms: int | None) -> PoseArrays | None:
        """The body in the RGB image (IMAGE mode for `timestamp_ms` None: no tracking)."""
        size = (rgb.shape[1], rgb.shape[0])
        rect = self._tracked if timestamp_ms is not None else None
        if rect is None and self._may_detect(timestamp_ms):
            bodies = self._detector.detect(rgb)
            self.detector_runs += 1
            self._last_detect_ms = timestamp_ms
            if bodies:
                rect = graph.detection_rect(bodies[0], size)
        self._tracked = None
        self.last_rect = rect
        if rect is None:
            return None
        warped = self._warper.warp(rgb, face_graph.roi_pixels(rect, size))
        raw, flag, _segmentation, heatmap, _world = self._model.run(warped, 1.0 / 255.0)
        score = float(flag.reshape(-1)[0])
        if score < self._settings.min_presence_confidence:
            return None
        points, visibility, presence = graph.decode_landmarks(raw, heatmap[0], rect)
        self._tracked = graph.landmarks_rect(points, size)
        body = slice(0, graph.NUM_BODY)
        return PoseArrays(points[body], visibility[body], presence[body], score)

    def _may_detect(self, timestamp_ms: int | None) -> bool:
        """Whether the detector may run now: always for stills and at a stream's first frame,
        then at most every `detect_interval_ms`."""
        last, interval = self._last_detect_ms, self._settings.detect_interval_ms
        if timestamp_ms is None or last is None or interval <= 0 or timestamp_ms < last:
            return True
        return timestamp_ms - last >= interval

    def reset(self) -> None:
        """Forget the tracked body (a new stream)."""
        self._tracked = None
        self._last_detect_ms = None

    def close(self) -> None:
        self.reset()
