"""Frame times the monitor can trust (`TimeBase`, `VideoFileSource`): issue 24's corrupt clocks.

An mp4 whose sample durations are 0 turned 2 s into 118 s and raised critical alerts; a
container with a frame rate of 0 was read at an assumed rate. Here: each kind of bad timestamp
(backwards, stall, jump, missing) against sane and unusable rates, a fuzz of container clocks
(hypothesis) against the promises of the time base, and the 1x1 video.
"""

from __future__ import annotations

import itertools
import logging
import math
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fakes import FakeCamera, numbered_image
from roadgaze.capture import CameraSource, ImageFolderSource, VideoFileSource
from roadgaze.capture.timebase import (
    JUMP_MIN_S,
    JUMP_PERIODS,
    TimeBase,
    sane_fps,
)
from roadgaze.config import CaptureConfig
from roadgaze.errors import SourceError


def times_of(fps: float | None, container: list[float | None]) -> list[float]:
    base = TimeBase("clip.mp4", fps)
    return [base.t_s(index, t_s) for index, t_s in enumerate(container)]


def test_good_container_times_are_kept_as_they_are() -> None:
    variable = [0.0, 0.033, 0.07, 0.1, 0.5, 0.533]  # a 0.4 s hiccup is below a jump
    assert times_of(30.0, variable) == variable


@pytest.mark.parametrize(
    ("container", "says"),
    [
        ([0.0, 0.04, 0.08, 0.06, 0.1], "go backwards at frame 3"),
        ([0.0, 0.04, 0.04, 0.12], "stall at frame 2"),
        ([0.0, 0.04, 2.0, 4.0], "jump 1.960 s at frame 2"),
        ([0.0, 0.04, None, 0.12], "frame 2 has no valid timestamp"),
    ],
    ids=["backwards", "stall", "jump", "missing"],
)
def test_a_bad_timestamp_switches_to_frame_index_time_with_one_warning(
    container: list[float | None], says: str, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING)
    base = TimeBase("clip.mp4", 25.0)
    times = [base.t_s(index, t_s) for index, t_s in enumerate([*container, 9.0, 0.0])]
    assert times[:2] == [0.0, 0.04]
    np.testing.assert_allclose(times[2:], 0.04 + 0.04 * np.arange(1, len(times) - 1))
    assert base.flagged and says in (base.fallback_reason or "")
    assert len(caplog.records) == 1 and "timing frames from their index at" in caplog.text


@pytest.mark.parametrize("fps", [None, 0.0, math.nan, -25.0, 1000.0])
def test_no_usable_rate_and_a_bad_timestamp_is_refused_in_one_line(
    fps: float | None, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING)
    base = TimeBase("clip.mp4", fps)
    assert "no usable frame rate" in caplog.text  # said at once, never assumed silently
    assert [base.t_s(i, t) for i, t in enumerate([0.0, 0.1, 0.2, 0.3])] == [0.0, 0.1, 0.2, 0.3]
    with pytest.raises(SourceError, match=r"stall at frame 4.*no usable frame rate") as caught:
        base.t_s(4, 0.3)
    assert "\n" not in str(caught.value) and "re-encode" in str(caught.value)
    with pytest.raises(SourceError, match=r"step 118\.000 s at frame 5"):
        _jump_without_rate(fps)


def _jump_without_rate(fps: float | None) -> float:
    """Steps of 0.1 s, then one of 118 s: over 1 s (no rate to judge it by)."""
    base = TimeBase("x", fps)
    for index, t_s in enumerate([0.0, 0.1, 0.2, 0.3, 0.4]):
        base.t_s(index, t_s)
    return base.t_s(5, 118.4)


def test_the_issues_clip_two_seconds_read_as_118_is_timed_by_its_frames() -> None:
    container = [index * 118.0 / 60 for index in range(60)]  # 2 s at 30 fps, clock 59x too fast
    times = times_of(30.0, container)
    assert times[-1] == pytest.approx(59 / 30)


@st.composite
def clocks(draw: st.DrawFn) -> tuple[float | None, list[float | None]]:
    fps = draw(
        st.one_of(
            st.none(),
            st.sampled_from([0.0, math.nan, math.inf, -1.0, 0.5, 1e6]),
            st.floats(1.0, 240.0),
        )
    )
    steps = draw(
        st.lists(
            st.one_of(
                st.floats(0.001, 0.1),  # ordinary frame steps
                st.sampled_from([0.0, -0.05, -10.0, 5.0, 1e9, math.nan, math.inf]),
                st.none(),  # no timestamp
            ),
            min_size=1,
            max_size=60,
        )
    )
    start = draw(st.floats(0.0, 10.0))
    container: list[float | None] = [start]
    for step in steps:
        previous = next((t for t in reversed(container) if t is not None), start)
        container.append(None if step is None else previous + step)
    return fps, container


@settings(max_examples=300, deadline=None)
@given(clocks())
def test_fuzzed_container_clocks_give_trusted_times_or_one_refusal(
    clock: tuple[float | None, list[float | None]],
) -> None:
    """Whatever the container says: times are finite, strictly increasing, and once flagged
    they step by exactly one period of a sane rate; or the source is refused (no usable rate)."""
    fps, container = clock
    base = TimeBase("fuzz.mp4", fps)
    times: list[float] = []
    try:
        for index, t_s in enumerate(container):
            times.append(base.t_s(index, t_s))
    except SourceError as exc:
        assert sane_fps(fps) is None and "no usable frame rate" in str(exc)
        return
    assert all(math.isfinite(t) and t >= 0 for t in times)
    assert all(b > a for a, b in itertools.pairwise(times))
    rate = sane_fps(fps)
    for (a, b), t_s in zip(itertools.pairwise(times), container[1:], strict=True):
        if base.flagged and rate is not None and b != t_s:
            assert b - a == pytest.approx(1.0 / rate)
        elif rate is not None:
            assert b - a <= max(JUMP_PERIODS / rate, JUMP_MIN_S) + 1e-9


class ClockCapture:
    """A capture whose container reports `times_ms` (POS_MSEC) and `fps`."""

    def __init__(self, times_ms: list[float], fps: float, size: int = 32) -> None:
        self.times_ms, self.fps, self.size = list(times_ms), fps, size
        self.read_count = 0

    def isOpened(self) -> bool:  # noqa: N802
        return True

    def read(self) -> tuple[bool, Any]:
        if self.read_count >= len(self.times_ms):
            return False, None
        self.read_count += 1
        return True, numbered_image(self.read_count, (self.size, self.size))

    def get(self, prop_id: int) -> float:
        if prop_id == cv2.CAP_PROP_POS_MSEC:
            return self.times_ms[max(0, self.read_count - 1)]
        values = {cv2.CAP_PROP_FPS: self.fps, cv2.CAP_PROP_FRAME_COUNT: len(self.times_ms)}
        return float(values.get(prop_id, 0.0))

    def set(self, prop_id: int, value: float) -> bool:
        return True

    def release(self) -> None:
        return None


def test_a_video_with_durations_of_zero_and_rate_zero_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "zero.mp4"
    path.write_bytes(b"x")
    source = VideoFileSource(path, capture_factory=lambda name: ClockCapture([0.0] * 5, 0.0))
    assert source.info.fps is None
    with source, pytest.raises(SourceError, match="stall at frame 1"):
        list(source)


def test_a_video_with_jumping_times_and_a_sane_rate_says_so_in_its_status(tmp_path: Path) -> None:
    path = tmp_path / "jumps.mp4"
    path.write_bytes(b"x")
    times_ms = [0.0, 40.0, 80.0, 3000.0, 6000.0]
    with VideoFileSource(path, capture_factory=lambda n: ClockCapture(times_ms, 25.0)) as source:
        times = [frame.t_s for frame in source]
    np.testing.assert_allclose(times, [0.0, 0.04, 0.08, 0.12, 0.16])
    assert "jump 2.920 s at frame 3" in (source.status.message or "")


def test_a_one_pixel_video_blames_the_video(tmp_path: Path) -> None:
    path = tmp_path / "dot.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (1, 1))
    for _ in range(3):
        writer.write(np.zeros((1, 1, 3), np.uint8))
    writer.release()
    with pytest.raises(SourceError, match=r"dot.avi is 1x1 pixels: too small to hold a face"):
        VideoFileSource(path)


def test_the_issues_mp4_with_sample_durations_of_zero_is_refused_at_its_second_frame(
    tmp_path: Path,
) -> None:
    """2 s at 30 fps whose `stts` sample durations are patched to 0: FFmpeg reads 0.5 fps and
    a frame every 2 s (118 s in all), which raised critical alerts before."""
    import struct

    good = tmp_path / "good.mp4"
    writer = cv2.VideoWriter(str(good), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (64, 48))
    for index in range(60):
        writer.write(np.full((48, 64, 3), index * 4, np.uint8))
    writer.release()
    data = bytearray(good.read_bytes())
    stts = data.find(b"stts")
    for entry in range(struct.unpack(">I", data[stts + 8 : stts + 12])[0]):
        struct.pack_into(">I", data, stts + 16 + 8 * entry, 0)  # sample_delta = 0
    corrupt = tmp_path / "zero_durations.mp4"
    corrupt.write_bytes(bytes(data))
    with VideoFileSource(good) as source:
        assert [frame.t_s for frame in source][-1] == pytest.approx(59 / 30)
    with VideoFileSource(corrupt) as source, pytest.raises(SourceError) as caught:
        list(source)
    assert "timestamps step 2.000 s at frame 1" in str(caught.value)
    assert "no usable frame rate (0.5 fps)" in str(caught.value)


def test_an_avi_whose_header_gives_a_rate_of_zero_is_refused_not_read_at_25_fps(
    tmp_path: Path,
) -> None:
    """The issue: such a file was read at FFmpeg's assumed 25 fps (timers 18 % off), silently."""
    import struct

    path = tmp_path / "rate0.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (64, 48))
    for index in range(10):
        writer.write(np.full((48, 64, 3), index * 20, np.uint8))
    writer.release()
    data = bytearray(path.read_bytes())
    with VideoFileSource(path) as source:
        assert source.info.fps == 30.0
    header = data.find(b"strh")
    struct.pack_into("<I", data, header + 32, 0)  # the video stream's dwRate
    path.write_bytes(bytes(data))
    with VideoFileSource(path) as source:  # FFmpeg takes the main header's period: fine
        assert source.info.fps == pytest.approx(30.0, rel=1e-3)
    struct.pack_into("<I", data, data.find(b"avih") + 8, 0)  # dwMicroSecPerFrame
    path.write_bytes(bytes(data))
    assert cv2.VideoCapture(str(path), cv2.CAP_FFMPEG).get(cv2.CAP_PROP_FPS) == 25.0
    with pytest.raises(SourceError, match=r"rate0\.avi: its AVI header gives no frame rate"):
        VideoFileSource(path)


def joined_times(fps: float | None, stamps: list[float | None]) -> tuple[list[float], Any]:
    from roadgaze.capture.timebase import JoinedTimeBase

    base = JoinedTimeBase("drive.mcap", fps)
    return [base.t_s(index, t_s) for index, t_s in enumerate(stamps)], base


@pytest.mark.parametrize(
    ("stamps", "joined", "breaks", "says"),
    [
        # One frame stamped 10^12 s ahead (a hostile file): that frame and the one after it
        # come back onto the drive's own spacing.
        ([0.0, 0.2, 0.4, 1e12, 0.8, 1.0], [0.0, 0.2, 0.4, 0.6, 0.8, 1.0], 2, "jump 999999999999.6"),
        # The vehicle's clock stepped an hour ahead mid-drive (NTP): joined once, spacing kept.
        ([10.0, 10.2, 10.4, 3610.6, 3610.8], [10.0, 10.2, 10.4, 10.6, 10.8], 1, "jump 3600.200 s"),
        # ... and back.
        (
            [10.0, 10.2, 10.4, 5.0, 5.2],
            [10.0, 10.2, 10.4, 10.6, 10.8],
            1,
            "go backwards at frame 3",
        ),
        ([0.0, 0.2, 0.2, 0.6], [0.0, 0.2, 0.4, 0.8], 1, "stall at frame 2"),
        ([0.0, 0.2, None, 0.6], [0.0, 0.2, 0.4, 0.6], 1, "frame 2 has no valid timestamp"),
        ([0.0, 0.2, math.inf, 0.6], [0.0, 0.2, 0.4, 0.6], 1, "frame 2 has no valid timestamp"),
    ],
    ids=["hostile-frame", "clock-step-ahead", "clock-step-back", "stall", "missing", "infinite"],
)
def test_a_recordings_clock_is_joined_across_a_break_with_one_warning(
    stamps: list[float | None],
    joined: list[float],
    breaks: int,
    says: str,
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING)
    times, base = joined_times(5.0, stamps)
    np.testing.assert_allclose(times, joined, atol=1e-6)
    assert base.breaks == breaks and says in (base.first_break or "")
    assert len(caplog.records) == 1 and "the clock goes on from there" in caplog.text


@pytest.mark.parametrize("fps", [None, 0.0, math.nan, 1e9, 0.5])
def test_a_sparse_recording_keeps_its_times_and_a_gap_in_its_frames_is_joined(
    fps: float | None,
) -> None:
    """Frames 2 s apart (a recording at 0.5 fps) are the drive's own times, whatever the
    summary's rate says; 3 s without a frame in frames 0.2 s apart (frames lost while
    recording) is unseen time, joined like any jump: never judged by the monitor."""
    sparse = [100.0 + 2.0 * index for index in range(8)]
    assert joined_times(fps, sparse)[0] == sparse
    gapped = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 4.0, 4.2]
    times, base = joined_times(fps, gapped)
    np.testing.assert_allclose(times, [0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.4], atol=1e-9)
    assert base.breaks == 1 and "jump 3.000 s at frame 6" in (base.first_break or "")


@settings(max_examples=300, deadline=None)
@given(clocks())
def test_fuzzed_recording_clocks_are_increasing_and_never_jump(
    clock: tuple[float | None, list[float | None]],
) -> None:
    """Whatever the stamps: times are finite, strictly increasing, and no jump gets through
    (nothing for the monitor's timers to run across)."""
    fps, stamps = clock
    times = joined_times(fps, stamps)[0]
    assert all(math.isfinite(t) and t >= 0 for t in times)
    assert all(b > a for a, b in itertools.pairwise(times))
    longest_step_s = 5.0  # of the ordinary steps the clocks draw; 10^9, inf, NaN never pass
    assert all(b - a <= longest_step_s + 1e-3 for a, b in itertools.pairwise(times))


@pytest.mark.parametrize("fps", [0.0, -30.0, 0.001, 1e9, math.nan, math.inf])
def test_an_image_folder_needs_a_rate_that_can_time_it(tmp_path: Path, fps: float) -> None:
    """A folder's images are timed index / capture.fps: 0.001 fps would put 1000 s between two
    images and the monitor's timers would run across them."""
    cv2.imwrite(str(tmp_path / "a.png"), numbered_image(1))
    with pytest.raises(SourceError, match=r"capture.fps .* cannot time its images") as caught:
        ImageFolderSource(tmp_path, fps=fps)
    assert "\n" not in str(caught.value)


def test_a_camera_read_that_hangs_is_said_and_its_time_kept() -> None:
    """The camera's clock is the machine's monotonic clock: a read that hangs 5 s gives a real
    5 s gap (kept, so recordings stay on the wall clock), said in a warning and the status."""
    now = [100.0]
    reads = [0]

    class HangingCamera(FakeCamera):
        def read(self) -> tuple[bool, Any]:
            reads[0] += 1
            if reads[0] <= 12:
                now[0] += 5.0 if reads[0] == 6 else 1 / 30
            return super().read()

    source = CameraSource(
        0, CaptureConfig(fps=30), capture_factory=lambda d: HangingCamera(12), clock=lambda: now[0]
    )
    with source:
        frames = []
        for frame in source:
            frames.append(frame)
            if frame.index >= 8:
                break
        status = source.status
    steps = [b.t_s - a.t_s for a, b in itertools.pairwise(frames)]
    assert any(step >= 5.0 for step in steps)  # kept, not joined
    assert "delivered no frame for 5.0 s (a read that hung)" in (status.message or "")
