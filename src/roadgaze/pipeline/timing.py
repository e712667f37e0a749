"""Per-stage times of the loop: one frame's (`StageTimes`), a run's ring of them and their stats."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.capture import SourceStatus

STAGES = (
    "decode",
    "enhance",
    "landmarks",
    "handover",
    "geometry",
    "smoothing",
    "monitor",
    "sinks",
    "total",
)
"""Timed stages. `total` is one frame's time in the loop, from asking for it to its last sink; the
stages of successive frames overlap (decoding and MediaPipe run in threads of their own), so the
loop's throughput is set by its slowest thread, not by `total`."""


@dataclass(frozen=True, slots=True)
class StageTimes:
    """Milliseconds spent on one frame per stage."""

    decode_ms: float
    """Waiting for the frame from the source (decoding a file; waiting for a camera frame)."""
    landmarks_ms: float
    """MediaPipe and the features of each face (`infer` and `measure`, on two threads)."""
    geometry_ms: float
    smoothing_ms: float
    monitor_ms: float
    sinks_ms: float
    total_ms: float
    handover_ms: float = 0.0
    """From the end of MediaPipe's work in the landmark thread to the loop taking the frame."""
    enhance_ms: float = 0.0
    """The front end's own time (roadgaze.landmarks.front_end: the decision and, on the frames
    that need it, the contrast curve; a second look's curve); not part of `landmarks`. For a file
    it runs on the decode thread, ahead of the frame, so it is not in `total` either."""

    def as_tuple(self) -> tuple[float, ...]:
        """The times in `STAGES` order."""
        return tuple(getattr(self, f"{stage}_ms") for stage in STAGES)


@dataclass(frozen=True, slots=True)
class StageStats:
    median_ms: float
    p99_ms: float


class StageTimings:
    """Per-stage times of the most recent `capacity` frames (a fixed ring: memory stays flat).

    The first `skip_first` frames (model start-up) are not recorded.
    """

    def __init__(self, capacity: int = 20_000, skip_first: int = 0) -> None:
        self._times_ms: npt.NDArray[np.float64] = np.zeros((capacity, len(STAGES)))
        self._count = 0
        self._to_skip = skip_first

    def skip_next(self, frames: int) -> None:
        """Do not record the next `frames` frames (the start-up of another pass)."""
        self._to_skip = frames

    def add(self, times: StageTimes) -> None:
        if self._to_skip > 0:
            self._to_skip -= 1
            return
        self._times_ms[self._count % len(self._times_ms)] = times.as_tuple()
        self._count += 1

    @property
    def count(self) -> int:
        """Frames recorded in total, skipped ones excluded (may exceed what the ring holds)."""
        return self._count

    def stats(self) -> dict[str, StageStats]:
        """Median and 99th percentile per stage over the frames held; empty without frames."""
        held = self._times_ms[: min(self._count, len(self._times_ms))]
        if len(held) == 0:
            return {}
        medians = np.median(held, axis=0)
        p99s = np.percentile(held, 99, axis=0)
        return {
            stage: StageStats(median_ms=float(medians[i]), p99_ms=float(p99s[i]))
            for i, stage in enumerate(STAGES)
        }


@dataclass(frozen=True, slots=True)
class RunSummary:
    """What one run of the loop did."""

    frames: int
    frames_with_face: int
    wall_s: float
    source_status: SourceStatus
    stages: dict[str, StageStats]

    @property
    def fps(self) -> float:
        return self.frames / self.wall_s if self.wall_s > 0 else 0.0

    @property
    def overhead_ratio(self) -> float:
        """Median total frame time over median landmark time (1.0: the loop costs nothing)."""
        total, landmarks = self.stages.get("total"), self.stages.get("landmarks")
        if total is None or landmarks is None or landmarks.median_ms <= 0:
            return math.nan
        return total.median_ms / landmarks.median_ms
