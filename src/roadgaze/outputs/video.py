"""Writing video files with OpenCV: which codec goes with which file name."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from roadgaze.errors import RoadgazeError

FOURCC_BY_SUFFIX = {".mp4": "mp4v", ".avi": "MJPG", ".mkv": "FFV1"}
"""Codec per container: MPEG-4 Part 2 in .mp4, Motion JPEG in .avi, lossless FFV1 in .mkv."""


def open_video_writer(
    path: Path, fps: float, size: tuple[int, int], fourcc: str, what: str = "video"
) -> Any:
    """An open `cv2.VideoWriter` for `path` (folders created); RoadgazeError when it cannot open.

    `size` is (width, height) in pixels.
    """
    import cv2

    fps = fps if math.isfinite(fps) and fps > 0 else 30.0
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RoadgazeError(f"cannot write {what} {path}: {exc.strerror or exc}") from None
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*fourcc), fps, size)
    if not writer.isOpened():
        allowed = ", ".join(f"{suffix} ({code})" for suffix, code in FOURCC_BY_SUFFIX.items())
        raise RoadgazeError(
            f"cannot write {what} {path}: OpenCV cannot encode {fourcc} there; check the folder "
            f"and use one of {allowed}"
        )
    return writer
