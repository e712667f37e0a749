"""The loop's threads: which step runs where, order, errors, stopping, and the interpreter set for
a loop (switch interval, garbage collection between frames)."""

from __future__ import annotations

import gc
import os
import sys
import threading
from collections.abc import Iterator
from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from fakes import ListSource, ScriptedDetector
from roadgaze.capture import SourceInfo
from roadgaze.pipeline import Pipeline
from roadgaze.pipeline.runtime import (
    MIDDLE_EVERY_FRAMES,
    SWITCH_INTERVAL_S,
    YOUNG_THRESHOLD,
    Collector,
    loop_runtime,
)
from roadgaze.pipeline.steps import DECODE_NICENESS
from roadgaze.types import Detection, Frame


class StagedDetector:
    """A `ScriptedDetector` in the three steps of `MediaPipeLandmarker`, noting the thread of
    each call."""

    def __init__(self, yaws_deg: list[float | None], fail_at: int | None = None) -> None:
        self.inner = ScriptedDetector(yaws_deg)
        self.fail_at = fail_at
        self.threads: dict[str, set[str]] = {"prepare": set(), "infer": set(), "measure": set()}
        self.inferred: list[int] = []

    def _note(self, step: str) -> None:
        self.threads[step].add(threading.current_thread().name)

    def prepare(self, image: np.ndarray) -> tuple[str, np.ndarray]:
        self._note("prepare")
        return ("prepared", image)

    def infer(self, prepared: tuple[str, np.ndarray], t_s: float | None) -> tuple[int, Detection]:
        self._note("infer")
        assert prepared[0] == "prepared"
        index = len(self.inferred)
        if index == self.fail_at:
            raise ValueError(f"MediaPipe failed on frame {index}")
        self.inferred.append(index)
        return index, self.inner.detect(prepared[1], t_s)

    def measure(self, inference: tuple[int, Detection]) -> Detection:
        self._note("measure")
        return inference[1]

    def detect(self, image: np.ndarray, t_s: float | None = None) -> Detection:
        return self.measure(self.infer(self.prepare(image), t_s))

    def close(self) -> None:
        return None


def loop_threads() -> set[str]:
    return {t.name for t in threading.enumerate() if t.name.startswith("roadgaze-")}


def values(record: Any) -> tuple[Any, ...]:
    sample = record.sample
    return (sample.t_s, sample.yaw_raw_deg, sample.yaw_deg, sample.yaw_rate_dps, record.verdict)


def yaws(count: int) -> list[float | None]:
    return [float(i % 30) for i in range(count)]


def test_a_file_is_decoded_inferred_and_measured_on_three_threads_in_order() -> None:
    detector = StagedDetector(yaws(40))
    records = [p.record for p in Pipeline(detector).frames(ListSource(40))]
    assert detector.threads == {
        "prepare": {"roadgaze-decode"},
        "infer": {"roadgaze-landmarks"},
        "measure": {threading.current_thread().name},
    }
    assert [r.frame for r in records] == list(range(40))
    # The same records as one frame at a time on this thread.
    one_by_one = Pipeline(StagedDetector(yaws(40)))
    expected = [one_by_one.process(frame).record for frame in ListSource(40)]

    assert [values(r) for r in records] == [values(r) for r in expected]
    assert loop_threads() == set()


class LiveListSource(ListSource):
    """`ListSource` as a camera: live, so it is never paced and never read ahead."""

    @property
    def info(self) -> SourceInfo:
        return replace(super().info, live=True)


@pytest.mark.parametrize("paced", ["camera", "realtime file"])
def test_a_paced_source_goes_straight_through_on_the_loops_thread(paced: str) -> None:
    """A camera, or a file at its own rate, is slower than the loop: no hand-over to another
    thread adds to a frame's latency. The records are those of the threaded loop."""
    count = 12
    detector = StagedDetector(yaws(count))
    pipeline = Pipeline(detector)
    if paced == "camera":
        frames = pipeline.frames(LiveListSource(count, fps=200.0))
        expected_prepare = {threading.current_thread().name}  # the detector's input_of, here
    else:
        frames = pipeline.frames(ListSource(count, fps=200.0), realtime=True)
        expected_prepare = {"roadgaze-decode"}
    during: list[set[str]] = []
    records = []
    for processed in frames:
        records.append(processed.record)
        during.append(loop_threads())
    here = threading.current_thread().name
    assert detector.threads["infer"] == {here}
    assert detector.threads["measure"] == {here}
    assert detector.threads["prepare"] == expected_prepare
    assert all("roadgaze-landmarks" not in names for names in during)
    assert [r.frame for r in records] == list(range(count))
    threaded_loop = Pipeline(StagedDetector(yaws(count))).frames(ListSource(count, fps=200.0))
    threaded = [p.record for p in threaded_loop]
    assert [values(r) for r in records] == [values(r) for r in threaded]
    assert loop_threads() == set()


def test_a_paced_loop_stops_and_reports_errors_as_the_threaded_one() -> None:
    detector = StagedDetector(yaws(30), fail_at=7)
    seen: list[int] = []
    with pytest.raises(ValueError, match="failed on frame 7"):
        for processed in Pipeline(detector).frames(LiveListSource(30)):
            seen.append(processed.record.frame)
    assert seen == list(range(7))
    detector = StagedDetector(yaws(30))
    stop = threading.Event()
    for processed in Pipeline(detector).frames(LiveListSource(30), stop=stop):
        if processed.record.frame == 4:
            stop.set()
    assert detector.inferred == list(range(5))  # nothing is inferred ahead of the loop
    assert Pipeline(StagedDetector(yaws(30))).run(LiveListSource(30), max_frames=3).frames == 3
    assert loop_threads() == set()


def test_a_plain_detector_infers_on_the_landmark_thread() -> None:
    calls: list[str] = []

    class Plain(ScriptedDetector):
        def detect(self, image: np.ndarray, t_s: float | None = None) -> Detection:
            calls.append(threading.current_thread().name)
            return super().detect(image, t_s)

    summary = Pipeline(Plain(yaws(10))).run(ListSource(10))
    assert summary.frames == 10 and set(calls) == {"roadgaze-landmarks"}
    assert summary.stages["landmarks"].median_ms >= 0
    assert 0 <= summary.stages["handover"].median_ms <= summary.stages["total"].median_ms


def test_an_error_in_mediapipe_reaches_the_caller_and_no_thread_is_left() -> None:
    detector = StagedDetector(yaws(30), fail_at=7)
    seen: list[int] = []
    with pytest.raises(ValueError, match="failed on frame 7"):
        for processed in Pipeline(detector).frames(ListSource(30)):
            seen.append(processed.record.frame)
    assert seen == list(range(7))
    assert loop_threads() == set()


def test_max_frames_and_stop_end_the_threads_with_the_loop() -> None:
    detector = StagedDetector(yaws(100))
    assert Pipeline(detector).run(ListSource(100), max_frames=5).frames == 5
    # The landmark thread runs at most a few frames ahead of the loop.
    assert 5 <= len(detector.inferred) <= 5 + 3
    assert loop_threads() == set()


def test_the_decode_thread_runs_at_a_lower_priority() -> None:
    niceness: list[int] = []

    class Recording(ListSource):
        def __iter__(self) -> Iterator[Frame]:
            for frame in super().__iter__():
                niceness.append(os.getpriority(os.PRIO_PROCESS, threading.get_native_id()))
                yield frame

    base = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    Pipeline(StagedDetector(yaws(5))).run(Recording(5))
    assert niceness == [min(19, base + DECODE_NICENESS)] * 5
    assert os.getpriority(os.PRIO_PROCESS, threading.get_native_id()) == base


def test_a_loop_sets_the_interpreter_and_restores_it_after_the_last_loop() -> None:
    import cv2

    switch_s, threshold = sys.getswitchinterval(), gc.get_threshold()
    cv2.setNumThreads(2)
    with loop_runtime():
        assert cv2.getNumThreads() == 1
        assert sys.getswitchinterval() == pytest.approx(min(switch_s, SWITCH_INTERVAL_S))
        assert gc.get_threshold()[0] == max(threshold[0], YOUNG_THRESHOLD)
        assert gc.get_freeze_count() > 0
        with loop_runtime():  # a second loop, e.g. another thread of a fleet run
            pass
        assert gc.get_threshold()[0] == max(threshold[0], YOUNG_THRESHOLD)
    assert sys.getswitchinterval() == pytest.approx(switch_s)
    assert gc.get_threshold() == threshold
    assert gc.get_freeze_count() == 0
    assert cv2.getNumThreads() == 2


def test_garbage_is_collected_between_frames_the_generations_in_turn() -> None:
    collected: list[int] = []

    def note(phase: str, info: dict[str, Any]) -> None:
        if phase == "start":
            collected.append(info["generation"])

    collector = Collector()
    gc.callbacks.append(note)
    try:
        for _ in range(2 * MIDDLE_EVERY_FRAMES):
            collector.after_frame()
    finally:
        gc.callbacks.remove(note)
    expected = [0] * (MIDDLE_EVERY_FRAMES - 1) + [1]
    assert collected == 2 * expected


def test_a_cycle_made_during_a_loop_is_still_freed() -> None:
    import weakref

    class Node:
        other: Any = None

    with loop_runtime():
        a, b = Node(), Node()
        a.other, b.other = b, a
        alive = weakref.ref(a)
        del a, b
        Collector().after_frame()
        assert alive() is None
