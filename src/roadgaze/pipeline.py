"""The one loop: frame source -> landmarks -> geometry -> smoother -> sinks, timed per stage.

`Pipeline.process(frame)` turns one frame into a `YawSample` (testable with a fake detector and
no camera); `Pipeline.frames(source)` is the loop as an iterator; `Pipeline.run(source, sinks)`
drives it and hands every sample to the sinks in the order given. A sink is a `SampleSink`
(`on_sample(sample)`, `close()`) or, when it also needs the image and timings (an annotated
video), a `FrameSink` (`on_frame(processed)`, `close()`). Monitors, publishers and writers plug in
as sinks without changing the loop; a sink placed earlier runs first, so a JSONL writer placed
after a monitor sink can read the monitor's verdict on the same sample.
"""

from __future__ import annotations

import logging
import math
import signal
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from roadgaze.capture import FrameSource, SourceStatus
from roadgaze.config import Config
from roadgaze.geometry import YAW_MODELS, FaceModelConstants, YawModel
from roadgaze.smoothing import YawSmoother
from roadgaze.types import Detection, FaceFeatures, Frame, LandmarkDetector, YawSample

log = logging.getLogger(__name__)

STAGES = ("decode", "landmarks", "geometry", "smoothing", "sinks", "total")
"""Timed stages; `total` is one whole loop iteration, from asking for the frame to the last sink."""


@dataclass(frozen=True, slots=True)
class StageTimes:
    """Milliseconds spent on one frame per stage."""

    decode_ms: float
    """Getting the frame from the source (decoding a file; waiting for a camera frame)."""
    landmarks_ms: float
    geometry_ms: float
    smoothing_ms: float
    sinks_ms: float
    total_ms: float

    def as_tuple(self) -> tuple[float, ...]:
        return (
            self.decode_ms,
            self.landmarks_ms,
            self.geometry_ms,
            self.smoothing_ms,
            self.sinks_ms,
            self.total_ms,
        )


@dataclass(frozen=True, slots=True)
class ProcessedFrame:
    """One frame and everything the pipeline made of it."""

    frame: Frame
    detection: Detection
    sample: YawSample
    times: StageTimes
    """Before the sinks ran, `sinks_ms` is 0 and `total_ms` ends after smoothing."""


class SampleSink(Protocol):
    """Receives every sample in order; `close()` once at the end (also after an error)."""

    def on_sample(self, sample: YawSample) -> None: ...

    def close(self) -> None: ...


@runtime_checkable
class FrameSink(Protocol):
    """A sink that also needs the image, the detection or the timings of each frame."""

    def on_frame(self, processed: ProcessedFrame) -> None: ...

    def close(self) -> None: ...


Sink = SampleSink | FrameSink


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


class Pipeline:
    """Landmarks -> geometry -> smoother for one stream; one instance per source."""

    def __init__(
        self,
        detector: LandmarkDetector,
        smoother: YawSmoother | None = None,
        yaw_model: YawModel = YAW_MODELS["center_ce"],
        constants: FaceModelConstants | None = None,
        clock: Callable[[], float] = time.perf_counter,
    ) -> None:
        self.detector = detector
        self.smoother = smoother if smoother is not None else YawSmoother()
        self.yaw_model = yaw_model
        self.constants = constants if constants is not None else FaceModelConstants()
        self._clock = clock

    @classmethod
    def from_config(cls, config: Config, detector: LandmarkDetector) -> Pipeline:
        geometry = config.geometry
        return cls(
            detector=detector,
            smoother=YawSmoother(config.smoothing),
            yaw_model=YAW_MODELS[geometry.model],
            constants=geometry.face_constants(),
        )

    def raw_yaw_deg(self, features: FaceFeatures | None) -> float | None:
        """The configured yaw model on one face; None without a face or for impossible geometry."""
        if features is None:
            return None
        yaw_deg = float(
            self.yaw_model(
                features.x_left_px, features.x_right_px, features.x_center_px, self.constants
            )
        )
        return yaw_deg if math.isfinite(yaw_deg) else None

    def process(self, frame: Frame, decode_ms: float = 0.0) -> ProcessedFrame:
        """One frame through landmarks, geometry and smoother; frames must come in time order."""
        clock = self._clock
        start = clock()
        detection = self.detector.detect(frame.image, frame.t_s)
        after_landmarks = clock()
        features = detection.driver
        yaw_raw_deg = self.raw_yaw_deg(features)
        after_geometry = clock()
        smoothed = self.smoother.update(frame.t_s, yaw_raw_deg)
        after_smoothing = clock()
        sample = YawSample(
            t_s=frame.t_s,
            frame=frame.index,
            face=features is not None,
            yaw_raw_deg=yaw_raw_deg,
            yaw_deg=None if smoothed is None else smoothed.yaw_deg,
            yaw_rate_dps=None if smoothed is None else smoothed.yaw_rate_dps,
            yaw_std_deg=None if smoothed is None else smoothed.yaw_std_deg,
            features=features,
            n_faces=len(detection.faces),
        )
        times = StageTimes(
            decode_ms=decode_ms,
            landmarks_ms=(after_landmarks - start) * 1e3,
            geometry_ms=(after_geometry - after_landmarks) * 1e3,
            smoothing_ms=(after_smoothing - after_geometry) * 1e3,
            sinks_ms=0.0,
            total_ms=decode_ms + (after_smoothing - start) * 1e3,
        )
        return ProcessedFrame(frame=frame, detection=detection, sample=sample, times=times)

    def frames(
        self,
        source: FrameSource,
        *,
        realtime: bool = False,
        max_frames: int | None = None,
    ) -> Iterator[ProcessedFrame]:
        """The loop as an iterator. `realtime` paces a file source at its own timeline."""
        clock = self._clock
        iterator = iter(source)
        pace = realtime and not source.info.live
        first_t_s: float | None = None
        wall_start = 0.0
        produced = 0
        while max_frames is None or produced < max_frames:
            before = clock()
            frame = next(iterator, None)
            decode_ms = (clock() - before) * 1e3
            if frame is None:
                return
            if pace:
                if first_t_s is None:
                    first_t_s, wall_start = frame.t_s, clock()
                wait_s = wall_start + (frame.t_s - first_t_s) - clock()
                if wait_s > 0:
                    time.sleep(wait_s)
            yield self.process(frame, decode_ms)
            produced += 1

    def run(
        self,
        source: FrameSource,
        sinks: Sequence[Sink] = (),
        *,
        realtime: bool = False,
        max_frames: int | None = None,
        timings: StageTimings | None = None,
    ) -> RunSummary:
        """Drive the loop to the end of the source, feeding every sink; sinks are not closed here.

        Stage times go into `timings` (a fresh `StageTimings` when None) and the summary.
        """
        timings = timings if timings is not None else StageTimings()
        clock = self._clock
        wants_frame = [isinstance(sink, FrameSink) for sink in sinks]
        frames = 0
        with_face = 0
        wall_start = clock()
        for processed in self.frames(source, realtime=realtime, max_frames=max_frames):
            before_sinks = clock()
            for sink, wants in zip(sinks, wants_frame, strict=True):
                if wants:
                    sink.on_frame(processed)  # type: ignore[union-attr]
                else:
                    sink.on_sample(processed.sample)  # type: ignore[union-attr]
            sinks_ms = (clock() - before_sinks) * 1e3
            times = processed.times
            timings.add(
                StageTimes(
                    decode_ms=times.decode_ms,
                    landmarks_ms=times.landmarks_ms,
                    geometry_ms=times.geometry_ms,
                    smoothing_ms=times.smoothing_ms,
                    sinks_ms=sinks_ms,
                    total_ms=times.total_ms + sinks_ms,
                )
            )
            frames += 1
            with_face += processed.sample.face
        return RunSummary(
            frames=frames,
            frames_with_face=with_face,
            wall_s=clock() - wall_start,
            source_status=source.status,
            stages=timings.stats(),
        )


def create_detector(config: Config) -> LandmarkDetector:
    """The production detector: MediaPipe FaceLandmarker in VIDEO mode (model via model_store)."""
    from roadgaze.landmarks import MediaPipeLandmarker

    return MediaPipeLandmarker.from_config(config, video=True)


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM raises KeyboardInterrupt so `with` blocks close every output."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum: int, frame: object) -> None:
        raise KeyboardInterrupt(f"signal {signum}")

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
