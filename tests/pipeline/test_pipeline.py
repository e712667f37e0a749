"""The loop with a fake detector: records, stage timings, sinks, pacing, stop; no camera."""

from __future__ import annotations

import time

import numpy as np
import pytest

from fakes import ListSource, ScriptedDetector, face_at
from roadgaze.config import Config
from roadgaze.pipeline import STAGES, Pipeline, StageTimes, StageTimings
from roadgaze.pose.geometry import center_ce
from roadgaze.types import Detection, FaceFeatures, Frame, FrameRecord, Gaze


class Recorder:
    def __init__(self, name: str, order: list[str]) -> None:
        self.name, self.order = name, order
        self.records: list[FrameRecord] = []
        self.frames: list[Frame] = []

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self.records.append(record)
        self.frames.append(frame)
        self.order.append(self.name)

    def close(self) -> None:
        return None


def test_process_gives_center_ce_yaw_and_smoothed_yaw() -> None:
    pipeline = Pipeline(ScriptedDetector([20.0, 20.0]))
    frame = Frame(index=0, t_s=0.0, image=np.zeros((4, 4, 3), np.uint8))
    processed = pipeline.process(frame, decode_ms=1.5)
    sample = processed.record.sample
    expected = float(center_ce(*(float(v) for v in vars_of(face_at(20.0)))))
    assert sample.face and sample.n_faces == 1
    assert sample.yaw_raw_deg == pytest.approx(expected)
    assert sample.yaw_deg == pytest.approx(expected)
    assert sample.features is not None
    assert vars_of(sample.features) == vars_of(face_at(20.0))
    assert processed.times.decode_ms == 1.5
    assert processed.times.total_ms >= processed.times.landmarks_ms + 1.5
    assert processed.record.verdict.gaze is Gaze.ON_ROAD and processed.record.alerts == ()


def vars_of(face: FaceFeatures) -> tuple[float, float, float]:
    return face.x_left_px, face.x_right_px, face.x_center_px


def test_no_face_samples_predict_then_the_track_is_kept() -> None:
    yaws: list[float | None] = [None, None, 10.0, 10.0, None, None, 10.0]
    pipeline = Pipeline(ScriptedDetector(yaws))
    samples = [p.record.sample for p in pipeline.frames(ListSource(len(yaws)))]
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

    sample = Pipeline(Impossible([])).frames(ListSource(1)).__next__().record.sample
    assert sample.face and sample.yaw_raw_deg is None and sample.yaw_deg is None


def test_run_feeds_sinks_in_order_and_times_every_stage() -> None:
    order: list[str] = []
    first, middle, last = (
        Recorder("first", order),
        Recorder("middle", order),
        Recorder("last", order),
    )
    pipeline = Pipeline(ScriptedDetector([5.0] * 12))
    timings = StageTimings(skip_first=2)
    summary = pipeline.run(ListSource(12), [first, middle, last], timings=timings)
    assert summary.frames == 12 and summary.frames_with_face == 12
    assert order[:3] == ["first", "middle", "last"] and len(order) == 36
    assert [r.frame for r in last.records] == list(range(12))
    assert middle.records[3] is last.records[3]  # one immutable record per frame
    assert middle.frames[3].index == 3
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
        timings.add(StageTimes(*(float(value),) * 7))
    stats = timings.stats()
    assert timings.count == 10
    assert stats["total"].median_ms == pytest.approx(7.5)  # frames 6..9
    assert StageTimings().stats() == {}


def test_from_config_uses_the_configured_model_and_constants() -> None:
    config = Config.model_validate({"geometry": {"model": "cylindrical"}})
    pipeline = Pipeline.from_config(config, ScriptedDetector([30.0]))
    face = face_at(30.0)
    from roadgaze.pose.geometry import cylindrical

    assert pipeline.pose.raw_yaw_deg(face) == pytest.approx(float(cylindrical(*vars_of(face))))
    assert pipeline.pose.raw_yaw_deg(None) is None


def test_the_monitor_is_a_stage_of_the_loop() -> None:
    """A 4 s glance to -30 deg (zone away) at 30 fps: the record 3 s in carries the alert."""
    yaws: list[float | None] = [-30.0 if 30 <= i < 150 else 0.0 for i in range(180)]
    config = Config.model_validate({"monitor": {"neutral_yaw_deg": 0.0}})
    pipeline = Pipeline.from_config(config, ScriptedDetector(yaws))
    records = [p.record for p in pipeline.frames(ListSource(len(yaws)))]
    raised = [(r.frame, a.label) for r in records for a in r.alerts]
    off_from = next(r.frame for r in records if r.verdict.gaze is Gaze.OFF_ROAD)
    assert 30 <= off_from <= 33  # the smoother follows the step within a few frames
    assert raised[0] == (off_from + 90, "long_distraction:warning")
    assert [label for _, label in raised] == ["long_distraction:warning", "cleared:info"]
    assert records[60].verdict.gaze is Gaze.OFF_ROAD
    assert records[60].verdict.off_road_s == pytest.approx((60 - off_from) / 30)


def test_speed_below_the_minimum_gates_the_alerts() -> None:
    yaws: list[float | None] = [-30.0] * 150
    config = Config.model_validate({"monitor": {"neutral_yaw_deg": 0.0}})
    pipeline = Pipeline.from_config(config, ScriptedDetector(yaws), speed=lambda: 10.0)
    records = [p.record for p in pipeline.frames(ListSource(len(yaws)))]
    assert not any(r.alerts for r in records)
    assert records[-1].verdict.moving is False and records[-1].verdict.speed_kmh == 10.0


def test_a_stop_ends_the_loop_before_the_next_frame() -> None:
    import threading

    stop = threading.Event()

    class StopAfter:
        def on_record(self, record: FrameRecord, frame: Frame) -> None:
            if record.frame == 4:
                stop.set()

        def close(self) -> None:
            return None

    pipeline = Pipeline(ScriptedDetector([0.0] * 20))
    assert pipeline.run(ListSource(20), [StopAfter()], stop=stop).frames == 5


def test_a_lap_glance_seen_through_the_matrix_pitch_raises_a_long_distraction() -> None:
    """MediaPipe's matrix pitch of -25 deg reads -37 with the down gain: the lap, not the road."""
    pitches = [-25.0 if 30 <= i < 150 else 0.0 for i in range(180)]
    config = Config.model_validate({"monitor": {"neutral_yaw_deg": 0.0, "neutral_pitch_deg": 0.0}})
    pipeline = Pipeline.from_config(config, ScriptedDetector([0.0] * 180, pitches))
    records = [p.record for p in pipeline.frames(ListSource(len(pitches)))]
    assert records[60].sample.pitch_raw_deg == pytest.approx(-25.0 * 1.48)
    assert records[60].sample.pitch_deg == pytest.approx(-37.0, abs=0.5)
    assert records[60].sample.roll_deg == 0.0
    assert (records[60].verdict.zone, records[60].verdict.on_road) == ("lap", False)
    assert (records[10].verdict.zone, records[10].verdict.on_road) == ("road", True)
    raised = [(r.frame, a.label) for r in records for a in r.alerts]
    off_from = next(r.frame for r in records if r.verdict.zone == "lap")
    assert raised == [(off_from + 90, "long_distraction:warning"), (raised[1][0], "cleared:info")]


def test_the_geometric_pitch_model_is_selectable() -> None:
    config = Config.model_validate({"pose": {"pitch_model": "geometric"}})
    pipeline = Pipeline.from_config(config, ScriptedDetector([0.0]))
    face = face_at(0.0, pitch_deg=-20.0)
    assert pipeline.pose.raw_pitch_deg(face) is None  # the fake face has no mid-line
    from dataclasses import replace

    from roadgaze.pose.pitch import midline_forward_model

    line = midline_forward_model(-20.0)
    face = replace(
        face,
        y_top_px=float(line.y_top),
        y_bottom_px=float(line.y_bottom),
        y_center_px=float(line.y_center),
    )
    assert pipeline.pose.raw_pitch_deg(face) == pytest.approx(-20.0)  # no down gain
