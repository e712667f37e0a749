"""A V4L2 camera read by a background thread: newest frame only, lost and re-opened on one timeline.

A consumer slower than the camera gets the latest frame and the frames it missed are counted as
drops, never queued. A camera that cannot be opened (when asked to wait for it) or that stops
delivering is reported in `status`, re-opened with exponential backoff and resumed; `t_s` keeps
counting from when the source was created, so one timeline spans every re-open. A frame that
comes a jump after the one before (beyond ten periods and 1 s, as for files) without the camera
being reported lost is said in a warning and in `status`.
"""

from __future__ import annotations

import logging
import math
import re
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from typing import Any

from roadgaze.capture.base import (
    SourceBase,
    SourceInfo,
    SourceStatus,
    VideoCaptureLike,
    as_bgr,
    finite_positive,
)
from roadgaze.capture.timebase import is_jump
from roadgaze.config import CaptureConfig
from roadgaze.errors import SourceError
from roadgaze.types import Frame

log = logging.getLogger(__name__)

CAMERA_DEVICE = re.compile(r"^/dev/video(\d+)$")


class CameraSource(SourceBase):
    """A V4L2 camera (`/dev/videoN` or an index) read by a background thread; newest frame only.

    Settings are applied in the order V4L2 needs: FOURCC, width, height, fps, then a one-frame
    buffer. `t_s` is `clock()` at capture, relative to when the source was created. A failed read
    marks the camera lost (logged and in `status`), then it is reopened with exponential backoff
    from `reconnect_initial_s` to `reconnect_max_s` until it delivers again or the source is closed.
    A camera that cannot be opened at all raises `SourceError`, unless `wait_for_device` (the
    daemon): then the source starts disconnected and the same backoff keeps trying.
    """

    def __init__(
        self,
        device: int | str,
        config: CaptureConfig | None = None,
        capture_factory: Callable[[int | str], VideoCaptureLike] | None = None,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] | None = None,
        wait_for_device: bool = False,
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
        self._capture = self._open()
        if self._capture is None:
            problem = (
                f"cannot open camera {device}: no such device or it is busy; check "
                "`v4l2-ctl --list-devices` and that no other program uses it"
            )
            if not wait_for_device:
                raise SourceError(problem)
            message = f"camera unavailable: {problem}"
            log.warning("%s; retrying", message)
            self._status = SourceStatus(connected=False, ever_connected=False, message=message)
        else:
            self._status = SourceStatus(ever_connected=True)
        self._t0_s = clock()
        self._last_t_s = -math.inf
        self._lost_since_frame = False
        self._grabbed = 0
        width, height, fps = self.config.width, self.config.height, self.config.fps
        if self._capture is not None:
            width = int(self._capture.get(_prop("CAP_PROP_FRAME_WIDTH"))) or width
            height = int(self._capture.get(_prop("CAP_PROP_FRAME_HEIGHT"))) or height
            fps = finite_positive(self._capture.get(_prop("CAP_PROP_FPS"))) or fps
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
                self._check_step(t_s)
                self._last_t_s = t_s
                frame = Frame(index=self._grabbed, t_s=t_s, image=as_bgr(raw))
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
                self._lost_since_frame = True
                message = f"camera {self.device} lost; reconnecting"
                log.warning(message)
                self._set_status(connected=False, message=message)
            self._sleep(delay_s)
            if self._stop.is_set():
                break
            self._capture = self._open()
            with self._condition:
                attempts = self._status.reopen_attempts + 1
                self._status = replace(self._status, reopen_attempts=attempts)
            if self._capture is None:
                log.info("camera %s not back yet; next try in %.1f s", self.device, delay_s)
                delay_s = min(delay_s * 2.0, self.config.reconnect_max_s)
            else:
                with self._condition:
                    reconnects = self._status.reconnects + 1
                message = f"camera {self.device} reconnected (reconnect {reconnects})"
                log.warning(message)
                self._set_status(
                    connected=True, ever_connected=True, reconnects=reconnects, message=message
                )
        with self._condition:
            self._status = replace(self._status, ended=True)
            self._condition.notify_all()

    def _check_step(self, t_s: float) -> None:
        """Say it when a frame comes a jump (`roadgaze.capture.timebase.is_jump`) after the one
        before without the camera having been reported lost: a read that hung (a stalled
        driver or machine). Its time is real; the monitor is told by the warning and the
        status, not by a changed clock (the wall-clock stamps of recordings stay true)."""
        step_s = t_s - self._last_t_s
        lost, self._lost_since_frame = self._lost_since_frame, False
        if (
            lost
            or not math.isfinite(step_s)
            or not is_jump(step_s, 1.0 / (self._info.fps or self.config.fps))
        ):
            return
        message = (
            f"camera {self.device} delivered no frame for {step_s:.1f} s (a read that hung) "
            f"until t={t_s:.3f} s"
        )
        log.warning(message)
        self._set_status(message=message)

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

    if isinstance(device, str) and (match := CAMERA_DEVICE.match(device)):
        device = int(match.group(1))
    capture: VideoCaptureLike = cv2.VideoCapture(device, cv2.CAP_V4L2)
    return capture


def camera_device(spec: str) -> int | str | None:
    """`/dev/videoN` or an integer index as a camera device, else None."""
    if spec.strip().isdigit():
        return int(spec)
    match = CAMERA_DEVICE.match(spec.strip())
    return spec.strip() if match else None
