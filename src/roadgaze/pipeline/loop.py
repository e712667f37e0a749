"""The only loop: frame source -> landmarks -> pose -> monitor -> sinks, timed per stage.

`Pipeline.process(frame)` turns one frame into a `FrameRecord` (testable with a fake detector
and no camera); `Pipeline.frames(source)` is the loop as an iterator; `Pipeline.run(source,
sinks, stop=...)` drives it and hands every record, with its frame, to each sink. `run`,
`replay`, `demo` and `bench` all use this loop; a sink only reads the record, so sinks are
independent of each other and of their order. The `Sink` protocol lives in `roadgaze.types`;
`roadgaze.pipeline.build_run` assembles a run's sinks and delivers the alerts raised outside the
loop to each of them.
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

from roadgaze.capture import FrameSource
from roadgaze.config import Config, EyesConfig
from roadgaze.landmarks.eyes import driver_eyes
from roadgaze.monitor import Monitor
from roadgaze.monitor.failures import check_frame
from roadgaze.phone.stage import PhoneStage
from roadgaze.pipeline.handoff import Handoff
from roadgaze.pipeline.runtime import Collector, loop_runtime
from roadgaze.pipeline.steps import (
    Decoded,
    DetectorSteps,
    Inferred,
    Pacer,
    decode_frames,
    front_end_ms,
    infer_frames,
    infer_one,
)
from roadgaze.pipeline.timing import RunSummary, StageTimes, StageTimings
from roadgaze.pose import PoseEstimator
from roadgaze.speed import SpeedSource, VehicleSpeed, no_speed, vehicle_speed
from roadgaze.types import Frame, FrameRecord, LandmarkDetector, Sink

READ_AHEAD_FRAMES = 2
"""Frames a file source is decoded (and prepared) ahead of the loop: enough to hide decoding, few
enough to keep memory flat."""
INFER_AHEAD_FRAMES = 1
"""Frames the landmark thread may hand over before the loop takes them (it runs one more)."""
STOP_GRACE_S = 1.0
"""After a stop is asked for, how long the frame in hand may take before a live source is closed
(which unblocks a loop waiting for a lost camera)."""


class StopSignal(Protocol):
    """Anything with `is_set()`: a `threading.Event`, the daemon's `StopFlag`."""

    def is_set(self) -> bool: ...


@dataclass(frozen=True, slots=True)
class ProcessedFrame:
    """One frame, its record and how long each stage took."""

    frame: Frame
    record: FrameRecord
    times: StageTimes
    """Before the sinks ran, `sinks_ms` is 0 and `total_ms` ends after the monitor."""


class Pipeline:
    """Landmarks -> pose -> monitor for one stream; one instance per source timeline."""

    def __init__(
        self,
        detector: LandmarkDetector,
        pose: PoseEstimator | None = None,
        monitor: Monitor | None = None,
        speed: SpeedSource | VehicleSpeed = no_speed,
        clock: Callable[[], float] = time.perf_counter,
        eyes: EyesConfig | None = None,
        phone: PhoneStage | None = None,
    ) -> None:
        self.detector = detector
        self.phone = phone
        """Hands and the phone judgement (None: phone detection off)."""
        self.eyes = eyes if eyes is not None else EyesConfig()
        self.pose = pose if pose is not None else PoseEstimator()
        self.monitor = monitor if monitor is not None else Monitor(Config().monitor)
        self.speed = vehicle_speed(speed)
        """The vehicle speed at each frame's time (a zero-argument source is the bus's)."""
        self._clock = clock
        self._steps = DetectorSteps.of(detector)
        self._frame_received_s = math.nan
        self._previous_grey: npt.NDArray[np.float32] | None = None
        """The last frame's grey sample, for the frozen-frame check."""

    @classmethod
    def from_config(
        cls,
        config: Config,
        detector: LandmarkDetector,
        speed: SpeedSource | VehicleSpeed = no_speed,
    ) -> Pipeline:
        return cls(
            detector=detector,
            pose=PoseEstimator.from_config(config),
            monitor=Monitor(config.monitor),
            speed=speed,
            eyes=config.eyes,
            phone=PhoneStage.from_config(config),
        )

    @property
    def frame_received_s(self) -> float:
        """When the frame in hand was received from its source (the `clock`, seconds; after
        pacing; in the landmark thread); sinks read it during `on_record`, e.g. to measure
        latency. NaN before a frame."""
        return self._frame_received_s

    def process(self, frame: Frame, decode_ms: float = 0.0) -> ProcessedFrame:
        """One frame through every stage on this thread; frames must come in time order."""
        return self._finish(infer_one(frame, None, self._steps, self._clock, decode_ms))

    def _finish(self, inferred: Inferred) -> ProcessedFrame:
        """The faces measured, then pose, smoothing and monitor, for a frame after `infer`."""
        clock = self._clock
        frame = inferred.frame
        start = clock()
        detection = self._steps.measure(inferred.inference)
        after_measure = clock()
        driver = detection.driver
        yaw_raw_deg = self.pose.raw_yaw_deg(driver)
        # The matrix pitch's down gain starts at the monitor's current neutral pitch.
        pitch_raw_deg = self.pose.raw_pitch_deg(driver, self.monitor.camera_neutral_pitch_deg)
        eyes = driver_eyes(driver, yaw_raw_deg, self.eyes)
        after_geometry = clock()
        sample = self.pose.smooth(frame.t_s, frame.index, detection, yaw_raw_deg, pitch_raw_deg)
        sample = sample if eyes is None else replace(sample, eyes=eyes)
        frame_check, self._previous_grey = check_frame(frame.image, self._previous_grey)
        sample = replace(sample, frame_check=frame_check)
        after_smoothing = clock()
        if self.phone is not None:  # the hand stage and the phone judgement (docs/phone.md)
            sample = self.phone.apply(frame, sample)
        after_hands = clock()
        hands_ms = (after_hands - after_smoothing) * 1e3  # counted with the landmarks
        alerts = self.monitor.update(sample, self.speed.kmh_at(frame.t_s))
        record = FrameRecord(sample=sample, verdict=self.monitor.verdict, alerts=alerts)
        after_monitor = clock()
        enhance_ms, enhance_in_infer_ms = front_end_ms(inferred)
        times = StageTimes(
            decode_ms=inferred.decode_ms,
            enhance_ms=enhance_ms,
            landmarks_ms=inferred.infer_ms
            - enhance_in_infer_ms
            + (after_measure - start) * 1e3
            + hands_ms,
            handover_ms=(start - inferred.inferred_s) * 1e3,
            geometry_ms=(after_geometry - after_measure) * 1e3,
            smoothing_ms=(after_smoothing - after_geometry) * 1e3,
            monitor_ms=(after_monitor - after_hands) * 1e3,
            sinks_ms=0.0,
            total_ms=inferred.decode_ms + (after_monitor - inferred.received_s) * 1e3,
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

        A file is decoded, and each image prepared for the detector, in a thread of its own
        `READ_AHEAD_FRAMES` ahead; a camera grabs in its own thread. A file read flat out runs
        MediaPipe in the landmark thread (`roadgaze.pipeline.steps`), handing each frame over as
        soon as it is done, and the rest on the caller's thread while MediaPipe works on the
        next frame: throughput. A camera, or a file paced at its own rate, delivers frames more
        slowly than the loop runs, so there a frame goes straight through on the caller's
        thread: no hand-over between threads adds to its latency (`docs/pipeline.md`).
        """
        spent: deque[Any] = deque(maxlen=2 * READ_AHEAD_FRAMES + 2)
        produced = 0
        with contextlib.ExitStack() as stack:
            stack.enter_context(loop_runtime())
            collector = Collector()
            items: Iterator[Decoded]
            if source.info.live:
                items = (Decoded(frame) for frame in source)
            else:
                decoded = decode_frames(source, self._steps.prepare, spent)
                decoding = Handoff(decoded, "roadgaze-decode", READ_AHEAD_FRAMES)
                items = iter(stack.enter_context(decoding))
            pacer = Pacer(self._clock) if realtime and not source.info.live else None
            in_order = infer_frames(items, self._steps, self._clock, pacer, spent)
            inferred: Iterator[Inferred]
            if source.info.live or realtime:
                inferred = in_order
                stack.callback(in_order.close)
            else:
                inferring = Handoff(in_order, "roadgaze-landmarks", INFER_AHEAD_FRAMES)
                inferred = iter(stack.enter_context(inferring))
            while max_frames is None or produced < max_frames:
                if stop is not None and stop.is_set():
                    return
                item = next(inferred, None)
                if item is None:
                    return
                self._frame_received_s = item.received_s
                yield self._finish(item)
                produced += 1
                collector.after_frame()  # after the frame's sinks: off its latency

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
                        replace(times, sinks_ms=sinks_ms, total_ms=times.total_ms + sinks_ms)
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
    """The production detector: the face landmarker in VIDEO mode on `landmarks.engine` (model via
    model_store), behind the front end of `landmarks.enhance`."""
    from roadgaze.landmarks import Landmarker
    from roadgaze.landmarks.front_end import with_front_end

    return with_front_end(Landmarker.from_config(config, video=True), config.landmarks.enhance)
