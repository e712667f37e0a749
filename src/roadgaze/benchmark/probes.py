"""Pipeline sinks that measure: resident memory, throughput after warm-up, capture stamps."""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path

import numpy as np

from roadgaze.types import Frame, FrameRecord, Sink


def resident_mb() -> float:
    """This process's resident memory (VmRSS) in MiB; NaN where /proc is not available."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return float("nan")


def cpu_seconds() -> float:
    """CPU time of this process, all threads (MediaPipe's, decoding, Zenoh's) together."""
    return time.process_time()


class MemoryProbe(Sink):
    """Samples VmRSS about once a second; the baseline is taken after `settle_s` of running."""

    def __init__(self, settle_s: float = 10.0) -> None:
        self._settle_s = settle_s
        self._start = time.monotonic()
        self._next = self._start
        self.baseline_mb: float | None = None
        self.last_mb = resident_mb()
        self.peak_mb = self.last_mb

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        now = time.monotonic()
        if now < self._next:
            return
        self._next = now + 1.0
        self.last_mb = resident_mb()
        self.peak_mb = max(self.peak_mb, self.last_mb)
        if self.baseline_mb is None and now - self._start >= self._settle_s:
            self.baseline_mb = self.last_mb

    def close(self) -> None:
        self.last_mb = resident_mb()

    @property
    def growth_mb(self) -> float | None:
        return None if self.baseline_mb is None else self.last_mb - self.baseline_mb


class ThroughputProbe(Sink):
    """Frames per second and CPU milliseconds per frame after the first `warmup` records.

    The clock starts when record `warmup` (0-based) has been handed to the sinks and stops at the
    last record, so model start-up is excluded and everything else (decoding, every stage, the
    sinks before this one, the loop itself) is included. The newest `capacity` intervals between
    records are kept for `median_interval_ms`, which a shared machine's load spikes move less.
    """

    def __init__(
        self,
        warmup: int,
        clock: Callable[[], float] = time.perf_counter,
        cpu_clock: Callable[[], float] = cpu_seconds,
        capacity: int = 20_000,
    ) -> None:
        self._warmup = warmup
        self._clock = clock
        self._cpu_clock = cpu_clock
        self._seen = 0
        self._start: tuple[float, float] | None = None
        self._last: tuple[float, float] | None = None
        self._intervals_s = np.zeros(capacity)

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self._seen += 1
        if self._seen == self._warmup + 1:
            self._start = (self._clock(), self._cpu_clock())
        elif self._seen > self._warmup + 1:
            now = (self._clock(), self._cpu_clock())
            previous = self._last or self._start
            assert previous is not None
            self._intervals_s[(self.frames - 1) % len(self._intervals_s)] = now[0] - previous[0]
            self._last = now

    def close(self) -> None:
        return None

    @property
    def frames(self) -> int:
        """Frames timed: those after the first one past the warm-up."""
        return max(0, self._seen - self._warmup - 1)

    @property
    def fps(self) -> float | None:
        if self._start is None or self._last is None or self._last[0] <= self._start[0]:
            return None
        return self.frames / (self._last[0] - self._start[0])

    @property
    def median_interval_ms(self) -> float | None:
        """Median time between two records after the warm-up, milliseconds."""
        held = self._intervals_s[: min(self.frames, len(self._intervals_s))]
        return float(np.median(held)) * 1e3 if len(held) else None

    @property
    def cpu_ms_per_frame(self) -> float | None:
        if self._start is None or self._last is None or self.frames == 0:
            return None
        return 1e3 * (self._last[1] - self._start[1]) / self.frames


class CaptureStamps(Sink):
    """Sink keeping, per frame index, when the loop received the frame and when its messages had
    been published (for latency).

    `received_s` reads the first for the current frame (`Pipeline.frame_received_s`); put this
    sink before the publisher and `published_mark` after it. The newest `capacity` frames are
    kept; `pop(index)` takes one out as (received_s, published_s or None), thread-safe.
    """

    def __init__(self, received_s: Callable[[], float], capacity: int = 4096) -> None:
        self._received_s = received_s
        self._capacity = capacity
        self._stamps: OrderedDict[int, list[float | None]] = OrderedDict()
        self._lock = threading.Lock()
        self.published_mark = _PublishedMark(self)

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        stamp = self._received_s()
        with self._lock:
            self._stamps[record.frame] = [stamp, None]
            while len(self._stamps) > self._capacity:
                self._stamps.popitem(last=False)

    def _published(self, index: int, now_s: float) -> None:
        with self._lock:
            entry = self._stamps.get(index)
            if entry is not None:
                entry[1] = now_s

    def pop(self, index: int) -> tuple[float, float | None] | None:
        with self._lock:
            entry = self._stamps.pop(index, None)
        if entry is None or entry[0] is None:
            return None
        return entry[0], entry[1]

    def close(self) -> None:
        return None


class _PublishedMark(Sink):
    """The sink after the publisher: stamps when a frame's messages were handed to Zenoh."""

    def __init__(self, stamps: CaptureStamps) -> None:
        self._stamps = stamps

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self._stamps._published(record.frame, time.perf_counter())

    def close(self) -> None:
        return None
