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

__all__ = [
    "IMAGE_SUFFIXES",
    "CameraSource",
    "FrameSource",
    "ImageFolderSource",
    "LoopingSource",
    "SourceInfo",
    "SourceStatus",
    "VideoCaptureLike",
    "VideoFileSource",
    "as_bgr",
    "camera_device",
    "open_source",
]
