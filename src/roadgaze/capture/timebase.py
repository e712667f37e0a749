"""Frame times a monitor can trust: container timestamps checked against the container's rate.

The monitor's timers (a 3 s glance, a 30 s window) run on frame times, so a corrupt container
clock raises or hides alerts. `TimeBase` checks each frame's container timestamp against the
previous one: going backwards, standing still (a stall), a step shorter than one period at
`MAX_FPS`, or a jump far beyond one frame period (more than `JUMP_PERIODS` periods and more than
`JUMP_MIN_S`; without a usable rate, any step over `JUMP_MIN_S`) flags it. On the first flag it
falls back to frame-index time (`index / fps`, continuing from the last good time) when the
container's frame rate is sane (`MIN_FPS`..`MAX_FPS`), and says so once; with no sane rate
either it raises `SourceError` (neither clock can time the monitor). A missing timestamp counts
as a flag too. `JoinedTimeBase` checks a recording's own stamps (an MCAP drive) by the same
rule and joins each break instead (its frames need not be evenly spaced). Pure: no OpenCV.
"""

from __future__ import annotations

import logging
import math
import statistics
import struct
from collections import deque
from pathlib import Path

from roadgaze.errors import SourceError

log = logging.getLogger("roadgaze.capture")

MIN_FPS = 1.0
MAX_FPS = 240.0
"""A container frame rate outside this range (or 0, NaN, missing) is not used for timing."""
JUMP_PERIODS = 10.0
JUMP_MIN_S = 1.0
"""A step between two frames is a jump when it exceeds both JUMP_PERIODS frame periods and
JUMP_MIN_S seconds (a variable-rate recording's hiccup stays below)."""

PERIOD_WINDOW = 31
"""A recording's frame period is the median of this many last accepted steps."""

AVI_HEADER_BYTES = 16 * 1024
"""How much of an AVI file is read for its stream headers."""


def sane_fps(fps: float | None) -> float | None:
    """`fps` when it can time frames (finite, MIN_FPS..MAX_FPS), else None."""
    if fps is None or not math.isfinite(fps) or not MIN_FPS <= fps <= MAX_FPS:
        return None
    return fps


def is_jump(step_s: float, period_s: float) -> bool:
    """Whether a step between two frames is a jump: beyond JUMP_PERIODS periods and
    JUMP_MIN_S."""
    return step_s > JUMP_PERIODS * period_s and step_s > JUMP_MIN_S


def step_problem(
    index: int, previous_t_s: float | None, t_s: float | None, period_s: float | None
) -> str | None:
    """What is wrong with frame `index`'s time `t_s` after `previous_t_s` (None: it is the
    first), or None when nothing is. A step is a jump beyond JUMP_PERIODS periods of `period_s`
    and JUMP_MIN_S; without a period, beyond JUMP_MIN_S."""
    if t_s is None or not math.isfinite(t_s) or t_s < 0:
        return f"frame {index} has no valid timestamp"
    if previous_t_s is None:
        return None
    step_s = t_s - previous_t_s
    if step_s < 0:
        return f"timestamps go backwards at frame {index} ({previous_t_s:.3f} s -> {t_s:.3f} s)"
    if step_s == 0:
        return f"timestamps stall at frame {index} (t = {t_s:.3f} s twice)"
    if step_s < 1.0 / MAX_FPS:
        return f"timestamps step only {step_s * 1000:.3f} ms at frame {index}"
    if period_s is None:
        return f"timestamps step {step_s:.3f} s at frame {index}" if step_s > JUMP_MIN_S else None
    if is_jump(step_s, period_s):
        return (
            f"timestamps jump {step_s:.3f} s at frame {index}, {step_s / period_s:.0f} "
            f"periods of {1.0 / period_s:g} fps"
        )
    return None


class TimeBase:
    """Turns container timestamps into trusted, strictly increasing frame times (seconds).

    `name` names the source in messages; `fps` is the container's nominal frame rate (any value:
    it is checked here). `fallback_reason` says why frame-index time is used, once it is.
    """

    def __init__(self, name: str, fps: float | None) -> None:
        self.name = name
        self.container_fps = fps
        self.fps = sane_fps(fps)
        self.fallback_reason: str | None = None
        self._index_origin = 0
        self._time_origin_s = 0.0
        self._previous_t_s: float | None = None
        if self.fps is None:
            log.warning(
                "%s: its container gives no usable frame rate (%s): frames are timed by their "
                "timestamps alone; a bad timestamp will stop the replay",
                name,
                "none" if fps is None else f"{fps:g} fps",
            )

    @property
    def flagged(self) -> bool:
        """True once the container's timestamps were found bad (frame-index time in use)."""
        return self.fallback_reason is not None

    def t_s(self, index: int, container_t_s: float | None) -> float:
        """The trusted time of frame `index` (0-based, every frame counted) whose container
        timestamp is `container_t_s` (None when the container gives none). Raises SourceError
        when the timestamp is bad and the container's rate cannot replace it."""
        if self.fallback_reason is None:
            problem = self._problem(index, container_t_s)
            if problem is None:
                assert container_t_s is not None
                self._accept(container_t_s)
                return container_t_s
            self._fall_back(index, problem)
        assert self.fps is not None
        t_s = self._time_origin_s + (index - self._index_origin) / self.fps
        self._previous_t_s = t_s
        return t_s

    def _accept(self, t_s: float) -> None:
        self._previous_t_s = t_s

    def _problem(self, index: int, t_s: float | None) -> str | None:
        period_s = None if self.fps is None else 1.0 / self.fps
        return step_problem(index, self._previous_t_s, t_s, period_s)

    def _fall_back(self, index: int, problem: str) -> None:
        if self.fps is None:
            rate = "none" if self.container_fps is None else f"{self.container_fps:g} fps"
            raise SourceError(
                f"video {self.name}: {problem}, and its container gives no usable frame rate "
                f"({rate}): neither can time the monitor; re-encode it with a constant rate, "
                "e.g. ffmpeg -i IN -r 30 OUT.mp4"
            )
        self.fallback_reason = problem
        self._index_origin = index
        previous = self._previous_t_s
        self._time_origin_s = 0.0 if previous is None else previous + 1.0 / self.fps
        log.warning(
            "%s: %s: timing frames from their index at the container's %g fps from here on "
            "(the monitor's timers never run on the bad timestamps)",
            self.name,
            problem,
            self.fps,
        )


class JoinedTimeBase:
    """Frame times from a recording's own stamps (an MCAP drive), joined across breaks.

    A recording's frames are not evenly spaced (frames dropped while recording, a slow image
    rate), so a break is not replaced by frame-index time as in `TimeBase`: each stamp is
    checked against the previous frame's time by `step_problem`, with the period of the last
    accepted steps (their median; before any, `fps` when sane, else 1 s). A bad step (backwards,
    a stall, a missing stamp, or a jump: a clock stepped on the vehicle, a hostile file) never
    reaches the monitor: that frame is timed one period after the previous frame and the
    frames after it keep their own spacing from there (the clock is re-based). The first break
    is logged (and kept in `first_break`), the count in `breaks`. Pure.
    """

    def __init__(self, name: str, fps: float | None) -> None:
        self.name = name
        rate = sane_fps(fps)
        self._seed_period_s = 1.0 / rate if rate is not None else 1.0 / MIN_FPS
        self._steps_s: deque[float] = deque(maxlen=PERIOD_WINDOW)
        self._shift_s = 0.0
        self._previous_t_s: float | None = None
        self.breaks = 0
        self.first_break: str | None = None

    @property
    def period_s(self) -> float:
        """The recording's frame period: the median of the last accepted steps."""
        return statistics.median(self._steps_s) if self._steps_s else self._seed_period_s

    def t_s(self, index: int, stamp_s: float | None) -> float:
        """The time of frame `index` whose own stamp is `stamp_s` (None when it has none)."""
        t_s = None if stamp_s is None else stamp_s - self._shift_s
        previous = self._previous_t_s
        problem = step_problem(index, previous, t_s, self.period_s)
        if problem is None:
            assert t_s is not None
            if previous is not None:
                self._steps_s.append(t_s - previous)
        else:
            t_s = 0.0 if previous is None else previous + self.period_s
            if stamp_s is not None and math.isfinite(stamp_s):
                self._shift_s = stamp_s - t_s
            self._break(problem)
        self._previous_t_s = t_s
        return t_s

    def _break(self, problem: str) -> None:
        self.breaks += 1
        if self.first_break is None:
            self.first_break = problem
            log.warning(
                "%s: %s: that frame is timed %.3f s after the one before and the clock goes on "
                "from there (the monitor's timers never run across the break; further breaks "
                "are counted)",
                self.name,
                problem,
                self.period_s,
            )


def check_avi_rate(path: Path) -> None:
    """Raise SourceError when `path` is an AVI whose headers give no frame rate (the video
    stream's `dwRate` or `dwScale` 0, and the main header's `dwMicroSecPerFrame` 0): FFmpeg then
    silently assumes 25 fps and invents every frame's
    time from it (AVI has no per-frame times), so no clock could time the monitor. Anything that
    is not such an AVI passes."""
    try:
        with path.open("rb") as stream:
            head = stream.read(AVI_HEADER_BYTES)
    except OSError:
        return  # the capture reports an unreadable file itself
    if head[:4] != b"RIFF" or head[8:12] != b"AVI ":
        return
    at = head.find(b"strh")
    while at >= 0 and head[at + 8 : at + 12] != b"vids":  # the video stream's header
        at = head.find(b"strh", at + 4)
    if at < 0 or len(head) < at + 36:
        return
    scale, rate = struct.unpack_from("<II", head, at + 28)
    main_header = head.find(b"avih")
    frame_us = struct.unpack_from("<I", head, main_header + 8)[0] if main_header >= 0 else 0
    if (scale == 0 or rate == 0) and frame_us == 0:  # FFmpeg falls back on avih's period
        raise SourceError(
            f"video {path}: its AVI header gives no frame rate (dwScale {scale}, dwRate {rate}, "
            f"dwMicroSecPerFrame {frame_us}); "
            "FFmpeg would assume 25 fps and invent every frame's time: neither can time the "
            "monitor; re-encode it with its real rate, e.g. ffmpeg -r 30 -i IN OUT.mp4"
        )
