"""The only loop: frame source -> landmarks -> pose -> monitor -> sinks, timed per stage.

`Pipeline.process(frame)` turns one frame into a `FrameRecord` (testable with a fake detector
and no camera); `Pipeline.frames(source)` is the loop as an iterator; `Pipeline.run(source,
sinks, stop=...)` drives it and hands every record, with its frame, to each sink. `run`,
`replay`, `demo` and `bench` all use this loop; a sink only reads the record, so sinks are
independent of each other and of their order.
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Generator, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from roadgaze.capture import FrameSource, SourceStatus
from roadgaze.config import Config, EyesConfig
from roadgaze.handoff import Handoff
from roadgaze.landmarks.eyes import driver_eyes
from roadgaze.monitor import Monitor
from roadgaze.pose import PoseEstimator
from roadgaze.types import Detection, Frame, FrameRecord, LandmarkDetector

STAGES = ("decode", "landmarks", "geometry", "smoothing", "monitor", "sinks", "total")
"""Timed stages; `total` is one whole loop iteration, from asking for the frame to the last sink."""

READ_AHEAD_FRAMES = 2
"""Frames a file source is decoded (and prepared) ahead of the loop: enough to hide decoding, few
enough to keep memory flat."""
STOP_GRACE_S = 1.0
"""After a stop is asked for, how long the frame in hand may take before a live source is closed
(which unblocks a loop waiting for a lost camera)."""

SpeedSource = Callable[[], float | None]
"""The vehicle speed in km/h for the monitor; None when unknown (taken as moving)."""


def no_speed() -> float | None:
    """The speed source of a replay without a bus: always unknown, i.e. moving (fail-safe)."""
    return None


class StopSignal(Protocol):
    """Anything with `is_set()`: a `threading.Event`, the daemon's `StopFlag`."""

    def is_set(self) -> bool: ...


class Sink(Protocol):
    """Receives every record, in order, with its frame; `close()` once at the end."""

    def on_record(self, record: FrameRecord, frame: Frame) -> None: ...

    def close(self) -> None: ...


@dataclass(frozen=True, slots=True)
class StageTimes:
    """Milliseconds spent on one frame per stage."""

    decode_ms: float
    """Getting the frame from the source (decoding a file; waiting for a camera frame)."""
    landmarks_ms: float
    geometry_ms: float
    smoothing_ms: float
    monitor_ms: float
    sinks_ms: float
    total_ms: float

    def as_tuple(self) -> tuple[float, ...]:
        """The times in `STAGES` order."""
        return tuple(getattr(self, name) for name in self.__slots__)


@dataclass(frozen=True, slots=True)
class ProcessedFrame:
    """One frame, its record and how long each stage took."""

    frame: Frame
    record: FrameRecord
    times: StageTimes
    """Before the sinks ran, `sinks_ms` is 0 and `total_ms` ends after the monitor."""


@dataclass(frozen=True, slots=True)
class _Decoded:
    """A frame from the source, with its image prepared for the detector when it could be."""

    frame: Frame
    prepared: Any = None
    """What the detector's `prepare(image)` made of the image (None: not prepared)."""


def _decoded(
    source: FrameSource, prepare: Callable[[Any], Any] | None, spent: deque[Any]
) -> Iterator[_Decoded]:
    """The decode thread's part: each frame and its prepared image. Prepared images come back
    through `spent` to be released here, off the loop's thread (a `mediapipe.Image`: 0.25 ms)."""
    for frame in source:
        while spent:
            spent.popleft()
        yield _Decoded(frame, None if prepare is None else prepare(frame.image))


@dataclass(frozen=True, slots=True)
class _Detected:
    """A frame after the landmark stage, on its way to the rest of the loop."""

    frame: Frame
    detection: Detection
    decode_ms: float
    landmarks_ms: float
    received_s: float
    """When the loop received the frame from its source (its `clock`, after pacing)."""


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


class Pipeline:
    """Landmarks -> pose -> monitor for one stream; one instance per source timeline."""

    def __init__(
        self,
        detector: LandmarkDetector,
        pose: PoseEstimator | None = None,
        monitor: Monitor | None = None,
        speed: SpeedSource = no_speed,
        clock: Callable[[], float] = time.perf_counter,
        eyes: EyesConfig | None = None,
    ) -> None:
        self.detector = detector
        self.eyes = eyes if eyes is not None else EyesConfig()
        self.pose = pose if pose is not None else PoseEstimator()
        self.monitor = monitor if monitor is not None else Monitor(Config().monitor)
        self.speed = speed
        self._clock = clock
        self._frame_received_s = math.nan

    @classmethod
    def from_config(
        cls, config: Config, detector: LandmarkDetector, speed: SpeedSource = no_speed
    ) -> Pipeline:
        return cls(
            detector=detector,
            pose=PoseEstimator.from_config(config),
            monitor=Monitor(config.monitor),
            speed=speed,
            eyes=config.eyes,
        )

    @property
    def frame_received_s(self) -> float:
        """When the loop received the frame in hand from its source (the `clock`, seconds; after
        pacing); sinks read it during `on_record`, e.g. to measure latency. NaN before a frame."""
        return self._frame_received_s

    def process(self, frame: Frame, decode_ms: float = 0.0) -> ProcessedFrame:
        """One frame through every stage; frames must come in time order."""
        return self._finish(self._detect(_Decoded(frame), decode_ms, self._clock()))

    def _detect(self, decoded: _Decoded, decode_ms: float, received_s: float) -> _Detected:
        """The landmark stage of one frame (with the image prepared beforehand when it was)."""
        frame = decoded.frame
        start = self._clock()
        detect_prepared = getattr(self.detector, "detect_prepared", None)
        if decoded.prepared is not None and detect_prepared is not None:
            detection: Detection = detect_prepared(decoded.prepared, frame.t_s)
        else:
            detection = self.detector.detect(frame.image, frame.t_s)
        landmarks_ms = (self._clock() - start) * 1e3
        return _Detected(frame, detection, decode_ms, landmarks_ms, received_s)

    def _finish(self, detected: _Detected) -> ProcessedFrame:
        """Pose, smoothing and monitor for a frame whose landmarks are known."""
        clock = self._clock
        frame, detection = detected.frame, detected.detection
        start = clock()
        driver = detection.driver
        yaw_raw_deg = self.pose.raw_yaw_deg(driver)
        # The matrix pitch's down gain starts at the monitor's current neutral pitch.
        pitch_raw_deg = self.pose.raw_pitch_deg(driver, self.monitor.state.neutral_pitch_deg)
        eyes = driver_eyes(driver, yaw_raw_deg, self.eyes)
        after_geometry = clock()
        sample = self.pose.smooth(frame.t_s, frame.index, detection, yaw_raw_deg, pitch_raw_deg)
        sample = sample if eyes is None else replace(sample, eyes=eyes)
        after_smoothing = clock()
        alerts = self.monitor.update(sample, self.speed())
        record = FrameRecord(sample=sample, verdict=self.monitor.verdict, alerts=alerts)
        after_monitor = clock()
        times = StageTimes(
            decode_ms=detected.decode_ms,
            landmarks_ms=detected.landmarks_ms,
            geometry_ms=(after_geometry - start) * 1e3,
            smoothing_ms=(after_smoothing - after_geometry) * 1e3,
            monitor_ms=(after_monitor - after_smoothing) * 1e3,
            sinks_ms=0.0,
            total_ms=detected.decode_ms + detected.landmarks_ms + (after_monitor - start) * 1e3,
        )
        return ProcessedFrame(frame=frame, record=record, times=times)

    def frames(
        self,
        source: FrameSource,
        *,
        realtime: bool = False,
        max_frames: int | None = None,
        stop: StopSignal | None = None,
    ) -> Generator[ProcessedFrame, None, None]:
        """The loop as an iterator. `realtime` paces a file source at its own timeline; `stop`
        ends the loop before the next frame.

        A file is decoded, and each image prepared for the detector (`prepare`), in a thread of its
        own `READ_AHEAD_FRAMES` ahead while the detector works; a camera grabs in its own thread.
        The rest runs on the caller's thread with no hand-over, so a frame's latency is its own.
        """
        clock = self._clock
        pace = realtime and not source.info.live
        first_t_s: float | None = None
        wall_start = 0.0
        produced = 0
        spent: deque[Any] = deque(maxlen=2 * READ_AHEAD_FRAMES + 2)
        with contextlib.ExitStack() as stack:
            items: Iterator[_Decoded]
            if source.info.live:
                items = (_Decoded(frame) for frame in source)
            else:
                prepare = getattr(self.detector, "prepare", None)
                decoding = Handoff(
                    _decoded(source, prepare, spent), "roadgaze-decode", READ_AHEAD_FRAMES
                )
                items = iter(stack.enter_context(decoding))
            while max_frames is None or produced < max_frames:
                if stop is not None and stop.is_set():
                    return
                before = clock()
                item = next(items, None)
                decode_ms = (clock() - before) * 1e3
                if item is None:
                    return
                if pace:
                    if first_t_s is None:
                        first_t_s, wall_start = item.frame.t_s, clock()
                    wait_s = wall_start + (item.frame.t_s - first_t_s) - clock()
                    if wait_s > 0:
                        time.sleep(wait_s)
                self._frame_received_s = clock()
                detected = self._detect(item, decode_ms, self._frame_received_s)
                if item.prepared is not None:
                    spent.append(item.prepared)
                del item  # the decode thread releases the prepared image
                yield self._finish(detected)
                produced += 1

    def run(
        self,
        source: FrameSource,
        sinks: Sequence[Sink] = (),
        *,
        realtime: bool = False,
        max_frames: int | None = None,
        timings: StageTimings | None = None,
        stop: StopSignal | None = None,
    ) -> RunSummary:
        """Drive the loop to the end of the source or a stop, feeding every sink; sinks are not
        closed here. Stage times go into `timings` (a fresh `StageTimings` when None) and the
        summary. A live source still blocked `STOP_GRACE_S` after a stop is closed."""
        timings = timings if timings is not None else StageTimings()
        clock = self._clock
        frames = 0
        with_face = 0
        done = threading.Event()
        if stop is not None and source.info.live:
            watcher = threading.Thread(
                target=_close_when_stopped, args=(stop, source, done), daemon=True
            )
            watcher.start()
        wall_start = clock()
        try:
            frames_in = self.frames(source, realtime=realtime, max_frames=max_frames, stop=stop)
            with contextlib.closing(frames_in) as loop:  # closed at once, even on an error
                for processed in loop:
                    before_sinks = clock()
                    for sink in sinks:
                        sink.on_record(processed.record, processed.frame)
                    sinks_ms = (clock() - before_sinks) * 1e3
                    times = processed.times
                    timings.add(
                        StageTimes(
                            decode_ms=times.decode_ms,
                            landmarks_ms=times.landmarks_ms,
                            geometry_ms=times.geometry_ms,
                            smoothing_ms=times.smoothing_ms,
                            monitor_ms=times.monitor_ms,
                            sinks_ms=sinks_ms,
                            total_ms=times.total_ms + sinks_ms,
                        )
                    )
                    frames += 1
                    with_face += processed.record.sample.face
        finally:
            done.set()
        return RunSummary(
            frames=frames,
            frames_with_face=with_face,
            wall_s=clock() - wall_start,
            source_status=source.status,
            stages=timings.stats(),
        )


def _close_when_stopped(stop: StopSignal, source: FrameSource, done: threading.Event) -> None:
    """Unblock a loop that waits for a lost camera once a stop is asked for."""
    while not done.wait(0.1):
        if stop.is_set():
            if not done.wait(STOP_GRACE_S):  # the frame in hand had its grace period
                source.close()
            return


def create_detector(config: Config) -> LandmarkDetector:
    """The production detector: MediaPipe FaceLandmarker in VIDEO mode (model via model_store)."""
    from roadgaze.landmarks import MediaPipeLandmarker

    return MediaPipeLandmarker.from_config(config, video=True)
