"""MediaPipe's SSD detectors beside the face's (palms, bodies) on LiteRT, and the model-file read
they and their landmark models share.

A detector's input is the image letterboxed with zeros into its square (the face engine's
`Warper`, MediaPipe's OpenCV converter), its outputs decoded against its anchors with
non-maximum suppression (`roadgaze.landmarks.engines.graph`, the face detector's decoding) and
projected back into image fractions. The detectors differ only in the numbers of `SsdSpec`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from roadgaze.errors import ModelError
from roadgaze.landmarks.engines import graph as face_graph
from roadgaze.landmarks.engines.litert import Warper, _Model

__all__ = ["FETCH", "SsdDetector", "SsdSpec", "read_model"]

FETCH = "run `roadgaze model fetch hands`"
"""The fix for a missing or wrong hand or pose model (both come with `model fetch hands`)."""


def read_model(path: Path, what: str) -> bytes:
    """The bytes of model file `path` (`what`: e.g. "palm detection"); ModelError if unreadable."""
    try:
        return path.read_bytes()
    except OSError as exc:
        raise ModelError(
            f"cannot read the {what} model {path}: {exc.strerror or exc}; {FETCH}"
        ) from None


@dataclass(frozen=True, slots=True)
class SsdSpec:
    """One SSD detector's numbers, as MediaPipe's graph sets them."""

    noun: str
    """What it detects, as messages name it ("palm", "pose")."""
    size: int
    """The square input's side, px."""
    strides: tuple[int, ...]
    """The anchor layers' strides."""
    nms_iou: float
    """Overlap above which the weaker of two detections is dropped."""
    scale: float
    """Input = pixel * scale + offset."""
    offset: float = 0.0


class SsdDetector:
    """Detections in an RGB image, best first, in image fractions."""

    def __init__(
        self, spec: SsdSpec, path: Path, min_confidence: float, threads: int, delegate: str
    ) -> None:
        import cv2

        self._spec = spec
        model = read_model(path, f"{spec.noun} detection")
        self._model = _Model(model, path.name, threads, delegate)
        if self._model.input_shape[1:3] != (spec.size, spec.size):
            raise ModelError(
                f"{path} takes {self._model.input_shape}, not a {spec.size} px {spec.noun} "
                f"detector; {FETCH} --force"
            )
        self._warper = Warper(spec.size, cv2.BORDER_CONSTANT)
        self._anchors = face_graph.ssd_anchors(spec.size, spec.strides)
        self._min_confidence = min_confidence

    def detect(self, rgb: npt.NDArray[np.uint8]) -> list[face_graph.FaceDetection]:
        spec = self._spec
        size = (rgb.shape[1], rgb.shape[0])
        roi = face_graph.letterbox_roi(*size)
        warped = self._warper.warp(rgb, (*roi, 0.0))
        boxes, scores = self._model.run(warped, spec.scale, spec.offset)
        found = face_graph.decode_detections(
            boxes[0], scores[0, :, 0], self._anchors, self._min_confidence, spec.size, spec.nms_iou
        )
        return [face_graph.project_detection(box, roi, size) for box in found]
