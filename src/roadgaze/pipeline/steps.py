"""The loop's two threads ahead of it: decoding a file, and the landmark inference.

Per frame the decode thread reads the frame and prepares its image for the detector
(`decode_frames`), the landmark thread runs MediaPipe on it (`infer_frames`), and the loop's own
thread measures the faces, estimates the pose, runs the monitor and feeds the sinks. MediaPipe
releases Python's lock while it works, so on a second core everything else overlaps with the
inference of the next frame and the loop runs at MediaPipe's own rate.

A camera, or a file paced at its own rate, delivers frames more slowly than that, so for them
the loop's own thread runs `infer_frames` too: each frame goes straight through, without a
hand-over between threads in its latency.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass
from typing import Any

from roadgaze.capture import FrameSource
from roadgaze.threads import lower_this_thread_priority as lower_this_thread_priority
from roadgaze.types import Detection, Frame, LandmarkDetector, RecordedDriver

log = logging.getLogger(__name__)

DECODE_NICENESS = 10
"""How much lower than the rest of the loop the decode thread runs (Linux thread niceness). It
works frames ahead, so it yields the core to the frame in flight (the loop's thread, MediaPipe's
threads, Zenoh's) instead of delaying it."""


def front_end_ms(inferred: Inferred) -> tuple[float, float]:
    """The front end's time on a frame (`roadgaze.landmarks.front_end`) and how much of it lies
    within `inferred.infer_ms`; (0, 0) for a detector without a front end."""
    inference = inferred.inference
    prepare_ms = float(getattr(inference, "prepare_ms", 0.0))
    retry_ms = float(getattr(inference, "retry_ms", 0.0))
    return prepare_ms + retry_ms, retry_ms + (prepare_ms if inferred.prepared_here else 0.0)


def _already_measured(detection: Any) -> Detection:
    """`measure` of a detector whose `detect` does all of the landmark stage at once."""
    return detection  # type: ignore[no-any-return]


@dataclass(frozen=True, slots=True)
class DetectorSteps:
    """A detector's landmark stage as the loop runs it: `prepare` (no state; the decode thread),
    `infer` (frames in order; the landmark thread) and `measure` (no state; the loop's thread).

    `Landmarker` has the three; a detector with only `detect` (a test's fake) infers the
    whole stage at once and `measure` passes its detection on.
    """

    prepare: Callable[[Any], Any] | None
    infer: Callable[[Any, float | None], Any]
    measure: Callable[[Any], Detection]
    follow: Callable[[RecordedDriver | None], None] | None = None
    """The detector's `follow`: told, before each frame, the driver a recording chose on it."""

    @classmethod
    def of(cls, detector: LandmarkDetector) -> DetectorSteps:
        prepare = getattr(detector, "prepare", None)
        infer = getattr(detector, "infer", None)
        measure = getattr(detector, "measure", None)
        follow = getattr(detector, "follow", None)
        if prepare is not None and infer is not None and measure is not None:
            return cls(prepare, infer, measure, follow)
        return cls(None, detector.detect, _already_measured, follow)

    def input_of(self, frame: Frame, prepared: Any) -> Any:
        """What `infer` takes for `frame`: its image prepared (here if not beforehand) or as is."""
        if prepared is not None:
            return prepared
        return frame.image if self.prepare is None else self.prepare(frame.image)


@dataclass(frozen=True, slots=True)
class Decoded:
    """A frame from the source, with its image prepared for the detector when it could be."""

    frame: Frame
    prepared: Any = None
    """What the detector's `prepare(image)` made of the image (None: not prepared)."""


def decode_frames(
    source: FrameSource, prepare: Callable[[Any], Any] | None, spent: deque[Any]
) -> Iterator[Decoded]:
    """The decode thread's part: each frame and its prepared image. Prepared images come back
    through `spent` to be released here, off the other threads (a `mediapipe.Image`: 0.25 ms).
    Runs `DECODE_NICENESS` below the rest of the loop."""
    lower_this_thread_priority(DECODE_NICENESS)
    for frame in source:
        while spent:
            spent.popleft()
        yield Decoded(frame, None if prepare is None else prepare(frame.image))


@dataclass(frozen=True, slots=True)
class Inferred:
    """A frame after the detector's `infer`, on its way to the loop's thread."""

    frame: Frame
    inference: Any
    """What `DetectorSteps.infer` returned (for a plain detector, the `Detection`)."""
    decode_ms: float
    received_s: float
    """When the landmark thread received the frame from its source (the loop's clock, after
    pacing): the start of the frame's latency."""
    inferred_s: float
    """When `infer` ended (the loop's clock)."""
    prepared_here: bool = False
    """The image was prepared inside `infer`'s time (no decode thread prepared it)."""

    @property
    def infer_ms(self) -> float:
        return (self.inferred_s - self.received_s) * 1e3


def infer_one(
    frame: Frame,
    prepared: Any,
    steps: DetectorSteps,
    clock: Callable[[], float],
    decode_ms: float = 0.0,
) -> Inferred:
    """`frame` (with its image `prepared`, or None) through the detector's `infer`, timed from
    now: the start of its latency."""
    received_s = clock()
    if steps.follow is not None:
        steps.follow(frame.recorded_driver)
    inference = steps.infer(steps.input_of(frame, prepared), frame.t_s)
    here = prepared is None and steps.prepare is not None
    return Inferred(frame, inference, decode_ms, received_s, clock(), here)


class Pacer:
    """Holds a file's frames back to its own timeline (`realtime` replay)."""

    def __init__(self, clock: Callable[[], float]) -> None:
        self._clock = clock
        self._first_t_s: float | None = None
        self._wall_start = 0.0

    def wait(self, t_s: float) -> None:
        if self._first_t_s is None:
            self._first_t_s, self._wall_start = t_s, self._clock()
        wait_s = self._wall_start + (t_s - self._first_t_s) - self._clock()
        if wait_s > 0:
            time.sleep(wait_s)


def infer_frames(
    items: Iterator[Decoded],
    steps: DetectorSteps,
    clock: Callable[[], float],
    pacer: Pacer | None,
    spent: deque[Any],
) -> Generator[Inferred, None, None]:
    """The landmark thread's part (the loop's own for a paced source): each frame through the
    detector's `infer`, in order. A prepared image goes back through `spent` to the decode
    thread once MediaPipe is done with it."""
    while True:
        before = clock()
        item = next(items, None)
        decode_ms = (clock() - before) * 1e3
        if item is None:
            return
        if pacer is not None:
            pacer.wait(item.frame.t_s)
        inferred = infer_one(item.frame, item.prepared, steps, clock, decode_ms)
        if item.prepared is not None:
            spent.append(item.prepared)
        del item  # the decode thread releases the prepared image
        yield inferred
