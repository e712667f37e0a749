"""MediaPipe's hand landmarker (palm detector + hand landmark model) on LiteRT.

The two models are MediaPipe's own `.tflite` files (`roadgaze.landmarks.hands.models` provisions
and verifies them); the graph around them is `roadgaze.landmarks.hands.graph`, the crops are the
face engine's `Warper` (MediaPipe's OpenCV converter: the palm detector's input letterboxed with
zeros, the hand's region with its borders replicated). `HandLandmarker.run(rgb, timestamp_ms)`
gives what MediaPipe's `HandLandmarker` gives: per hand 21 normalised landmarks, the presence
score and the handedness score. In VIDEO mode (`timestamp_ms` given) a hand is tracked from the
previous frame's landmarks and the palm detector runs only while fewer hands are tracked than
asked for and at most every `detect_interval_ms` (0: whenever MediaPipe's graph would).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from roadgaze.errors import ModelError
from roadgaze.landmarks.engines import graph as face_graph
from roadgaze.landmarks.engines.litert import Warper, _Model
from roadgaze.landmarks.hands import graph
from roadgaze.landmarks.ssd_detector import SsdDetector, SsdSpec, read_model


@dataclass(frozen=True, slots=True)
class HandArrays:
    """One hand as the model gives it."""

    points: npt.NDArray[np.float32]
    """(21, 3) normalised landmarks: x, y in image fractions, z in the scale of x."""
    presence: float
    """The model's hand-presence score, 0..1."""
    handedness: float
    """The model's 0..1 score for MediaPipe's label `Left` (> 0.5; its first label, the
    binary classifier's). MediaPipe labels hands as if the image were mirrored, so on an
    unmirrored camera `Left` is the person's own right hand (`roadgaze.landmarks.hands.stage`)."""


PALM = SsdSpec("palm", graph.PALM_SIZE, graph.PALM_STRIDES, graph.PALM_NMS_IOU, 1.0 / 255.0)
"""MediaPipe's palm detector (inputs 0..1)."""


@dataclass(frozen=True, slots=True)
class HandSettings:
    """MediaPipe's HandLandmarker options (its defaults) and the detector's pace."""

    num_hands: int = 2
    min_detection_confidence: float = 0.5
    min_presence_confidence: float = 0.5
    min_tracking_confidence: float = 0.5
    detect_interval_ms: int = 0
    threads: int = 1
    delegate: str = "xnnpack"


class HandLandmarker:
    """MediaPipe's HandLandmarker on LiteRT (see the module docstring). ModelError (one line
    naming the file and the fix) when a model is missing or LiteRT cannot load it."""

    def __init__(self, palm_path: Path, landmark_path: Path, settings: HandSettings) -> None:
        import cv2

        self._settings = settings
        self._detector = SsdDetector(
            PALM, palm_path, settings.min_detection_confidence, settings.threads, settings.delegate
        )
        self._model = _Model(
            read_model(landmark_path, "hand landmark"),
            landmark_path.name,
            settings.threads,
            settings.delegate,
        )
        if self._model.input_shape[1:3] != (graph.LANDMARKS_SIZE, graph.LANDMARKS_SIZE):
            raise ModelError(
                f"{landmark_path} takes {self._model.input_shape}, not a hand landmark model; "
                "run `roadgaze model fetch hands --force`"
            )
        self._warper = Warper(graph.LANDMARKS_SIZE, cv2.BORDER_REPLICATE)
        self._tracked: list[face_graph.Rect] = []
        self._last_detect_ms: int | None = None
        self.detector_runs = 0

    def run(self, rgb: npt.NDArray[np.uint8], timestamp_ms: int | None) -> list[HandArrays]:
        """The hands in the RGB image (IMAGE mode for `timestamp_ms` None: no tracking)."""
        size = (rgb.shape[1], rgb.shape[0])
        settings = self._settings
        rects = self._tracked if timestamp_ms is not None else []
        if len(rects) < settings.num_hands and self._may_detect(timestamp_ms):
            palms = self._detector.detect(rgb)
            self.detector_runs += 1
            self._last_detect_ms = timestamp_ms
            detected = [graph.palm_rect(palm, size) for palm in palms]
            rects = graph.add_detections(rects, detected, settings.min_tracking_confidence)
        hands: list[HandArrays] = []
        for rect in rects[: settings.num_hands]:
            found = self._landmarks(rgb, rect, size)
            if found is not None:
                hands.append(found)
        removed = graph.duplicates([hand.points for hand in hands], size)
        hands = [hand for index, hand in enumerate(hands) if index not in removed]
        self._tracked = [graph.landmarks_rect(hand.points, size) for hand in hands]
        return hands

    def _may_detect(self, timestamp_ms: int | None) -> bool:
        """Whether the palm detector may run now: always for stills and at a stream's first
        frame, then at most every `detect_interval_ms`."""
        last, interval = self._last_detect_ms, self._settings.detect_interval_ms
        if timestamp_ms is None or last is None or interval <= 0 or timestamp_ms < last:
            return True
        return timestamp_ms - last >= interval

    def _landmarks(
        self, rgb: npt.NDArray[np.uint8], rect: face_graph.Rect, size: tuple[int, int]
    ) -> HandArrays | None:
        warped = self._warper.warp(rgb, face_graph.roi_pixels(rect, size))
        raw, presence, handedness, _world = self._model.run(warped, 1.0 / 255.0)
        score = float(presence.reshape(-1)[0])
        if score < self._settings.min_presence_confidence:
            return None
        points = face_graph.project_landmarks(raw, graph.LANDMARKS_SIZE, rect, size)
        points[:, 2] /= graph.LANDMARKS_Z_SCALE
        return HandArrays(points, score, float(handedness.reshape(-1)[0]))

    def reset(self) -> None:
        """Forget the tracked hands (a new stream)."""
        self._tracked = []
        self._last_detect_ms = None

    def close(self) -> None:
        self.reset()
