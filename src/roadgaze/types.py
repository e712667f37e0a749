"""Frozen dataclasses that flow between the pipeline stages.

Every per-frame object carries `t_s`, the time on the source's timeline (container time for a
video file, seconds since start for a live camera), so time-based logic counts seconds, not
frames. Image x grows to the right, y downwards. Yaw > 0: head turned to the driver's own left
(ISO 8855), which an unmirrored camera sees as the nose pointing to the image right.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import TracebackType
from typing import Protocol, Self

import numpy as np
import numpy.typing as npt


@dataclass(frozen=True, slots=True)
class Frame:
    """One image from a frame source."""

    index: int
    """0-based frame number at the source (gaps mean dropped frames on a live source)."""
    t_s: float
    """Seconds on the source timeline; strictly increasing within one source."""
    image: npt.NDArray[np.uint8]
    """BGR, uint8, shape (height, width, 3)."""


@dataclass(frozen=True, slots=True)
class FaceFeatures:
    """One face as the yaw models see it.

    `x_left_px`, `x_right_px` and `x_center_px` are measured in the roll-removed frame (the image
    rotated about the face so that the eye line is horizontal), in pixels; only their differences
    matter to the yaw models.
    """

    x_left_px: float
    x_right_px: float
    x_center_px: float
    roll_deg: float
    """In-plane head rotation removed before measuring, degrees (positive: counter-clockwise)."""
    box_px: tuple[float, float, float, float]
    """Face bounding box in the original image: x_min, y_min, x_max, y_max."""
    quality: float
    """0..1; low when the face is small, cut by the image edge or poorly fitted."""
    landmarks_px: npt.NDArray[np.float32]
    """(N, 3) landmark x, y in image pixels and z (depth) in the same pixel scale."""
    mediapipe_yaw_deg: float | None = None
    """MediaPipe's own yaw from its facial transformation matrix, project sign convention."""
    mediapipe_pitch_deg: float | None = None


@dataclass(frozen=True, slots=True)
class Detection:
    """All faces found in one image and which of them is the driver."""

    faces: tuple[FaceFeatures, ...]
    driver_index: int | None
    """Index into `faces` of the driver, None when no face was found."""

    @property
    def driver(self) -> FaceFeatures | None:
        return None if self.driver_index is None else self.faces[self.driver_index]


@dataclass(frozen=True, slots=True)
class SmoothedYaw:
    """State of the yaw smoother after one update or prediction."""

    yaw_deg: float
    yaw_rate_dps: float
    yaw_std_deg: float


@dataclass(frozen=True, slots=True)
class YawSample:
    """The pipeline's per-frame result."""

    t_s: float
    frame: int
    face: bool
    yaw_raw_deg: float | None
    """Center-CE yaw of this frame; None without a face or when the model cannot explain it."""
    yaw_deg: float | None
    """Smoothed yaw; None before the first face or after the track was dropped."""
    yaw_rate_dps: float | None
    yaw_std_deg: float | None
    features: FaceFeatures | None = None
    n_faces: int = 0


class LandmarkDetector(Protocol):
    """Finds faces in one image; MediaPipe in production, a small fake in tests.

    `t_s` None means an independent still image (IMAGE mode); a float means one frame of a stream
    (VIDEO mode), and successive calls must pass strictly increasing `t_s`.
    """

    def detect(self, image: npt.NDArray[np.uint8], t_s: float | None = None) -> Detection: ...

    def close(self) -> None: ...


class ClosesOnExit:
    """Mixin for resources: `with resource:` returns it and calls `close()` on the way out."""

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()
