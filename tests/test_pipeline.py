"""The loop with a fake detector: samples, stage timings, sinks, pacing; no camera, no MediaPipe."""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np
import pytest

from roadgaze.capture import SourceInfo, SourceStatus
from roadgaze.config import Config
from roadgaze.geometry import center_ce, forward_model
from roadgaze.pipeline import STAGES, Pipeline, ProcessedFrame, StageTimes, StageTimings
from roadgaze.types import ClosesOnExit, Detection, FaceFeatures, Frame, YawSample


def face_at(yaw_deg: float) -> FaceFeatures:
    """A face whose boundaries and centre come from the paper's forward model."""
    projected = forward_model(yaw_deg, half_width_px=80.0, pivot_x_px=320.0)
    return FaceFeatures(
        x_left_px=float(projected.x_left),
        x_right_px=float(projected.x_right),
        x_center_px=float(projected.x_center),
        roll_deg=0.0,
        box_px=(220.0, 140.0, 420.0, 380.0),
        quality=1.0,
        landmarks_px=np.zeros((0, 3), np.float32),
    )


class ScriptedDetector:
    """Fake LandmarkDetector: the true yaw per call (None: no face), checking time order."""

    def __init__(self, yaws_deg: list[float | None]) -> None:
        self.yaws_deg = list(yaws_deg)
        self.calls: list[float | None] = []
        self.closed = False

    def detect(self, image: np.ndarray, t_s: float | None = None) -> Detection:
        assert t_s is not None and (not self.calls or t_s > (self.calls[-1] or -1.0))
        yaw_deg = self.yaws_deg[len(self.calls)]
        self.calls.append(t_s)
        if yaw_deg is None:
            return Detection(faces=(), driver_index=None)
        return Detection(faces=(face_at(yaw_deg),), driver_index=0)

    def close(self) -> None:
        self.closed = True


class ListSource(ClosesOnExit):
    """Fake FrameSource over blank frames at `fps`."""

    def __init__(self, count: int, fps: float = 30.0) -> None:
        self.count, self.fps = count, fps
        self._status = SourceStatus()

    @property
    def info(self) -> SourceInfo:
        return SourceInfo("list", False, self.fps, self.count, 64, 48)

    @property
    def status(self) -> SourceStatus:
        return self._status

    def __iter__(self) -> Iterator[Frame]:
        for i in range(self.count):
            self._status = SourceStatus(frames_delivered=i + 1)
            yield Frame(index=i, t_s=i / self.fps, image=np.zeros((48, 64, 3), np.uint8))

    def close(self) -> None:
        return None


class Recorder:
    def __init__(self, name: str, order: list[str]) -> None:
        self.name, self.order = name, order
        self.samples: list[YawSample] = []

    def on_sample(self, sample: YawSample) -> None:
        self.samples.append(sample)
        self.order.append(self.name)

    def close(self) -> None:
        return None


class FrameRecorder:
    def __init__(self, order: list[str]) -> None:
        self.order = order
        self.processed: list[ProcessedFrame] = []

    def on_frame(self, processed: ProcessedFrame) -> None:
        self.processed.append(processed)
        self.order.append("frames")

    def close(self) -> None:
        return None


def test_process_gives_center_ce_yaw_and_smoothed_yaw() -> None:
    pipeline = Pipeline(ScriptedDetector([20.0, 20.0]))
    frame = Frame(index=0, t_s=0.0, image=np.zeros((4, 4, 3), np.uint8))
    processed = pipeline.process(frame, decode_ms=1.5)
    sample = processed.sample
    expected = float(center_ce(*(float(v) for v in vars_of(face_at(20.0)))))
    assert sample.face and sample.n_faces == 1
    assert sample.yaw_raw_deg == pytest.approx(expected)
    assert sample.yaw_deg == pytest.approx(expected)
    assert sample.features is not None
    assert vars_of(sample.features) == vars_of(face_at(20.0))
    assert processed.times.decode_ms == 1.5
    assert processed.times.total_ms >= processed.times.landmarks_ms + 1.5


def vars_of(face: FaceFeatures) -> tuple[float, float, float]:
    return face.x_left_px, face.x_right_px, face.x_center_px


def test_no_face_samples_predict_then_the_track_is_kept() -> None:
    yaws: list[float | None] = [None, None, 10.0, 10.0, None, None, 10.0]
    pipeline = Pipeline(ScriptedDetector(yaws))
    samples = [p.sample for p in pipeline.frames(ListSource(len(yaws)))]
    assert [s.face for s in samples] == [y is not None for y in yaws]
    assert samples[0].yaw_deg is None and samples[0].yaw_raw_deg is None
    assert samples[1].yaw_std_deg is None
    assert samples[4].yaw_raw_deg is None
    assert samples[4].yaw_deg is not None
    assert samples[5].yaw_std_deg > samples[4].yaw_std_deg  # type: ignore[operator]
    assert [s.frame for s in samples] == list(range(7))


def test_impossible_geometry_counts_as_face_without_yaw() -> None:
    class Impossible(ScriptedDetector):
        def detect(self, image: np.ndarray, t_s: float | None = None) -> Detection:
            self.calls.append(t_s)
            face = face_at(0.0)
            bad = FaceFeatures(
                x_left_px=100.0,
                x_right_px=90.0,
                x_center_px=95.0,
                roll_deg=0.0,
                box_px=face.box_px,
                quality=1.0,
                landmarks_px=face.landmarks_px,
            )
            return Detection(faces=(bad,), driver_index=0)

    sample = Pipeline(Impossible([])).frames(ListSource(1)).__next__().sample
    assert sample.face and sample.yaw_raw_deg is None and sample.yaw_deg is None


def test_run_feeds_sinks_in_order_and_times_every_stage() -> None:
    order: list[str] = []
    first, frames, last = Recorder("first", order), FrameRecorder(order), Recorder("last", order)
    pipeline = Pipeline(ScriptedDetector([5.0] * 12))
    timings = StageTimings(skip_first=2)
    summary = pipeline.run(ListSource(12), [first, frames, last], timings=timings)
    assert summary.frames == 12 and summary.frames_with_face == 12
    assert order[:3] == ["first", "frames", "last"] and len(order) == 36
    assert [s.frame for s in last.samples] == list(range(12))
    assert frames.processed[3].sample is last.samples[3]
    assert timings.count == 10
    assert set(summary.stages) == set(STAGES)
    total = summary.stages["total"].median_ms
    assert total >= summary.stages["landmarks"].median_ms
    assert summary.overhead_ratio >= 1.0
    assert summary.source_status.frames_delivered == 12


def test_max_frames_stops_the_loop() -> None:
    pipeline = Pipeline(ScriptedDetector([0.0] * 10))
    assert pipeline.run(ListSource(10), max_frames=4).frames == 4


def test_realtime_paces_a_file_at_its_own_rate() -> None:
    pipeline = Pipeline(ScriptedDetector([0.0] * 6))
    start = time.perf_counter()
    pipeline.run(ListSource(6, fps=20.0), realtime=True)
    assert time.perf_counter() - start >= 0.24  # 5 periods of 50 ms


def test_stage_timings_ring_keeps_the_most_recent_frames() -> None:
    timings = StageTimings(capacity=4)
    for value in range(10):
        timings.add(StageTimes(*(float(value),) * 6))
    stats = timings.stats()
    assert timings.count == 10
    assert stats["total"].median_ms == pytest.approx(7.5)  # frames 6..9
    assert StageTimings().stats() == {}


def test_from_config_uses_the_configured_model_and_constants() -> None:
    config = Config.model_validate({"geometry": {"model": "cylindrical"}})
    pipeline = Pipeline.from_config(config, ScriptedDetector([30.0]))
    face = face_at(30.0)
    from roadgaze.geometry import cylindrical

    assert pipeline.raw_yaw_deg(face) == pytest.approx(float(cylindrical(*vars_of(face))))
    assert pipeline.raw_yaw_deg(None) is None
