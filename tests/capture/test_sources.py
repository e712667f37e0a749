"""Frame sources on real files written by OpenCV, and the V4L2 camera with a fake capture."""

from __future__ import annotations

import itertools
import threading
import time
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from fakes import FakeCamera, numbered_image
from repo_paths import VIDEOS
from roadgaze.capture import (
    CameraSource,
    ImageFolderSource,
    LoopingSource,
    VideoFileSource,
    camera_device,
    open_source,
)
from roadgaze.config import CaptureConfig, Config
from roadgaze.errors import SourceError


def write_video(path: Path, frames: int, fps: float, fourcc: str) -> Path:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*fourcc), fps, (160, 120))
    assert writer.isOpened()
    for i in range(frames):
        writer.write(numbered_image(i))
    writer.release()
    return path


@pytest.mark.parametrize(
    ("name", "fourcc", "fps"),
    [("clip.avi", "MJPG", 25.0), ("clip.mp4", "mp4v", 30.0), ("clip.mkv", "FFV1", 15.0)],
)
def test_video_file_delivers_every_frame_with_container_times(
    tmp_path: Path, name: str, fourcc: str, fps: float
) -> None:
    path = write_video(tmp_path / name, 40, fps, fourcc)
    with VideoFileSource(path) as source:
        assert source.info.frame_count == 40
        assert source.info.fps == pytest.approx(fps)
        assert (source.info.width, source.info.height) == (160, 120)
        assert not source.info.live
        frames = list(source)
    assert [f.index for f in frames] == list(range(40))
    times = np.array([f.t_s for f in frames])
    assert np.all(np.diff(times) > 0)
    np.testing.assert_allclose(times, np.arange(40) / fps, atol=0.002)
    assert frames[0].image.shape == (120, 160, 3)
    assert frames[0].image.dtype == np.uint8
    assert source.status.frames_delivered == 40
    assert source.status.ended and not source.status.truncated


@pytest.mark.parametrize("suffix", ["avi", "mkv"])
def test_truncated_file_processes_what_is_readable_and_reports_the_stop(
    tmp_path: Path, suffix: str
) -> None:
    fourcc = {"avi": "MJPG", "mkv": "FFV1"}[suffix]
    whole = write_video(tmp_path / f"whole.{suffix}", 30, 30.0, fourcc).read_bytes()
    cut = tmp_path / f"cut.{suffix}"
    cut.write_bytes(whole[: int(len(whole) * 0.6)])
    with VideoFileSource(cut) as source:
        frames = list(source)
    assert 5 < len(frames) < 30
    status = source.status
    assert status.truncated
    assert status.message is not None
    assert f"read {len(frames)} of 30" in status.message
    assert f"t={frames[-1].t_s:.3f} s" in status.message


def test_mp4_truncated_before_its_index_is_one_clear_error(tmp_path: Path) -> None:
    whole = write_video(tmp_path / "whole.mp4", 30, 30.0, "mp4v").read_bytes()
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(whole[: len(whole) // 2])
    with pytest.raises(SourceError, match="cannot read video"):
        VideoFileSource(cut)


@pytest.mark.parametrize(
    ("content", "message"),
    [(b"", "cannot read video"), (b"not a video at all" * 200, "cannot read video")],
)
def test_corrupt_file_is_one_clear_error(tmp_path: Path, content: bytes, message: str) -> None:
    path = tmp_path / "bad.mp4"
    path.write_bytes(content)
    with pytest.raises(SourceError, match=message):
        VideoFileSource(path)


def test_missing_file_is_one_clear_error(tmp_path: Path) -> None:
    with pytest.raises(SourceError, match="not found"):
        VideoFileSource(tmp_path / "nope.mp4")


@pytest.mark.skipif(not VIDEOS.is_dir(), reason="no evaluation videos ($ROADGAZE_DATA)")
def test_animated_gif_frames_and_times() -> None:
    with VideoFileSource(VIDEOS / "head-pose-face-detection-female.gif") as source:
        frames = list(source)
    assert len(frames) == 23
    times = [f.t_s for f in frames]
    assert times[0] == 0.0
    assert all(b > a for a, b in itertools.pairwise(times))
    assert times[-1] == pytest.approx(1.83, abs=0.01)


class StuckClockCapture:
    """A capture whose container time never advances (some streams report 0 throughout)."""

    def __init__(self, frames: int) -> None:
        self.left = frames

    def isOpened(self) -> bool:  # noqa: N802
        return True

    def read(self) -> tuple[bool, Any]:
        if self.left == 0:
            return False, None
        self.left -= 1
        return True, numbered_image(self.left)

    def get(self, prop_id: int) -> float:
        return {cv2.CAP_PROP_FPS: 20.0, cv2.CAP_PROP_FRAME_COUNT: 5.0}.get(prop_id, 0.0)

    def set(self, prop_id: int, value: float) -> bool:
        return True

    def release(self) -> None:
        return None


def test_non_increasing_container_times_are_replaced_by_the_nominal_period(
    tmp_path: Path,
) -> None:
    path = tmp_path / "any.avi"
    path.write_bytes(b"x")
    with VideoFileSource(path, capture_factory=lambda name: StuckClockCapture(5)) as source:
        times = [f.t_s for f in source]
    np.testing.assert_allclose(times, [0.0, 0.05, 0.1, 0.15, 0.2])


def test_image_folder_in_name_order_skipping_unreadable_images(tmp_path: Path) -> None:
    for i in (2, 0, 1):
        cv2.imwrite(str(tmp_path / f"img{i}.png"), numbered_image(i))
    (tmp_path / "img1b.jpg").write_bytes(b"broken")
    (tmp_path / "notes.txt").write_text("not an image")
    with ImageFolderSource(tmp_path, fps=10.0) as source:
        frames = list(source)
    assert source.info.frame_count == 4
    assert [f.index for f in frames] == [0, 1, 2]
    np.testing.assert_allclose([f.t_s for f in frames], [0.0, 0.1, 0.3])
    np.testing.assert_array_equal(frames[2].image, numbered_image(2))
    assert source.status.frames_skipped == 1


def test_empty_folder_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(SourceError, match="holds no image"):
        ImageFolderSource(tmp_path)


def test_looping_source_keeps_time_increasing_across_passes(tmp_path: Path) -> None:
    path = write_video(tmp_path / "clip.avi", 10, 10.0, "MJPG")
    with LoopingSource(lambda: VideoFileSource(path), passes=3) as source:
        frames = list(source)
    assert [f.index for f in frames] == list(range(30))
    times = np.array([f.t_s for f in frames])
    np.testing.assert_allclose(times, np.arange(30) / 10.0, atol=0.002)


def test_open_source_decides_from_the_string(tmp_path: Path) -> None:
    video = write_video(tmp_path / "clip.avi", 3, 10.0, "MJPG")
    folder = tmp_path / "stills"
    folder.mkdir()
    cv2.imwrite(str(folder / "a.png"), numbered_image(0))
    with open_source(str(video), Config()) as source:
        assert isinstance(source, VideoFileSource)
    with open_source(str(folder), Config()) as source:
        assert isinstance(source, ImageFolderSource)
    with pytest.raises(SourceError, match="no video file, image folder or camera"):
        open_source(str(tmp_path / "missing.mp4"), Config())


@pytest.mark.parametrize(
    ("spec", "device"),
    [("0", 0), ("12", 12), ("/dev/video3", "/dev/video3"), ("/dev/sda", None), ("cam", None)],
)
def test_camera_device_parsing(spec: str, device: int | str | None) -> None:
    assert camera_device(spec) == device


def test_camera_settings_are_applied_in_v4l2_order() -> None:
    calls: list[Any] = []
    config = CaptureConfig(width=800, height=600, fps=25.0, fourcc="MJPG")
    devices: list[Any] = []

    def factory(device: int | str) -> FakeCamera:
        devices.append(device)
        return FakeCamera(None, log=calls)

    with CameraSource("/dev/video5", config, capture_factory=factory) as source:
        assert source.info.live
        assert source.info.frame_count is None
        first = next(iter(source))
    assert devices == ["/dev/video5"]
    assert calls[:5] == [
        (cv2.CAP_PROP_FOURCC, float(cv2.VideoWriter.fourcc(*"MJPG"))),
        (cv2.CAP_PROP_FRAME_WIDTH, 800.0),
        (cv2.CAP_PROP_FRAME_HEIGHT, 600.0),
        (cv2.CAP_PROP_FPS, 25.0),
        (cv2.CAP_PROP_BUFFERSIZE, 1.0),
    ]
    assert calls[-1] == "release"
    assert first.image.shape == (120, 160, 3)
    assert first.t_s >= 0.0


def test_camera_that_cannot_open_is_one_clear_error() -> None:
    with pytest.raises(SourceError, match="cannot open camera 7"):
        CameraSource(7, capture_factory=lambda device: FakeCamera(None, opened=False))


def test_lost_camera_is_reported_retried_with_backoff_and_resumed() -> None:
    calls: list[Any] = []
    opens = iter(
        [
            FakeCamera(5, log=calls),  # delivers 5 frames, then every read fails
            FakeCamera(None, opened=False, log=calls),
            FakeCamera(None, opened=False, log=calls),
            FakeCamera(None, log=calls),  # back
        ]
    )
    sleeps: list[float] = []
    config = CaptureConfig(reconnect_initial_s=0.25, reconnect_max_s=0.6)
    source = CameraSource(
        0, config, capture_factory=lambda device: next(opens), sleep=sleeps.append
    )
    with source:
        frames = []
        deadline = time.monotonic() + 10.0
        for frame in source:
            frames.append(frame)
            if source.status.reconnects >= 1 and len(frames) >= 8:
                break
            assert time.monotonic() < deadline, "camera never came back"
        status = source.status
    assert sleeps[:3] == [0.25, 0.5, 0.6]
    assert status.reconnects == 1
    assert status.connected
    assert status.message is not None and "reconnected" in status.message
    times = [f.t_s for f in frames]
    assert all(b > a for a, b in itertools.pairwise(times))


def test_slow_consumer_gets_the_newest_frame_and_drops_are_counted() -> None:
    calls: list[Any] = []
    with CameraSource(0, capture_factory=lambda device: FakeCamera(None, log=calls)) as source:
        taken = []
        for frame in source:
            taken.append(frame)
            time.sleep(0.03)  # ~15 camera frames per consumed frame
            if len(taken) == 5:
                break
        status = source.status
    indices = [f.index for f in taken]
    assert all(b - a > 1 for a, b in itertools.pairwise(indices))
    assert status.frames_dropped >= indices[-1] - len(indices)
    assert status.frames_delivered == 5


def test_camera_close_stops_the_grab_thread() -> None:
    before = threading.active_count()
    source = CameraSource(0, capture_factory=lambda device: FakeCamera(None))
    assert threading.active_count() == before + 1
    source.close()
    assert threading.active_count() == before


def test_a_camera_waited_for_is_unavailable_then_opens_on_the_same_backoff() -> None:
    opens = iter(
        [
            FakeCamera(None, opened=False),  # not there at start
            FakeCamera(None, opened=False),
            FakeCamera(None),  # plugged in
        ]
    )
    sleeps: list[float] = []
    plugged_in = threading.Event()

    def sleep(seconds: float) -> None:
        sleeps.append(seconds)
        plugged_in.wait(5.0)

    config = CaptureConfig(reconnect_initial_s=0.25, reconnect_max_s=10.0)
    source = CameraSource(
        0, config, capture_factory=lambda device: next(opens), sleep=sleep, wait_for_device=True
    )
    first = source.status
    plugged_in.set()
    with source:
        frame = next(iter(source))
        status = source.status
    assert (first.state, first.connected) == ("unavailable", False)
    assert first.message is not None and first.message.startswith("camera unavailable: ")
    assert sleeps[:2] == [0.25, 0.5]
    assert (status.state, status.reopen_attempts, status.reconnects) == ("open", 2, 1)
    assert frame.t_s > 0.0  # one timeline from when the source was created
