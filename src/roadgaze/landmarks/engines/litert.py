"""The face landmarker's three models on LiteRT, with MediaPipe's graph rebuilt around them.

The models and the canonical face come from the same verified `face_landmarker.task` (a zip)
MediaPipe reads. Per frame: the region of each face (from the previous frame's landmarks while
one is tracked, else from the face detector), the region warped to the landmark model's input with
OpenCV exactly as MediaPipe's `ImageToTensorCalculator` does on the CPU (a perspective warp of the
region's corners, bilinear, borders replicated; the detector's input letterboxed with zeros), the
landmark model, its face-presence score (kept above `min_presence_confidence`), in VIDEO mode
with one face the one-euro smoothing, the blendshapes from their 146 landmarks and the
transformation matrix from the canonical face (`roadgaze.landmarks.engines.geometry`). The rules
are `roadgaze.landmarks.engines.graph`.

With `retry_rejected` (the front end's, on dark and flat frames) a face the landmark model
rejects gets three more looks, roadgaze's own (`_landmarks_in`, docs/conditions.md).

`threads` sets LiteRT's thread count (1 by default: a worker per core scales, and a second thread
was slower on a loaded 2-core machine). `delegate` is `xnnpack` (LiteRT's default CPU kernels),
`none` (its reference-free builtin kernels without delegates) or the path of a delegate library
(`load_delegate`): the way to a vehicle's NPU, e.g. the libraries of `ai-edge-litert-sdk-qualcomm`,
`-mediatek`, `-intel` or `-google-tensor`.
"""

from __future__ import annotations

import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.config import LandmarksConfig
from roadgaze.errors import ModelError
from roadgaze.landmarks.engines import graph
from roadgaze.landmarks.engines.geometry import CanonicalFace, transformation_matrix
from roadgaze.landmarks.native_log import filtered_native_stderr
from roadgaze.landmarks.results import FaceArrays

DETECTOR_MEMBER = "face_detector.tflite"
LANDMARKS_MEMBER = "face_landmarks_detector.tflite"
BLENDSHAPES_MEMBER = "face_blendshapes.tflite"
GEOMETRY_MEMBER = "geometry_pipeline_metadata_landmarks.binarypb"
LANDMARKS_SIZE = 256
BLENDSHAPE_LANDMARKS = (
    0, 1, 4, 5, 6, 7, 8, 10, 13, 14, 17, 21, 33, 37, 39, 40, 46, 52, 53, 54, 55, 58, 61, 63, 65,
    66, 67, 70, 78, 80, 81, 82, 84, 87, 88, 91, 93, 95, 103, 105, 107, 109, 127, 132, 133, 136,
    144, 145, 146, 148, 149, 150, 152, 153, 154, 155, 157, 158, 159, 160, 161, 162, 163, 168, 172,
    173, 176, 178, 181, 185, 191, 195, 197, 234, 246, 249, 251, 263, 267, 269, 270, 276, 282, 283,
    284, 285, 288, 291, 293, 295, 296, 297, 300, 308, 310, 311, 312, 314, 317, 318, 321, 323, 324,
    332, 334, 336, 338, 356, 361, 362, 365, 373, 374, 375, 377, 378, 379, 380, 381, 382, 384, 385,
    386, 387, 388, 389, 390, 397, 398, 400, 402, 405, 409, 415, 454, 466, 468, 469, 470, 471, 472,
    473, 474, 475, 476, 477,
)  # fmt: skip
"""The landmarks the blendshape model reads, as x, y pixels (`face_blendshapes_graph.cc`)."""
BLENDSHAPE_INDEX = np.array(BLENDSHAPE_LANDMARKS, np.intp)
BLENDSHAPE_NAMES = (
    "_neutral", "browDownLeft", "browDownRight", "browInnerUp", "browOuterUpLeft",
    "browOuterUpRight", "cheekPuff", "cheekSquintLeft", "cheekSquintRight", "eyeBlinkLeft",
    "eyeBlinkRight", "eyeLookDownLeft", "eyeLookDownRight", "eyeLookInLeft", "eyeLookInRight",
    "eyeLookOutLeft", "eyeLookOutRight", "eyeLookUpLeft", "eyeLookUpRight", "eyeSquintLeft",
    "eyeSquintRight", "eyeWideLeft", "eyeWideRight", "jawForward", "jawLeft", "jawOpen",
    "jawRight", "mouthClose", "mouthDimpleLeft", "mouthDimpleRight", "mouthFrownLeft",
    "mouthFrownRight", "mouthFunnel", "mouthLeft", "mouthLowerDownLeft", "mouthLowerDownRight",
    "mouthPressLeft", "mouthPressRight", "mouthPucker", "mouthRight", "mouthRollLower",
    "mouthRollUpper", "mouthShrugLower", "mouthShrugUpper", "mouthSmileLeft", "mouthSmileRight",
    "mouthStretchLeft", "mouthStretchRight", "mouthUpperUpLeft", "mouthUpperUpRight",
    "noseSneerLeft", "noseSneerRight",
)  # fmt: skip
RETRY_LOOKS = ((False, False), (True, False), (False, True), (True, False))
"""(re-cut from the last look's landmarks, mirrored) of each look at a face (`_landmarks_in`)."""
DELEGATES = ("xnnpack", "none")
"""Named delegates; anything else is the path of a delegate library."""


@dataclass(frozen=True, slots=True)
class Bundle:
    """The bytes of the three models and the canonical face, read from a `.task` file."""

    detector: bytes
    landmarks: bytes
    blendshapes: bytes
    face: CanonicalFace

    @classmethod
    def read(cls, model_path: Path) -> Bundle:
        """ModelError (one line naming the file) when it is not a face landmarker bundle."""
        try:
            with zipfile.ZipFile(model_path) as archive:
                detector, landmarks = archive.read(DETECTOR_MEMBER), archive.read(LANDMARKS_MEMBER)
                blendshapes = archive.read(BLENDSHAPES_MEMBER)
                metadata = archive.read(GEOMETRY_MEMBER)
        except (OSError, KeyError, zipfile.BadZipFile, EOFError) as exc:
            raise ModelError(
                f"{model_path} is not a readable face landmarker bundle ({exc}); "
                "run `roadgaze model fetch --force`"
            ) from None
        return cls(detector, landmarks, blendshapes, CanonicalFace.from_metadata(metadata))


def _load_delegate(path: str) -> Any:
    """LiteRT's external delegate from the library at `path`. The library is opened first:
    LiteRT's own loader leaves a half-made object behind on a bad path, whose clean-up prints a
    traceback. OSError for a library that cannot be opened or is no delegate."""
    import ctypes

    from ai_edge_litert import interpreter as litert

    library = ctypes.CDLL(path)
    if not hasattr(library, "tflite_plugin_create_delegate"):
        raise OSError(f"{path} is not a LiteRT delegate (no tflite_plugin_create_delegate)")
    return litert.load_delegate(path)


class _Model:
    """One TFLite model on a LiteRT interpreter: write the input view, `invoke`, read outputs."""

    def __init__(self, content: bytes, name: str, threads: int, delegate: str) -> None:
        from ai_edge_litert import interpreter as litert

        options: dict[str, Any] = {"num_threads": threads}
        if delegate == "none":
            options["experimental_op_resolver_type"] = (
                litert.OpResolverType.BUILTIN_WITHOUT_DEFAULT_DELEGATES
            )
        try:
            if delegate not in DELEGATES:
                options["experimental_delegates"] = [_load_delegate(delegate)]
            with filtered_native_stderr():
                self._interpreter = litert.Interpreter(model_content=content, **options)
                self._interpreter.allocate_tensors()
        except (ValueError, RuntimeError, OSError) as exc:
            raise ModelError(f"LiteRT cannot load {name}: {exc}") from None
        details = self._interpreter.get_input_details()[0]
        self.input_shape = tuple(int(n) for n in details["shape"])
        self._input = self._interpreter.tensor(details["index"])
        self._outputs = [d["index"] for d in self._interpreter.get_output_details()]

    def run(
        self,
        values: npt.NDArray[Any],
        scale: float | npt.NDArray[np.float32] = 1.0,
        offset: float = 0.0,
    ) -> list[npt.NDArray[np.float32]]:
        """The outputs (copies, model order) for the input `values * scale + offset` of
        `input_shape` without the batch, written straight into the interpreter's input;
        `scale` is a number or float32 factors broadcast over `values`' last axis."""
        view = self._input()[0]
        np.multiply(values, np.float32(scale), out=view, casting="unsafe")
        if offset:
            view += np.float32(offset)
        del view  # LiteRT refuses to run while a view of its buffers is alive
        self._interpreter.invoke()  # LiteRT releases Python's lock while it works
        return [self._interpreter.get_tensor(index) for index in self._outputs]


class Warper:
    """A rotated region of an image on a square (`warp`), with its work buffers kept: fresh
    arrays each frame cost more in page faults than the arithmetic. One thread at a time; the
    returned image is overwritten by the next call."""

    def __init__(self, side_px: int, border: int) -> None:
        self.side_px, self._border = side_px, border
        self._across = np.arange(side_px, dtype=np.float32)[None, :]
        self._down = np.arange(side_px, dtype=np.float32)[:, None]
        self._row = np.empty((side_px, 1), np.float32)
        self._x, self._y = (np.empty((side_px, side_px), np.float32) for _ in range(2))
        self._whole = np.empty((side_px, side_px, 2), np.int16)
        self._fraction = np.empty((side_px, side_px), np.uint16)
        self._out = np.empty((side_px, side_px, 3), np.uint8)

    def _source(self, out: npt.NDArray[np.float32], row: npt.NDArray[np.float64]) -> None:
        """out[y, x] = row[0] x + row[1] y + row[2] (source pixels, float32)."""
        np.multiply(self._down, np.float32(row[1]), out=self._row)
        self._row += np.float32(row[2])
        np.multiply(self._across, np.float32(row[0]), out=out)
        out += self._row

    def warp(
        self, rgb: npt.NDArray[np.uint8], roi: tuple[float, float, float, float, float]
    ) -> npt.NDArray[np.uint8]:
        """The rotated region `roi` (centre x, y, width, height px, degrees) of `rgb` on the
        square, as MediaPipe's OpenCV converter makes it: `getPerspectiveTransform` of the
        region's `boxPoints` onto the square's corners and `warpPerspective`, bilinear.

        MediaPipe's own OpenCV samples at source positions rounded to 1/32 pixel and interpolates
        in fixed point (OpenCV's classic `warpPerspective`); OpenCV >= 4.11 in Python interpolates
        in floats, which moved the detector's keypoints by up to 0.4 px. So the source positions
        are computed here (a rectangle onto a square: an affine map), `convertMaps` rounds them
        to 1/32 pixel as the classic code does, and `remap` interpolates them with the
        fixed-point tables. The positions are float32 (less memory traffic than doubles and
        no rounding pass in numpy: 1.30 -> 0.78 ms of CPU per 256 px crop): where the classic
        double lies within float32's rounding (6e-5 px at 640 px) of a 1/64 px tie, a pixel is
        sampled 1/32 px apart, about 35 of 65,536 pixels of a 256 px crop, moving the
        landmarks by about 0.01 px.
        """
        import cv2

        cx, cy, width, height, angle_deg = roi
        corners = cv2.boxPoints(((cx, cy), (width, height), angle_deg)).astype(np.float32)
        side = float(self.side_px)
        target = np.array([[0, side], [0, 0], [side, 0], [side, side]], np.float32)
        inverse = np.linalg.inv(cv2.getPerspectiveTransform(corners, target))
        inverse /= inverse[2, 2]
        self._source(self._x, inverse[0])
        self._source(self._y, inverse[1])
        cv2.convertMaps(self._x, self._y, cv2.CV_16SC2, self._whole, self._fraction)
        cv2.remap(
            rgb,
            self._whole,
            self._fraction,
            cv2.INTER_LINEAR,
            dst=self._out,
            borderMode=self._border,
        )
        return self._out


class FaceDetector:
    """The bundle's short-range face detector: regions of the faces in an RGB image."""

    def __init__(self, model: bytes, min_confidence: float, threads: int, delegate: str) -> None:
        import cv2

        self._model = _Model(model, DETECTOR_MEMBER, threads, delegate)
        self._warper = Warper(graph.DETECTOR_SIZE, cv2.BORDER_CONSTANT)
        self._anchors = graph.ssd_anchors()
        self._min_confidence = min_confidence

    def detect(self, rgb: npt.NDArray[np.uint8]) -> list[graph.FaceDetection]:
        """Every face, best first, in image fractions."""
        size = (rgb.shape[1], rgb.shape[0])
        roi = graph.letterbox_roi(*size)
        warped = self._warper.warp(rgb, (*roi, 0.0))
        boxes, scores = self._model.run(warped, 2.0 / 255.0, -1.0)
        found = graph.decode_detections(
            boxes[0], scores[0, :, 0], self._anchors, self._min_confidence
        )
        return [graph.project_detection(face, roi, size) for face in found]

    def count(self, rgb: npt.NDArray[np.uint8]) -> int:
        """Faces in the image (the multi-face switch's check)."""
        return len(self.detect(rgb))

    def close(self) -> None:
        """Nothing to release beyond the interpreter, which Python frees."""


@dataclass(frozen=True, slots=True)
class Models:
    """The three models on interpreters of their own (one landmarker's)."""

    detector: FaceDetector
    landmarks: _Model
    blendshapes: _Model

    @classmethod
    def load(cls, bundle: Bundle, settings: LandmarksConfig) -> Models:
        """ModelError when LiteRT cannot load one of them."""
        threads, delegate = settings.threads, settings.delegate
        return cls(
            FaceDetector(bundle.detector, settings.min_detection_confidence, threads, delegate),
            _Model(bundle.landmarks, LANDMARKS_MEMBER, threads, delegate),
            _Model(bundle.blendshapes, BLENDSHAPES_MEMBER, threads, delegate),
        )


class LiteRtFaceLandmarker:
    """MediaPipe's FaceLandmarker (`num_faces`, IMAGE or VIDEO mode) on LiteRT: `run` gives what
    `roadgaze.landmarks.results.run_landmarker` gives for MediaPipe's."""

    def __init__(
        self,
        bundle: Bundle,
        settings: LandmarksConfig,
        num_faces: int,
        video: bool,
        models: Models | None = None,
    ) -> None:
        import cv2

        models = models or Models.load(bundle, settings)
        self._settings = settings
        self._detector, self._landmarks = models.detector, models.landmarks
        self._blendshapes = models.blendshapes
        self._face = bundle.face
        self._mirror = graph.mirror_order(bundle.face.points)  # ValueError: not a face
        self._warper = Warper(LANDMARKS_SIZE, cv2.BORDER_REPLICATE)
        self._num_faces = num_faces
        self._video = video
        self._tracked: list[graph.Rect] = []
        self._smoother = graph.OneEuroSmoother() if video and num_faces == 1 else None

    def run(self, rgb: npt.NDArray[np.uint8], timestamp_ms: int | None) -> list[FaceArrays]:
        """Faces in the RGB image: normalised landmarks, the matrix and the blendshapes each."""
        size = (rgb.shape[1], rgb.shape[0])
        return [(points, *self.complete(points, size)) for points in self.track(rgb, timestamp_ms)]

    def track(
        self, rgb: npt.NDArray[np.uint8], timestamp_ms: int | None, retry_rejected: bool = False
    ) -> list[npt.NDArray[np.float32]]:
        """The normalised landmarks of the faces in the RGB image: the part of `run` the next
        frame depends on (regions, tracking, smoothing); `complete` gives the rest."""
        size = (rgb.shape[1], rgb.shape[0])
        rects = self._tracked if self._video else []
        if len(rects) < self._num_faces:
            found = self._detector.detect(rgb)[: self._num_faces]
            detected = [graph.detection_rect(face, size) for face in found]
            rects = graph.associate(rects, detected, self._settings.min_tracking_confidence)
        faces: list[npt.NDArray[np.float32]] = []
        tracked: list[graph.Rect] = []
        for rect in rects[: self._num_faces]:
            points = self._landmarks_in(rgb, rect, size, retry_rejected)
            if points is None:
                continue
            faces.append(points)
            tracked.append(graph.landmarks_rect(points, size))
        self._tracked = tracked
        if self._smoother is not None:
            if faces and timestamp_ms is not None:
                scale = np.array([size[0], size[1], size[0]], np.float32)
                smoothed = self._smoother.apply(timestamp_ms * 1000, faces[0] * scale)
                faces[0] = smoothed / scale  # float32 / float32: already MediaPipe's floats
            else:
                self._smoother.reset()
        return faces

    def _landmarks_in(
        self, rgb: npt.NDArray[np.uint8], rect: graph.Rect, size: tuple[int, int], retry: bool
    ) -> npt.NDArray[np.float32] | None:
        """The normalised landmarks of the face in `rect`, None when the landmark model rejects
        it (presence <= `min_presence_confidence`). With `retry`, three more looks at a rejected
        face: the region re-cut from its landmarks (as tracking cuts the next frame's), the first
        crop mirrored (a second opinion: the model is not mirror-symmetric), and re-cut again."""
        points = None
        for recut, mirrored in RETRY_LOOKS if retry else RETRY_LOOKS[:1]:
            region = graph.landmarks_rect(points, size) if recut and points is not None else rect
            warped = self._warper.warp(rgb, graph.roi_pixels(region, size))
            outputs = self._landmarks.run(warped[:, ::-1] if mirrored else warped, 1.0 / 255.0)
            raw = outputs[0]
            if mirrored:
                raw = graph.unmirror_landmarks(raw, LANDMARKS_SIZE, self._mirror)
            points = graph.project_landmarks(raw, LANDMARKS_SIZE, region, size)
            presence = 1.0 / (1.0 + np.exp(-float(outputs[1].reshape(-1)[0])))
            if presence > self._settings.min_presence_confidence:
                return points
        return None

    def complete(
        self, points: npt.NDArray[np.float32], size: tuple[int, int]
    ) -> tuple[npt.NDArray[np.float64] | None, dict[str, float]]:
        """The transformation matrix and the blendshapes of one face `track` found in an image
        of `size` (width, height). Nothing later depends on them, so the loop computes them on
        the thread that measures the face, while `track` works on the next frame (only that
        thread uses the blendshape model)."""
        return transformation_matrix(points, size, self._face), self._scores(points, size)

    def _scores(self, points: npt.NDArray[np.float32], size: tuple[int, int]) -> dict[str, float]:
        """The blendshapes of one face: its model's landmarks in pixels (float32 products),
        multiplied straight into the model's input (`take` picks the rows in a third of the
        time of fancy indexing)."""
        subset = points.take(BLENDSHAPE_INDEX, axis=0)[:, :2]
        scores = self._blendshapes.run(subset, np.array(size, np.float32))[0]
        return dict(zip(BLENDSHAPE_NAMES, scores.reshape(-1).tolist(), strict=True))

    def close(self) -> None:
        self._tracked = []


class LiteRtEngine:
    """LiteRT landmarkers for the bundle at `model_path` (see the module docstring). Raises
    ImportError without ai-edge-litert and ModelError for a bundle LiteRT cannot load (checked
    here, by loading the first landmarker's models)."""

    name = "litert"

    def __init__(self, config: LandmarksConfig, model_path: Path, video: bool) -> None:
        import ai_edge_litert.interpreter  # noqa: F401  (ImportError here, not mid-stream)

        self._bundle = Bundle.read(model_path)
        self._settings = config
        self._video = video
        self._spare: Models | None = Models.load(self._bundle, self._settings)

    def image(self, rgb: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
        """LiteRT reads the RGB array itself."""
        return rgb

    def landmarker(self, num_faces: int) -> LiteRtFaceLandmarker:
        models, self._spare = self._spare, None
        return LiteRtFaceLandmarker(self._bundle, self._settings, num_faces, self._video, models)

    def counter(self) -> FaceDetector:
        settings = self._settings
        return FaceDetector(
            self._bundle.detector,
            settings.min_detection_confidence,
            settings.threads,
            settings.delegate,
        )
