"""`open_source`: the frame source a user names on the command line."""

from __future__ import annotations

from pathlib import Path

from roadgaze.capture.base import FrameSource
from roadgaze.capture.camera import CameraSource, camera_device
from roadgaze.capture.files import ImageFolderSource, VideoFileSource
from roadgaze.capture.mcap import McapSource, is_mcap
from roadgaze.config import Config
from roadgaze.errors import SourceError


def open_source(
    spec: str, config: Config | None = None, *, wait_for_camera: bool = False
) -> FrameSource:
    """The frame source a user names: an existing file (a video or an MCAP recording), a folder,
    `/dev/videoN` or an index.

    Raises `SourceError` when the string names none of these or the source cannot be opened;
    with `wait_for_camera` a camera that cannot be opened yet is waited for instead (its status
    says so), as the daemon wants.
    """
    config = config if config is not None else Config()
    path = Path(spec).expanduser()
    if path.is_file():
        return open_file(path, config)
    if path.is_dir():
        return ImageFolderSource(path, fps=config.capture.fps)
    device = camera_device(spec)
    if device is not None:
        return CameraSource(device, config.capture, wait_for_device=wait_for_camera)
    raise SourceError(
        f"no video file, image folder or camera '{spec}'; pass an existing file or folder, "
        "/dev/videoN or a camera index"
    )


def open_file(path: Path, config: Config | None = None) -> FrameSource:
    """A file as a drive: an MCAP recording (by its magic bytes) or a video file."""
    if is_mcap(path):
        config = config if config is not None else Config()
        return McapSource(path, config.record.camera_topic, config.record.max_chunk_mib)
    return VideoFileSource(path)
