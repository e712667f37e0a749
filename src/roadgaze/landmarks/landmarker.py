"""The face landmarker as a `LandmarkDetector`: IMAGE mode for stills, VIDEO mode for streams.

Its models run on the engine `landmarks.engine` chooses (`roadgaze.landmarks.engines`: LiteRT, or
MediaPipe's FaceLandmarker; `MediaPipeLandmarker` always runs MediaPipe's). It measures every face
with `features_from_landmarks` and chooses the driver among several faces by
`LandmarksConfig.driver` (see `roadgaze.landmarks.driver_track`). The work of one frame comes in
three steps so that a stream can run them on three threads (`roadgaze.pipeline`): `prepare` (the
image for the engine; no state), `infer` (the engine itself, the frames in order; in VIDEO mode
also the driver's choice, which the next frame's tracking needs) and `measure` (the features of
each face; no state). `detect` is the three in a row.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

from roadgaze.config import Config, LandmarksConfig
from roadgaze.landmarks.driver import box_iou, choose_driver, merge_mirrored, rule_side
from roadgaze.landmarks.driver_track import DriverTracker
from roadgaze.landmarks.engines import FaceCounting, FaceRunner, Tracking, open_engine
from roadgaze.landmarks.eye_contrast import eye_checks
from roadgaze.landmarks.eyes import LEFT_EYE, RIGHT_EYE
from roadgaze.landmarks.features import (
    DEFAULT_CHOICE,
    NUM_LANDMARKS,
    LandmarkChoice,
    features_from_landmarks,
    finite_box_px,
)
from roadgaze.landmarks.multi_face import BackgroundCount, FaceMode, MultiFaceSwitch
from roadgaze.landmarks.native_log import filtered_native_stderr
from roadgaze.landmarks.results import Blendshapes, FaceArrays
from roadgaze.landmarks.rgb import rgb_to_gray, to_rgb
from roadgaze.landmarks.seat import ambiguity, driver_image_side
from roadgaze.types import ClosesOnExit, Detection, FaceFeatures, RecordedDriver

__all__ = ["Inference", "Landmarker", "MediaPipeLandmarker", "PreparedImage", "to_rgb"]


@dataclass(frozen=True, slots=True)
class PreparedImage:
    """An image converted for the engine (`Landmarker.prepare`)."""

    rgb: npt.NDArray[np.uint8]
    engine_image: Any
    """What the engine reads: a `mediapipe.Image` (MediaPipe's own copy of `rgb`), or `rgb`."""
    gray: npt.NDArray[np.uint8]
    """The grey image the eye check measures."""


Box = tuple[float, float, float, float]


@dataclass(frozen=True, slots=True)
class FoundFace:
    """One face as the engine found it, before roadgaze measures it."""

    landmarks_px: npt.NDArray[np.float32]
    """(478, 3) landmarks: x, y in pixels, z in the scale of x; all finite."""
    matrix: npt.NDArray[np.float64] | None
    """MediaPipe's 4x4 facial transformation matrix (the LiteRT engine computes the same)."""
    blendshapes: Blendshapes | None
    box_px: Box
    """(x_min, y_min, x_max, y_max) of the landmarks, pixels (what `FaceFeatures.box_px` holds)."""
    pending: Callable[[], tuple[npt.NDArray[np.float64] | None, Blendshapes | None]] | None = None
    """An engine that tracks faces apart (`Tracking`): the matrix and the blendshapes, computed
    when the face is measured (`matrix` and `blendshapes` are None until then)."""

    def outputs(self) -> tuple[npt.NDArray[np.float64] | None, Blendshapes | None]:
        """The matrix and the blendshapes (computed now for a pending face)."""
        return (self.matrix, self.blendshapes) if self.pending is None else self.pending()


@dataclass(frozen=True, slots=True)
class Inference:
    """What the engine found in one frame (`Landmarker.infer`), for `measure`."""

    gray: npt.NDArray[np.uint8]
    """The image the faces were found in, in grey (the eye check measures it)."""
    faces: tuple[FoundFace, ...]
    driver_index: int | None
    """VIDEO mode: the driver among `faces` (None: no face). IMAGE mode: None, `measure` chooses."""
    mirrored: tuple[FoundFace, ...] = ()
    """`mirror_average`: the faces found in the horizontally flipped image."""
    driver_ambiguous: str = ""
    """VIDEO mode: why the driver cannot be told from another face ('' when it can)."""


class Landmarker(ClosesOnExit):
    """The face landmarker as a `roadgaze.types.LandmarkDetector`; a context manager.

    `video=False`: IMAGE mode, each call independent (`t_s` must be None), up to
    `landmarks.max_faces` faces per image.
    `video=True`: VIDEO mode, tracking across calls; `t_s` must be given and strictly increase.
    A stream runs a one-face landmarker and switches to the `max_faces` one only while a face
    count sees several faces (`roadgaze.landmarks.multi_face`); with
    `landmarks.multi_face_check_s = 0`, `max_faces = 1` or `mirror_average` every frame runs one
    landmarker with `max_faces` faces. `engine` overrides `landmarks.engine`. `seat_side`: where
    the driver sits in the image, +1 right, -1 left, 0 unknown (`driver_image_side`; `from_config`
    takes it from `[monitor] cabin` and the camera mounting; +1, a left-hand-drive car's, by
    default). Raises ModelError (one line) for a model that cannot be loaded.
    """

    engine_override: ClassVar[str | None] = None
    """An engine this class always runs, whatever `landmarks.engine` says."""

    def __init__(
        self,
        landmarks_config: LandmarksConfig,
        model_path: Path,
        video: bool = False,
        choice: LandmarkChoice = DEFAULT_CHOICE,
        engine: str | None = None,
        seat_side: int = 1,
    ) -> None:
        from roadgaze.errors import ModelError

        self._config = landmarks_config
        self._video = video
        self._choice = choice
        self._last_ms = -1
        self._last_t_s = -math.inf
        self._side = rule_side(landmarks_config.driver, seat_side)
        self._tracker = DriverTracker(landmarks_config.driver, seat_side)
        self._recorded: RecordedDriver | None = None
        self._retry_rejected = False
        """`infer`'s, for the engine's runs of the frame it works on."""
        self._landmarker: FaceRunner | None = None
        self._mirror_landmarker: FaceRunner | None = None
        self._single_landmarker: FaceRunner | None = None
        self._counter: FaceCounting | None = None
        self._background: BackgroundCount | None = None
        self._switch: MultiFaceSwitch | None = None
        switching = (
            video
            and landmarks_config.max_faces > 1
            and landmarks_config.multi_face_check_s > 0
            and not landmarks_config.mirror_average
        )
        self._engine = open_engine(
            landmarks_config, model_path, video, engine or self.engine_override
        )
        try:
            self._landmarker = self._engine.landmarker(landmarks_config.max_faces)
            if landmarks_config.mirror_average:
                self._mirror_landmarker = self._engine.landmarker(landmarks_config.max_faces)
            counter = self._engine.counter() if switching else None
            if counter is not None:
                self._counter = counter
                self._single_landmarker = self._engine.landmarker(1)
                self._background = BackgroundCount(counter)
                self._switch = MultiFaceSwitch(landmarks_config.multi_face_check_s)
        except (RuntimeError, ValueError, OSError) as exc:
            self.close()
            raise ModelError(f"cannot load face landmarker model {model_path}: {exc}") from None
        except ModelError:
            self.close()
            raise

    @property
    def engine(self) -> str:
        """The engine that runs: `litert` or `mediapipe` (after any fallback)."""
        return self._engine.name

    @classmethod
    def from_config(cls, config: Config, video: bool = False) -> Landmarker:
        """A landmarker with the model from `resolve_model` (fetched on first use if allowed)."""
        from roadgaze.landmarks.model_store import resolve_model
        from roadgaze.mounting import CameraMounting

        mounting = CameraMounting.from_config(config.monitor)
        angles = (mounting.yaw_deg, mounting.pitch_deg, mounting.roll_deg)
        side = driver_image_side(config.monitor.cabin, *angles)
        return cls(config.landmarks, resolve_model(config.model), video=video, seat_side=side)

    @property
    def video(self) -> bool:
        return self._video

    @property
    def face_mode(self) -> FaceMode:
        """Which landmarker the stream runs now (MULTI when it never switches)."""
        return FaceMode.MULTI if self._switch is None else self._switch.mode

    def prepare(self, image: npt.NDArray[np.uint8]) -> PreparedImage:
        """The image as the engine takes it (RGB; for MediaPipe copied into a `mediapipe.Image`).

        Keeps no state, so another thread may prepare the next frame while this landmarker works
        (the loop's decode thread does). Raises ValueError for an image that is not uint8 2-D/3-D.
        """
        rgb = to_rgb(image)
        return PreparedImage(rgb, self._engine.image(rgb), rgb_to_gray(rgb))

    def detect(self, image: npt.NDArray[np.uint8], t_s: float | None = None) -> Detection:
        """All faces in one BGR (or grayscale / BGRA) uint8 image and which one is the driver.

        Raises ValueError for an image that is not uint8 2-D/3-D, for `t_s` None in VIDEO mode or
        a float in IMAGE mode, and for a `t_s` earlier than the previous one.
        """
        if self._landmarker is None:
            raise ValueError("landmarker is closed")
        return self.measure(self.infer(self.prepare(image), t_s))

    def detect_prepared(self, prepared: PreparedImage, t_s: float | None = None) -> Detection:
        """`detect` of an image `prepare` made; the same errors but the image's."""
        return self.measure(self.infer(prepared, t_s))

    def infer(
        self, prepared: PreparedImage, t_s: float | None = None, *, retry_rejected: bool = False
    ) -> Inference:
        """The engine on an image `prepare` made: the faces in pixels and, in VIDEO mode, the
        driver. `retry_rejected` (the front end's, on dark and flat frames): an engine that can
        (LiteRT) looks again at a face its landmark model rejected.

        Calls must come in frame order (one thread at a time); the errors are `detect`'s but the
        image's.
        """
        if self._landmarker is None:
            raise ValueError("landmarker is closed")
        rgb, mp_image = prepared.rgb, prepared.engine_image
        timestamp_ms: int | None = None
        if self._video:
            if t_s is None:
                raise ValueError("VIDEO mode needs a timestamp t_s for every frame")
            if not math.isfinite(t_s) or t_s <= self._last_t_s:
                raise ValueError(
                    f"timestamps must strictly increase: {t_s} s after {self._last_t_s} s"
                )
            # MediaPipe (and the LiteRT engine's smoothing) needs increasing integer milliseconds.
            timestamp_ms = max(round(t_s * 1000.0), self._last_ms + 1)
            self._last_t_s, self._last_ms = t_s, timestamp_ms
        elif t_s is not None:
            raise ValueError("IMAGE mode takes no timestamp; construct with video=True")
        size = (rgb.shape[1], rgb.shape[0])
        self._retry_rejected = retry_rejected
        if self._switch is not None and t_s is not None:
            faces = self._run_switching(mp_image, size, t_s, timestamp_ms)
        else:
            faces = self._find(self._landmarker, mp_image, size, timestamp_ms)
        mirrored: list[FoundFace] = []
        if self._mirror_landmarker is not None:
            flipped = self._engine.image(np.ascontiguousarray(rgb[:, ::-1]))
            mirrored = self._find(self._mirror_landmarker, flipped, size, timestamp_ms)
        if not self._video:
            return Inference(prepared.gray, tuple(faces), None, tuple(mirrored))
        # Chosen on the faces of the original image (with `mirror_average` their merged
        # measurements keep these indices).
        tracker = self._tracker
        driver_index = tracker.step(faces, t_s or 0.0, self._recorded)
        if self._switch is not None and self._switch.mode is FaceMode.MULTI:
            self._switch.seen(t_s or 0.0, len(faces), tracker.box_px)
        return Inference(
            prepared.gray, tuple(faces), driver_index, tuple(mirrored), tracker.ambiguous
        )

    def follow(self, recorded: RecordedDriver | None) -> None:
        """The driver a recording chose on the frame `infer` takes next (None: choose afresh);
        the loop calls it before each frame of a recording."""
        self._recorded = recorded

    def measure(self, inference: Inference) -> Detection:
        """The features of each face `infer` found (roll removed, eyes, quality) and the driver.

        Keeps no state, so it may run on another thread while `infer` works on the next frame.
        """
        gray = inference.gray
        faces = self._features(inference.faces, gray)
        if self._mirror_landmarker is not None:
            mirrored = self._features(inference.mirrored, np.ascontiguousarray(gray[:, ::-1]))
            faces = merge_mirrored(faces, mirrored, gray.shape[1])
        if not self._video:
            rule = self._config.driver
            index = choose_driver(faces, rule, side=self._side)
            return Detection(tuple(faces), index, ambiguity(faces, index, rule, self._side))
        return Detection(tuple(faces), inference.driver_index, inference.driver_ambiguous)

    def _run_switching(
        self, mp_image: Any, size: tuple[int, int], t_s: float, timestamp_ms: int | None
    ) -> list[FoundFace]:
        """One frame of a stream: the one-face landmarker unless a count sees several faces."""
        switch, background = self._switch, self._background
        assert switch is not None and background is not None
        started = background.take()  # a count started on the previous frame
        if started is not None:
            switch.counted(*started)
        if switch.check_due(t_s):
            if switch.next_check_t_s is None:  # the first frame: counted before it is tracked
                switch.counted(t_s, background.now(mp_image))
            else:  # the periodic count, beside this frame's landmarks, taken at the next frame
                background.start(t_s, mp_image)
        if switch.mode is FaceMode.SINGLE:
            faces = self._find(self._single_landmarker, mp_image, size, timestamp_ms)
            if not faces and switch.previous_box is not None:
                # Tracking was lost on this frame. MediaPipe would look for a face only on the
                # next one; look again now (its detector runs once it tracks no face), as the
                # multi-face landmarker, which detects on every frame, would have.
                faces = self._find(self._single_landmarker, mp_image, size, self._next_ms())
            box = faces[0].box_px if faces else None
            if not switch.jumped(t_s, box) and not self._elsewhere(box):
                return faces
            switch.counted(t_s, background.now(mp_image))
            if not switch.multi:
                return faces
            return self._find(self._landmarker, mp_image, size, self._next_ms())
        return self._find(self._landmarker, mp_image, size, timestamp_ms)

    def _elsewhere(self, box: Box | None) -> bool:
        """The one face found is not the driver a recording chose on this frame: count now."""
        recorded = None if self._recorded is None else self._recorded.box_px
        return recorded is not None and (box is None or box_iou(box, recorded) < 0.3)

    def _next_ms(self) -> int:
        """A further MediaPipe timestamp within the current frame (a second call on it)."""
        self._last_ms += 1
        return self._last_ms

    def _find(
        self,
        landmarker: FaceRunner | None,
        mp_image: Any,
        size: tuple[int, int],
        timestamp_ms: int | None,
    ) -> list[FoundFace]:
        """The faces of one run of `landmarker` on the engine's image `mp_image` of `size`
        (width, height) pixels; a face with other than 478 landmarks or a non-finite one is
        dropped (`features_from_landmarks` could not measure it)."""
        if landmarker is None:
            raise ValueError("landmarker is closed")
        scale = np.array([size[0], size[1], size[0]], np.float32)
        tracking = landmarker if isinstance(landmarker, Tracking) else None
        if tracking is not None:
            # The rest of each face is left to `measure` (the loop's other thread).
            tracked = tracking.track(mp_image, timestamp_ms, self._retry_rejected)
            results: list[FaceArrays] = [(points, None, None) for points in tracked]
        else:
            results = landmarker.run(mp_image, timestamp_ms)
        faces: list[FoundFace] = []
        for points, matrix, blendshapes in results:
            pixels = points * scale
            if pixels.shape != (NUM_LANDMARKS, 3):
                continue
            box = finite_box_px(pixels)
            if box is None:
                continue
            pending = None
            if tracking is not None:
                pending = functools.partial(tracking.complete, points, size)
            faces.append(FoundFace(pixels, matrix, blendshapes, box, pending))
        return faces

    def _features(
        self, found: tuple[FoundFace, ...], gray: npt.NDArray[np.uint8]
    ) -> list[FaceFeatures]:
        """Each face measured, with its blendshapes and the contrast and sharpness of its eyes
        (on `gray`, the image it was found in)."""
        size = (gray.shape[1], gray.shape[0])
        faces: list[FaceFeatures] = []
        for face in found:
            pixels = face.landmarks_px
            right_contrast, right_sharpness, right_lids = eye_checks(gray, pixels, RIGHT_EYE)
            left_contrast, left_sharpness, left_lids = eye_checks(gray, pixels, LEFT_EYE)
            matrix, blendshapes = face.outputs()
            faces.append(
                features_from_landmarks(
                    pixels,
                    size,
                    matrix,
                    self._choice,
                    blendshapes=blendshapes,
                    eye_contrast=(right_contrast, left_contrast),
                    eye_sharpness=(right_sharpness, left_sharpness),
                    eye_lid_share=(right_lids, left_lids),
                )
            )
        return faces

    def close(self) -> None:
        with filtered_native_stderr():
            names = ("_background", "_landmarker", "_mirror_landmarker", "_single_landmarker")
            for name in (*names, "_counter"):
                resource = getattr(self, name, None)
                if resource is not None:
                    resource.close()
                    setattr(self, name, None)


class MediaPipeLandmarker(Landmarker):
    """A `Landmarker` on MediaPipe's FaceLandmarker whatever `landmarks.engine` says: the
    reference the LiteRT engine is held equal to."""

    engine_override = "mediapipe"
