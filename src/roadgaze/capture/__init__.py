"""Capture: frame sources behind one Protocol (video, MCAP recording, image folder, V4L2, loop)."""

from roadgaze.capture.base import (
    FrameSource,
    SourceInfo,
    SourceStatus,
    VideoCaptureLike,
    as_bgr,
)
from roadgaze.capture.camera import CameraSource, camera_device
from roadgaze.capture.files import IMAGE_SUFFIXES, ImageFolderSource, LoopingSource, VideoFileSource
from roadgaze.capture.mcap import McapSource, is_mcap
from roadgaze.capture.open import open_file, open_source

__all__ = [
    "IMAGE_SUFFIXES",
    "CameraSource",
    "FrameSource",
    "ImageFolderSource",
    "LoopingSource",
    "McapSource",
    "SourceInfo",
    "SourceStatus",
    "VideoCaptureLike",
    "VideoFileSource",
    "as_bgr",
    "camera_device",
    "is_mcap",
    "open_file",
    "open_source",
]
