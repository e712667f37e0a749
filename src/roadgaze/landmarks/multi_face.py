"""Finding the driver among several faces without four-face inference on every frame.

In VIDEO mode MediaPipe's FaceLandmarker runs its face detector on every frame on which it tracks
fewer faces than `num_faces`; with `num_faces = 4` and one driver that is every frame (about 19 %
more CPU per frame, measured on the demo drive). So a stream runs a one-face landmarker, which
tracks the face and skips the detector, and checks for further faces with the bundle's own face
detector (`FaceCounter`, about 3 ms) at the first frame, every `landmarks.multi_face_check_s`
seconds, and whenever the tracked face jumps or comes back after a loss. Only while the check sees
two or more faces does the stream switch to the `max_faces` landmarker, where the driver rule
(`landmarks.driver`) chooses; after `MULTI_FACE_RETURN_S` with at most one face it returns to the
one-face landmarker. `MultiFaceSwitch` is that decision, pure and testable without MediaPipe.
The periodic counts run on a thread of their own (`BackgroundCount`) beside that frame's
landmarks and take effect at the next frame (always the next, so a replay gives the same
results every time), so the stream's landmark thread does not wait for them; the first frame's
count and a count after a jump are made at once, because they decide that very frame.
"""

from __future__ import annotations

import logging
import zipfile
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any, Protocol

from roadgaze.landmarks.driver import DRIVER_MATCH_IOU, box_iou
from roadgaze.landmarks.native_log import filtered_native_stderr

log = logging.getLogger(__name__)

MULTI_FACE_RETURN_S = 1.0
"""Seconds with at most one face before the multi-face landmarker hands back to the one-face one."""
DETECTOR_MEMBER = "face_detector.tflite"
"""The face detector inside `face_landmarker.task` (a zip), the one FaceLandmarker itself uses."""

Box = tuple[float, float, float, float]


class FaceMode(StrEnum):
    SINGLE = "single"
    """One-face landmarker: tracks the face, no detector per frame."""
    MULTI = "multi"
    """`max_faces` landmarker: the driver rule chooses among several faces."""


@dataclass(slots=True)
class MultiFaceSwitch:
    """Which landmarker a stream runs, and when it must count faces first.

    Per frame: if `check_due(t_s)`, count the faces and call `counted`; run the landmarker of
    `mode`; in SINGLE mode, if `jumped(t_s, box)`, count now and call `counted` (in MULTI mode
    then, run the multi-face landmarker on this frame too); in MULTI mode call `seen`.
    """

    check_period_s: float
    return_after_s: float = MULTI_FACE_RETURN_S
    mode: FaceMode = FaceMode.SINGLE
    next_check_t_s: float | None = None
    """None: count at the next frame (the first frame of a stream)."""
    last_count_t_s: float | None = None
    few_faces_since_t_s: float | None = None
    previous_box: Box | None = None
    """The driver's box on the previous frame (None: no face)."""

    @property
    def multi(self) -> bool:
        """True while the multi-face landmarker runs."""
        return self.mode is FaceMode.MULTI

    def check_due(self, t_s: float) -> bool:
        return self.mode is FaceMode.SINGLE and (
            self.next_check_t_s is None or t_s >= self.next_check_t_s
        )

    def counted(self, t_s: float, faces: int) -> None:
        """A face count at `t_s`: two or more switch to MULTI."""
        self.last_count_t_s = t_s
        self.next_check_t_s = t_s + self.check_period_s
        if faces >= 2:
            self.mode = FaceMode.MULTI
            self.few_faces_since_t_s = None

    def jumped(self, t_s: float, box: Box | None) -> bool:
        """In SINGLE mode, after the frame: True when the tracked face is back after a frame
        without one, or moved elsewhere (box overlap with the previous frame's below
        `DRIVER_MATCH_IOU`); such a face may be someone else, so count the faces now."""
        previous, self.previous_box = self.previous_box, box
        if box is None or self.last_count_t_s == t_s:
            return False
        return previous is None or box_iou(box, previous) < DRIVER_MATCH_IOU

    def seen(self, t_s: float, faces: int, driver_box: Box | None) -> None:
        """In MULTI mode, after the frame: at most one face for `return_after_s` goes back."""
        self.previous_box = driver_box
        if faces >= 2:
            self.few_faces_since_t_s = None
            return
        if self.few_faces_since_t_s is None:
            self.few_faces_since_t_s = t_s
        elif t_s - self.few_faces_since_t_s >= self.return_after_s:
            self.mode = FaceMode.SINGLE
            self.next_check_t_s = t_s + self.check_period_s
            self.few_faces_since_t_s = None


def detector_model_bytes(model_path: Path) -> bytes | None:
    """The face detector model inside the landmarker bundle; None when it cannot be read."""
    try:
        with zipfile.ZipFile(model_path) as bundle:
            return bundle.read(DETECTOR_MEMBER)
    except (OSError, KeyError, zipfile.BadZipFile) as exc:
        log.warning(
            "no face detector in %s (%s): every frame runs the multi-face model", model_path, exc
        )
        return None


class FaceCounter:
    """Counts the faces in an image with MediaPipe's short-range face detector (IMAGE mode)."""

    def __init__(self, model_bytes: bytes, min_confidence: float) -> None:
        from mediapipe.tasks.python import vision
        from mediapipe.tasks.python.core.base_options import BaseOptions

        options = vision.FaceDetectorOptions(
            base_options=BaseOptions(model_asset_buffer=model_bytes),
            running_mode=vision.RunningMode.IMAGE,
            min_detection_confidence=min_confidence,
        )
        self._detector: Any = vision.FaceDetector.create_from_options(options)
        self._started = False

    def count(self, image: Any) -> int:
        """Faces in the `mediapipe.Image` `image`."""
        if self._started:
            return len(self._detector.detect(image).detections)
        with filtered_native_stderr():  # MediaPipe's first inference logs its set-up on fd 2
            result = self._detector.detect(image)
        self._started = True
        return len(result.detections)

    def close(self) -> None:
        if self._detector is not None:
            self._detector.close()
            self._detector = None


class FaceCounting(Protocol):
    """Counts faces in an engine's image (`FaceCounter`, or the LiteRT engine's detector)."""

    def count(self, image: Any) -> int: ...

    def close(self) -> None: ...


class BackgroundCount:
    """One face count at a time on a thread of its own: `start` it on one frame, `take` it on
    the next."""

    def __init__(self, counter: FaceCounting) -> None:
        self._counter = counter
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="roadgaze-facecount")
        self._pending: tuple[float, Future[int]] | None = None

    @property
    def pending(self) -> bool:
        return self._pending is not None

    def start(self, t_s: float, image: Any) -> None:
        """Count the faces in the `mediapipe.Image` `image` of the frame at `t_s`."""
        if self._pending is None:
            self._pending = (t_s, self._pool.submit(self._counter.count, image))

    def now(self, image: Any) -> int:
        """Faces in `image`, counted at once, on the counting thread after any pending count: the
        counter (a detector with its own buffers) never runs twice at the same time."""
        return self._pool.submit(self._counter.count, image).result()

    def take(self) -> tuple[float, int] | None:
        """(t_s, faces) of the count started (waiting for it: it ran beside a whole frame's
        landmarks, so it is done), None when none was started. Raises what the count raised."""
        if self._pending is None:
            return None
        t_s, future = self._pending
        self._pending = None
        return t_s, future.result()

    def close(self) -> None:
        """Wait for a pending count; the counter itself is closed by its owner."""
        self._pool.shutdown(wait=True)
