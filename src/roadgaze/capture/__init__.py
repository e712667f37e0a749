"""Capture: frame sources behind one Protocol (video file, image folder, V4L2 camera, loop)."""

from roadgaze.capture.base import (
    FrameSource,
    SourceInfo,
    SourceStatus,
    VideoCaptureLike,
    as_bgr,
)
from roadgaze.capture.camera import CameraSource, camera_device
from roadgaze.capture.files import IMAGE_SUFFIXES, ImageFolderSource, LoopingSource, VideoFileSource
from roadgaze.capture.open import open_source
from roadgaze.capture.readahead import READ_AHEAD_FRAMES, ReadAhead

__all__ = [
    "IMAGE_SUFFIXES",
    "READ_AHEAD_FRAMES",
    "CameraSource",
    "FrameSource",
    "ImageFolderSource",
    "LoopingSource",
    "ReadAhead",
    "SourceInfo",
    "SourceStatus",
    "VideoCaptureLike",
    "VideoFileSource",
    "as_bgr",
    "camera_device",
    "open_source",
]
