"""FaceLandmarker results as numpy arrays, without one Python object per landmark.

MediaPipe's Python API turns every landmark of every face into a `NormalizedLandmark` object
(about 1.1 ms per face per frame on the development machine), which roadgaze then turned back into
an array (another 0.9 ms). Where MediaPipe's Python package talks to its C library through ctypes
(mediapipe >= 0.10.30), `run_landmarker` calls the same C function the public
`detect`/`detect_for_video` calls and reads the landmark array straight out of the C result
(0.05 ms); with any other MediaPipe it uses the public API and one vectorised conversion. Both give
identical numbers (tested).

MediaPipe >= 1.0 runs each C call of a landmarker on a thread of its own (`SerialDispatcher`, so
that one landmarker is never called from two threads at once): two thread hand-overs per call.
roadgaze calls a landmarker from one thread at a time (the loop's landmark thread), so it calls
the C function the dispatcher wraps on that thread, with the same arguments and MediaPipe's own
status check (`_raw_library`); the hand-overs cost 0.1-0.5 ms per frame, more while the other
core is busy.
"""

from __future__ import annotations

import ctypes
import functools
import importlib
from typing import Any

import numpy as np
import numpy.typing as npt

Blendshapes = dict[str, float]
"""MediaPipe's blendshape scores of one face by category name (`eyeBlinkLeft`: 0..1)."""
FaceArrays = tuple[npt.NDArray[np.float32], npt.NDArray[np.float64] | None, Blendshapes | None]
"""One face: (N, 3) landmarks x, y, z as MediaPipe normalises them (x, y in 0..1 of the image
width and height, z in the scale of x), the 4x4 facial transformation matrix or None, and the
blendshape scores or None (a landmarker made without `output_face_blendshapes`)."""


class _CResultReader:
    """The ctypes layout of MediaPipe's C result, checked once; None when it is not as expected."""

    def __init__(self, result_type: Any, landmark_type: Any) -> None:
        self.result_type = result_type
        self.floats_per_landmark = ctypes.sizeof(landmark_type) // 4

    @classmethod
    def find(cls) -> _CResultReader | None:
        try:
            module = importlib.import_module("mediapipe.tasks.python.vision.face_landmarker")
            landmark_c = importlib.import_module(
                "mediapipe.tasks.python.components.containers.landmark_c"
            )
            result_type = module.MpFaceLandmarkerResultC
            landmark_type = landmark_c.MpNormalizedLandmarkC
        except (ImportError, AttributeError):
            return None
        layout_ok = (
            (landmark_type.x.offset, landmark_type.y.offset, landmark_type.z.offset) == (0, 4, 8)
            and ctypes.sizeof(landmark_type) % 4 == 0
            and {
                "face_landmarks",
                "face_landmarks_count",
                "facial_transformation_matrixes",
                "face_blendshapes",
                "face_blendshapes_count",
            }
            <= {name for name, *_ in result_type._fields_}
        )
        return cls(result_type, landmark_type) if layout_ok else None

    def read(self, result: Any) -> list[FaceArrays]:
        faces: list[FaceArrays] = []
        matrices = [
            _matrix(result.facial_transformation_matrixes[i])
            for i in range(result.facial_transformation_matrixes_count)
        ]
        blendshapes = [
            _scores(result.face_blendshapes[i]) for i in range(result.face_blendshapes_count)
        ]
        for i in range(result.face_landmarks_count):
            face = result.face_landmarks[i]
            count = int(face.landmarks_count)
            scores = blendshapes[i] if i < len(blendshapes) else None
            if count == 0:
                faces.append((np.empty((0, 3), np.float32), None, scores))
                continue
            stride = self.floats_per_landmark
            flat = _floats(face.landmarks, count * stride)
            points = flat.reshape(count, stride)[:, :3].copy()
            matrix = matrices[i] if i < len(matrices) else None
            faces.append((points, matrix, scores))
        return faces


def _floats(pointer: Any, count: int) -> npt.NDArray[np.float32]:
    """A copy of `count` C floats at `pointer` (one memory copy; `np.ctypeslib.as_array` builds
    a ctypes array type first, several times slower)."""
    address = ctypes.cast(pointer, ctypes.c_void_p).value
    return np.frombuffer(ctypes.string_at(address or 0, 4 * count), dtype=np.float32)


def _matrix(matrix: Any) -> npt.NDArray[np.float64] | None:
    """MediaPipe's `MpMatrixC` (column-major floats) as a row-major float64 array, as its own
    `to_numpy` reads it; None when empty."""
    rows, cols = int(matrix.rows), int(matrix.cols)
    if not matrix.data or rows == 0 or cols == 0:
        return None
    return np.asarray(_floats(matrix.data, rows * cols).reshape(cols, rows).T, np.float64)


def _scores(categories: Any) -> Blendshapes:
    """The scores of one face's C category list (52 entries: name and score each)."""
    found: Blendshapes = {}
    for j in range(int(categories.categories_count)):
        category = categories.categories[j]
        name = category.category_name
        if name:
            found[name.decode("utf-8", "replace")] = float(category.score)
    return found


@functools.cache
def _reader() -> _CResultReader | None:
    """Found on first use: importing MediaPipe waits until a landmarker runs."""
    return _CResultReader.find()


@functools.cache
def _status_check() -> Any:
    """MediaPipe's `handle_status(status, error_message)`; None where it is not found."""
    try:
        utils = importlib.import_module("mediapipe.tasks.python.core.mediapipe_c_utils")
    except ImportError:
        return None
    return getattr(utils, "handle_status", None)


def _raw_library(landmarker: Any) -> Any | None:
    """The `ctypes.CDLL` behind the landmarker's `SerialDispatcher`, None where there is none."""
    raw = getattr(getattr(landmarker, "_lib", None), "_lib", None)
    needed = (
        "MpFaceLandmarkerDetectForVideo",
        "MpFaceLandmarkerDetectImage",
        "MpFaceLandmarkerCloseResult",
        "MpErrorFree",
    )
    if not isinstance(raw, ctypes.CDLL) or _status_check() is None:
        return None
    return raw if all(hasattr(raw, name) for name in needed) else None


def uses_c_results(landmarker: Any) -> bool:
    """True when `run_landmarker` reads this landmarker's results straight from the C library."""
    lib = getattr(landmarker, "_lib", None)
    return (
        _reader() is not None
        and getattr(landmarker, "_handle", None) is not None
        and hasattr(lib, "MpFaceLandmarkerDetectForVideo")
        and hasattr(lib, "MpFaceLandmarkerDetectImage")
        and hasattr(lib, "MpFaceLandmarkerCloseResult")
    )


def run_landmarker(
    landmarker: Any, image: Any, timestamp_ms: int | None, direct: bool = True
) -> list[FaceArrays]:
    """Every face MediaPipe's `landmarker` finds in the `mediapipe.Image` `image`.

    `timestamp_ms` None: IMAGE mode (`detect`); an int: VIDEO mode (`detect_for_video`, strictly
    increasing). `direct=False` forces the public API (tests compare the two). Errors are
    MediaPipe's own (ValueError, RuntimeError).
    """
    reader = _reader() if direct else None
    if reader is not None and uses_c_results(landmarker):
        return _run_direct(landmarker, image, timestamp_ms, reader)
    if timestamp_ms is None:
        result = landmarker.detect(image)
    else:
        result = landmarker.detect_for_video(image, timestamp_ms)
    matrices = result.facial_transformation_matrixes or []
    blendshape_lists = result.face_blendshapes or []
    faces: list[FaceArrays] = []
    for index, face in enumerate(result.face_landmarks):
        points = np.array([(p.x, p.y, p.z) for p in face], dtype=np.float32).reshape(-1, 3)
        matrix = np.asarray(matrices[index], np.float64) if index < len(matrices) else None
        scores = blendshape_lists[index] if index < len(blendshape_lists) else None
        blendshapes = (
            None if scores is None else {str(c.category_name): float(c.score) for c in scores}
        )
        faces.append((points, matrix, blendshapes))
    return faces


def _run_direct(
    landmarker: Any, image: Any, timestamp_ms: int | None, reader: _CResultReader
) -> list[FaceArrays]:
    """What `detect`/`detect_for_video` do, minus the per-landmark Python objects (and, where
    MediaPipe dispatches its C calls to a thread of its own, minus the hand-overs)."""
    lib = landmarker._lib
    raw = _raw_library(landmarker)
    result = reader.result_type()
    args: tuple[Any, ...] = (landmarker._handle, image._image_ptr, None)
    if timestamp_ms is not None:
        args += (timestamp_ms,)
    name = (
        "MpFaceLandmarkerDetectImage" if timestamp_ms is None else "MpFaceLandmarkerDetectForVideo"
    )
    if raw is None:
        getattr(lib, name)(*args, ctypes.byref(result))
    else:
        error = ctypes.c_char_p()
        status = getattr(raw, name)(*args, ctypes.byref(result), ctypes.byref(error))
        try:
            _status_check()(status, error)
        finally:
            if error.value is not None:
                raw.MpErrorFree(error)
    try:
        return reader.read(result)
    finally:
        (lib if raw is None else raw).MpFaceLandmarkerCloseResult(ctypes.byref(result))
