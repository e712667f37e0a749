"""File sources: every frame of a video file or an image folder, and a looping replay of a file.

A file source delivers every frame, with timestamps from the container checked by `TimeBase`
(or `index / fps` for a folder), strictly increasing; nothing is dropped.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np
import numpy.typing as npt

from roadgaze.capture.base import (
    FrameSource,
    SourceBase,
    SourceInfo,
    SourceStatus,
    VideoCaptureLike,
    as_bgr,
    finite_positive,
)
from roadgaze.capture.timebase import MAX_FPS, MIN_FPS, TimeBase, check_avi_rate, sane_fps
from roadgaze.errors import SourceError
from roadgaze.types import Frame

# FFmpeg prints its own complaints about bad files on stderr; we report them as one clear line.
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")

log = logging.getLogger(__name__)

MIN_SIDE_PX = 2
"""Smaller frames (a 1x1 video) cannot hold a face: refused at open, naming the video."""
IMAGE_SUFFIXES = frozenset({".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".ppm"})


class VideoFileSource(SourceBase):
    """Every frame of a video file OpenCV/FFmpeg can read (animated GIF included).

    `t_s` is the container's presentation time of each frame, checked by `TimeBase`: once a
    timestamp is missing, goes backwards, stalls or jumps far beyond the frame rate, frames are
    timed by their index at the container's rate (said once, and in `status.message`); with no
    usable rate either, iterating raises `SourceError`. Raises `SourceError` when the file is
    missing, holds no readable frame or its frames are smaller than 2x2 pixels. A stream that
    ends before the announced frame count is reported in `status` (truncated, with the stop
    point) and logged.
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
        if capture_factory is None:
            check_avi_rate(self.path)
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
        if min(first.shape[:2]) < MIN_SIDE_PX:
            self.close()
            raise SourceError(
                f"video {self.path} is {first.shape[1]}x{first.shape[0]} pixels: too small to "
                f"hold a face (at least {MIN_SIDE_PX}x{MIN_SIDE_PX} needed)"
            )
        self._first: npt.NDArray[np.uint8] | None = as_bgr(first)
        self._first_t_s = self._container_time_s()
        count = self._capture.get(cv2.CAP_PROP_FRAME_COUNT)
        height, width = first.shape[:2]
        self._raw_fps = self._capture.get(cv2.CAP_PROP_FPS)
        self._info = SourceInfo(
            name=str(self.path),
            live=False,
            fps=sane_fps(self._raw_fps),
            frame_count=int(count) if finite_positive(count) else None,
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
        time_base = TimeBase(str(self.path), self._raw_fps)
        index = 0
        previous_t_s: float | None = None
        image = self._first
        container_t_s = self._first_t_s
        self._first = None
        while image is not None:
            t_s = time_base.t_s(index, container_t_s)
            if time_base.flagged and self._status.message is None:
                message = f"video {self.path}: {time_base.fallback_reason}: frame-index time used"
                self._status = replace(self._status, message=message)
            self._status = replace(self._status, frames_delivered=index + 1)
            yield Frame(index=index, t_s=t_s, image=image)
            previous_t_s = t_s
            index += 1
            if self._capture is None:
                return
            ok, raw = self._capture.read()
            if not ok or raw is None:
                break
            image = as_bgr(raw)
            container_t_s = self._container_time_s()
        self._finish(index, previous_t_s)

    def _finish(self, delivered: int, last_t_s: float | None) -> None:
        expected = self._info.frame_count
        # Containers round their frame count; only a clear shortfall means truncation.
        truncated = expected is not None and delivered < expected - max(1, expected // 100)
        message = self._status.message
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


class ImageFolderSource(SourceBase):
    """The images of a folder in name order, as frames `index / fps` seconds apart.

    Unreadable images are skipped with a warning and counted in `status.frames_skipped`.
    Raises `SourceError` when the folder holds no image, or when `fps` could not time frames
    (outside `MIN_FPS`..`MAX_FPS`, as for a video's rate).
    """

    def __init__(self, folder: str | Path, fps: float = 30.0) -> None:
        import cv2

        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise SourceError(f"image folder {self.folder} not found")
        if sane_fps(fps) is None:  # its images are timed index / fps: nothing else times them
            raise SourceError(
                f"image folder {self.folder}: capture.fps {fps:g} cannot time its images (it "
                f"must lie within {MIN_FPS:g} to {MAX_FPS:g}); e.g. --set capture.fps=30"
            )
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
            yield Frame(index=index, t_s=position / self._fps, image=as_bgr(image))
            index += 1
        self._status = replace(self._status, ended=True)

    def close(self) -> None:
        return None


class LoopingSource(SourceBase):
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
