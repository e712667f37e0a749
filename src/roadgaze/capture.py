"""Frame sources behind one Protocol: video files, V4L2 cameras and image folders.

A file source (video or folder) delivers every frame, with timestamps from the container (or
`index / fps` for a folder), strictly increasing. A live camera keeps only the newest frame: a
background thread grabs continuously, a consumer slower than the camera gets the latest frame and
the frames it missed are counted as drops, never queued. A camera that stops delivering is
reported, reopened with exponential backoff and resumed.

`open_source(spec, config)` picks the source from a string: an existing file, an existing folder,
`/dev/videoN` or an integer camera index.
"""

from __future__ import annotations

import logging
import math
import os
import re
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from types import TracebackType
from typing import Any, Protocol, Self

import numpy as np
import numpy.typing as npt

from roadgaze.config import CaptureConfig, Config
from roadgaze.errors import SourceError
from roadgaze.types import ClosesOnExit, Frame

# FFmpeg prints its own complaints about bad files on stderr; we report them as one clear line.
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")

log = logging.getLogger(__name__)

IMAGE_SUFFIXES = frozenset({".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".ppm"})
_CAMERA_DEVICE = re.compile(r"^/dev/video(\d+)$")


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
    reconnects: int = 0
    """Successful re-opens of a camera after it was lost."""
    ended: bool = False
    truncated: bool = False
    """The stream ended before the frame count its container announced."""
    message: str | None = None
    """Last event worth telling the user: a lost camera, a truncated file's stop point."""


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


class _SourceBase(ClosesOnExit):
    """What the sources share: a context manager with a `status`."""

    _status: SourceStatus

    @property
    def status(self) -> SourceStatus:
        return self._status


def _finite_positive(value: float) -> float | None:
    return value if math.isfinite(value) and value > 0 else None


class VideoFileSource(_SourceBase):
    """Every frame of a video file OpenCV/FFmpeg can read (animated GIF included).

    `t_s` is the container's presentation time of each frame; a missing or non-increasing
    container time is replaced by the previous time plus one nominal frame period. Raises
    `SourceError` when the file is missing or holds no readable frame. A stream that ends before
    the announced frame count is reported in `status` (truncated, with the stop point) and logged.
    """

    def __init__(
        self,
        path: str | Path,
        capture_factory: Callable[[str], VideoCaptureLike] | None = None,
    ) -> None:
        import cv2

        self.path = Path(path)
        if not self.path.is_file():
            raise SourceError(f"video file {self.path} not found; pass an existing video file")
        factory = capture_factory or (lambda name: cv2.VideoCapture(name, cv2.CAP_FFMPEG))
        self._capture: VideoCaptureLike | None = factory(str(self.path))
        if not self._capture.isOpened():
            self._capture.release()
            self._capture = None
            raise SourceError(
                f"cannot read video {self.path}: OpenCV/FFmpeg does not recognise it (corrupt, "
                "truncated before its index, or an unsupported format); try re-encoding it"
            )
        ok, first = self._capture.read()
        if not ok or first is None:
            self.close()
            raise SourceError(f"cannot read video {self.path}: it holds no readable frame")
        self._first: npt.NDArray[np.uint8] | None = _as_bgr(first)
        self._first_t_s = self._container_time_s()
        count = self._capture.get(cv2.CAP_PROP_FRAME_COUNT)
        height, width = first.shape[:2]
        self._info = SourceInfo(
            name=str(self.path),
            live=False,
            fps=_finite_positive(self._capture.get(cv2.CAP_PROP_FPS)),
            frame_count=int(count) if _finite_positive(count) else None,
            width=int(width),
            height=int(height),
        )
        self._status = SourceStatus()
        self._iterated = False

    @property
    def info(self) -> SourceInfo:
        return self._info

    def _container_time_s(self) -> float | None:
        import cv2

        assert self._capture is not None
        msec = self._capture.get(cv2.CAP_PROP_POS_MSEC)
        return msec / 1000.0 if math.isfinite(msec) and msec >= 0 else None

    def __iter__(self) -> Iterator[Frame]:
        if self._iterated:
            raise SourceError(f"video {self.path} can be iterated only once; open it again")
        self._iterated = True
        period_s = 1.0 / (self._info.fps or 30.0)
        index = 0
        previous_t_s: float | None = None
        image = self._first
        t_s = self._first_t_s
        self._first = None
        while image is not None:
            if t_s is None or (previous_t_s is not None and t_s <= previous_t_s):
                t_s = 0.0 if previous_t_s is None else previous_t_s + period_s
            self._status = replace(self._status, frames_delivered=index + 1)
            yield Frame(index=index, t_s=t_s, image=image)
            previous_t_s = t_s
            index += 1
            if self._capture is None:
                return
            ok, raw = self._capture.read()
            if not ok or raw is None:
                break
            image = _as_bgr(raw)
            t_s = self._container_time_s()
        self._finish(index, previous_t_s)

    def _finish(self, delivered: int, last_t_s: float | None) -> None:
        expected = self._info.frame_count
        # Containers round their frame count; only a clear shortfall means truncation.
        truncated = expected is not None and delivered < expected - max(1, expected // 100)
        message = None
        if truncated:
            message = (
                f"video {self.path} ended early: read {delivered} of {expected} announced frames, "
                f"stopped after t={last_t_s or 0.0:.3f} s (file truncated or damaged)"
            )
            log.warning(message)
        self._status = replace(self._status, ended=True, truncated=truncated, message=message)

    def close(self) -> None:
        if self._capture is not None:
            self._capture.release()
            self._capture = None


def _as_bgr(image: Any) -> npt.NDArray[np.uint8]:
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


class ImageFolderSource(_SourceBase):
    """The images of a folder in name order, as frames `index / fps` seconds apart.

    Unreadable images are skipped with a warning and counted in `status.frames_skipped`.
    Raises `SourceError` when the folder holds no image.
    """

    def __init__(self, folder: str | Path, fps: float = 30.0) -> None:
        import cv2

        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise SourceError(f"image folder {self.folder} not found")
        self._paths = sorted(
            p for p in self.folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file()
        )
        if not self._paths:
            suffixes = ", ".join(sorted(IMAGE_SUFFIXES))
            raise SourceError(f"image folder {self.folder} holds no image ({suffixes})")
        self._fps = fps
        first = cv2.imread(str(self._paths[0]))
        height, width = first.shape[:2] if first is not None else (0, 0)
        self._info = SourceInfo(
            name=str(self.folder),
            live=False,
            fps=fps,
            frame_count=len(self._paths),
            width=int(width),
            height=int(height),
        )
        self._status = SourceStatus()

    @property
    def info(self) -> SourceInfo:
        return self._info

    def __iter__(self) -> Iterator[Frame]:
        import cv2

        skipped = 0
        index = 0
        for position, path in enumerate(self._paths):
            image = cv2.imread(str(path))
            if image is None:
                skipped += 1
                log.warning("skipping unreadable image %s", path)
                self._status = replace(self._status, frames_skipped=skipped)
                continue
            self._status = replace(self._status, frames_delivered=index + 1)
            yield Frame(index=index, t_s=position / self._fps, image=_as_bgr(image))
            index += 1
        self._status = replace(self._status, ended=True)

    def close(self) -> None:
        return None


class CameraSource(_SourceBase):
    """A V4L2 camera (`/dev/videoN` or an index) read by a background thread; newest frame only.

    Settings are applied in the order V4L2 needs: FOURCC, width, height, fps, then a one-frame
    buffer. `t_s` is `clock()` at capture, relative to when the source was opened. A failed read
    marks the camera lost (logged and in `status`), then it is reopened with exponential backoff
    from `reconnect_initial_s` to `reconnect_max_s` until it delivers again or the source is closed.
    Raises `SourceError` when the camera cannot be opened at all.
    """

    def __init__(
        self,
        device: int | str,
        config: CaptureConfig | None = None,
        capture_factory: Callable[[int | str], VideoCaptureLike] | None = None,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] | None = None,
    ) -> None:
        self.device = device
        self.config = config if config is not None else CaptureConfig()
        self._factory = capture_factory or _v4l2_capture
        self._clock = clock
        self._stop = threading.Event()
        self._sleep = sleep or (lambda seconds: self._stop.wait(seconds) and None)
        self._condition = threading.Condition()
        self._latest: Frame | None = None
        self._taken = True
        self._status = SourceStatus()
        self._capture = self._open()
        if self._capture is None:
            raise SourceError(
                f"cannot open camera {device}: no such device or it is busy; check "
                "`v4l2-ctl --list-devices` and that no other program uses it"
            )
        self._t0_s = clock()
        self._last_t_s = -math.inf
        self._grabbed = 0
        width = int(self._capture.get(_prop("CAP_PROP_FRAME_WIDTH"))) or self.config.width
        height = int(self._capture.get(_prop("CAP_PROP_FRAME_HEIGHT"))) or self.config.height
        fps = _finite_positive(self._capture.get(_prop("CAP_PROP_FPS"))) or self.config.fps
        self._info = SourceInfo(
            name=f"camera {device}",
            live=True,
            fps=fps,
            frame_count=None,
            width=width,
            height=height,
        )
        self._thread = threading.Thread(target=self._grab_loop, name="camera-grab", daemon=True)
        self._thread.start()

    @property
    def info(self) -> SourceInfo:
        return self._info

    @property
    def status(self) -> SourceStatus:
        with self._condition:
            return self._status

    def _open(self) -> VideoCaptureLike | None:
        try:
            capture = self._factory(self.device)
        except Exception as exc:  # a driver error is a lost camera, not a crash
            log.debug("opening camera %s raised %s", self.device, exc)
            return None
        if not capture.isOpened():
            capture.release()
            return None
        settings = (
            ("CAP_PROP_FOURCC", float(_fourcc(self.config.fourcc))),
            ("CAP_PROP_FRAME_WIDTH", float(self.config.width)),
            ("CAP_PROP_FRAME_HEIGHT", float(self.config.height)),
            ("CAP_PROP_FPS", float(self.config.fps)),
            ("CAP_PROP_BUFFERSIZE", 1.0),
        )
        for name, value in settings:
            if not capture.set(_prop(name), value):
                log.debug("camera %s did not accept %s=%s", self.device, name, value)
        return capture

    def _grab_loop(self) -> None:
        delay_s = self.config.reconnect_initial_s
        while not self._stop.is_set():
            capture = self._capture
            ok, raw = (False, None) if capture is None else _safe_read(capture)
            if ok and raw is not None:
                t_s = max(self._clock() - self._t0_s, self._last_t_s + 1e-6)
                self._last_t_s = t_s
                frame = Frame(index=self._grabbed, t_s=t_s, image=_as_bgr(raw))
                self._grabbed += 1
                with self._condition:
                    dropped = self._status.frames_dropped + (0 if self._taken else 1)
                    self._status = replace(self._status, frames_dropped=dropped)
                    self._latest = frame
                    self._taken = False
                    self._condition.notify_all()
                delay_s = self.config.reconnect_initial_s
                continue
            if capture is not None:
                capture.release()
                self._capture = None
                message = f"camera {self.device} lost; reconnecting"
                log.warning(message)
                self._set_status(connected=False, message=message)
            self._sleep(delay_s)
            if self._stop.is_set():
                break
            self._capture = self._open()
            if self._capture is None:
                log.info("camera %s not back yet; next try in %.1f s", self.device, delay_s)
                delay_s = min(delay_s * 2.0, self.config.reconnect_max_s)
            else:
                with self._condition:
                    reconnects = self._status.reconnects + 1
                message = f"camera {self.device} reconnected (reconnect {reconnects})"
                log.warning(message)
                self._set_status(connected=True, reconnects=reconnects, message=message)
        with self._condition:
            self._status = replace(self._status, ended=True)
            self._condition.notify_all()

    def _set_status(self, **changes: Any) -> None:
        with self._condition:
            self._status = replace(self._status, **changes)

    def __iter__(self) -> Iterator[Frame]:
        while True:
            with self._condition:
                while self._taken and not self._stop.is_set():
                    self._condition.wait(timeout=0.5)
                if self._stop.is_set():
                    return
                frame = self._latest
                self._taken = True
                self._status = replace(
                    self._status, frames_delivered=self._status.frames_delivered + 1
                )
            assert frame is not None
            yield frame

    def close(self) -> None:
        self._stop.set()
        with self._condition:
            self._condition.notify_all()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout=5.0)
        if self._capture is not None:
            self._capture.release()
            self._capture = None


def _safe_read(capture: VideoCaptureLike) -> tuple[bool, Any]:
    try:
        return capture.read()
    except Exception as exc:  # a driver error is a lost camera, not a crash
        log.debug("camera read raised %s", exc)
        return False, None


def _prop(name: str) -> int:
    import cv2

    return int(getattr(cv2, name))


def _fourcc(code: str) -> int:
    import cv2

    return int(cv2.VideoWriter.fourcc(*code))


def _v4l2_capture(device: int | str) -> VideoCaptureLike:
    """cv2.VideoCapture on V4L2; `/dev/videoN` is opened as index N (OpenCV's V4L2 backend
    does not open devices by name)."""
    import cv2

    if isinstance(device, str) and (match := _CAMERA_DEVICE.match(device)):
        device = int(match.group(1))
    capture: VideoCaptureLike = cv2.VideoCapture(device, cv2.CAP_V4L2)
    return capture


def camera_device(spec: str) -> int | str | None:
    """`/dev/videoN` or an integer index as a camera device, else None."""
    if spec.strip().isdigit():
        return int(spec)
    match = _CAMERA_DEVICE.match(spec.strip())
    return spec.strip() if match else None


def open_source(spec: str, config: Config | None = None) -> FrameSource:
    """The frame source a user names: an existing file, a folder, `/dev/videoN` or an index.

    Raises `SourceError` when the string names none of these or the source cannot be opened.
    """
    config = config if config is not None else Config()
    path = Path(spec).expanduser()
    if path.is_file():
        return VideoFileSource(path)
    if path.is_dir():
        return ImageFolderSource(path, fps=config.capture.fps)
    device = camera_device(spec)
    if device is not None:
        return CameraSource(device, config.capture)
    raise SourceError(
        f"no video file, image folder or camera '{spec}'; pass an existing file or folder, "
        "/dev/videoN or a camera index"
    )


class LoopingSource(_SourceBase):
    """A file source played again and again (benchmarks, soak tests) on one increasing timeline.

    `open_once()` opens a fresh pass; each pass's times are shifted to continue after the previous
    pass by one frame period, and frame indices keep counting. Stops after `duration_s` of wall
    time (checked between frames) or `passes` passes, whichever comes first.
    """

    def __init__(
        self,
        open_once: Callable[[], FrameSource],
        duration_s: float | None = None,
        passes: int | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._open_once = open_once
        self._duration_s = duration_s
        self._passes = passes
        self._clock = clock
        self._current: FrameSource | None = open_once()
        self._info = replace(self._current.info, frame_count=None)
        self._status = SourceStatus()
        self.passes_done = 0

    @property
    def info(self) -> SourceInfo:
        return self._info

    def __iter__(self) -> Iterator[Frame]:
        start_s = self._clock()
        offset_s = 0.0
        index = 0
        period_s = 1.0 / (self._info.fps or 30.0)
        while self._passes is None or self.passes_done < self._passes:
            source = self._current if self._current is not None else self._open_once()
            self._current = source
            last_t_s = None
            with source:
                for frame in source:
                    if self._duration_s is not None and self._clock() - start_s >= self._duration_s:
                        self._status = replace(self._status, ended=True)
                        return
                    last_t_s = frame.t_s
                    self._status = replace(self._status, frames_delivered=index + 1)
                    yield Frame(index=index, t_s=offset_s + frame.t_s, image=frame.image)
                    index += 1
            self._current = None
            self.passes_done += 1
            if last_t_s is None:
                break
            offset_s += last_t_s + period_s
        self._status = replace(self._status, ended=True)

    def close(self) -> None:
        if self._current is not None:
            self._current.close()
            self._current = None
