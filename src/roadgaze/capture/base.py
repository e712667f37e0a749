"""What every frame source shares: its info, its status, the Protocol and BGR conversion."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from types import TracebackType
from typing import Any, Protocol, Self

import numpy as np
import numpy.typing as npt

from roadgaze.types import ClosesOnExit, Frame


@dataclass(frozen=True, slots=True)
class SourceInfo:
    """What is known about a source once it is open."""

    name: str
    live: bool
    """True for a camera (newest frame only, drops counted); False for files and folders."""
    fps: float | None
    """Nominal frame rate; None when the container does not say."""
    frame_count: int | None
    """Frames the container announces; None for a camera or when unknown."""
    width: int
    height: int


@dataclass(frozen=True, slots=True)
class SourceStatus:
    """Counters and state of a source, safe to read from another thread."""

    frames_delivered: int = 0
    frames_dropped: int = 0
    """Live source only: frames replaced by a newer one before the consumer took them."""
    frames_skipped: int = 0
    """Files only: unreadable images skipped in a folder."""
    connected: bool = True
    ever_connected: bool = True
    """False while a camera that was never opened is still being waited for."""
    reconnects: int = 0
    """Successful re-opens of a camera after it was lost (or after it could not be opened)."""
    reopen_attempts: int = 0
    """Attempts, failed or not, to re-open a lost or not yet available camera."""
    ended: bool = False
    truncated: bool = False
    """The stream ended before the frame count its container announced."""
    message: str | None = None
    """Last event worth telling the user: a lost camera, a truncated file's stop point."""

    @property
    def state(self) -> str:
        """`open`, `unavailable` (never opened yet), `reconnecting` (lost) or `ended`."""
        if self.ended:
            return "ended"
        if self.connected:
            return "open"
        return "reconnecting" if self.ever_connected else "unavailable"


class FrameSource(Protocol):
    """Anything that yields `Frame`s with strictly increasing `t_s`; a context manager."""

    @property
    def info(self) -> SourceInfo: ...

    @property
    def status(self) -> SourceStatus: ...

    def __iter__(self) -> Iterator[Frame]: ...

    def close(self) -> None: ...

    def __enter__(self) -> Self: ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None: ...


class VideoCaptureLike(Protocol):
    """The part of `cv2.VideoCapture` the sources use; tests pass a fake."""

    def isOpened(self) -> bool: ...  # noqa: N802 (OpenCV's name)

    def read(self) -> tuple[bool, Any]: ...

    def get(self, prop_id: int) -> float: ...

    def set(self, prop_id: int, value: float) -> bool: ...

    def release(self) -> None: ...


class SourceBase(ClosesOnExit):
    """What the sources share: a context manager with a `status`."""

    _status: SourceStatus

    @property
    def status(self) -> SourceStatus:
        return self._status


def finite_positive(value: float) -> float | None:
    return value if math.isfinite(value) and value > 0 else None


def as_bgr(image: Any) -> npt.NDArray[np.uint8]:
    """OpenCV images as 3-channel uint8 BGR (grey and BGRA inputs are converted)."""
    import cv2

    array = np.asarray(image)
    if array.dtype != np.uint8:
        array = cv2.convertScaleAbs(array)
    if array.ndim == 2:
        return np.asarray(cv2.cvtColor(array, cv2.COLOR_GRAY2BGR), dtype=np.uint8)
    if array.shape[2] == 4:
        return np.asarray(cv2.cvtColor(array, cv2.COLOR_BGRA2BGR), dtype=np.uint8)
    return array
