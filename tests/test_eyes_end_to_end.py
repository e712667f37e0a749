"""The eyes end to end on a rendered drive: real MediaPipe, the pipeline, the monitor's alerts at
their times, the records and the VSS signals (no evaluation data needed)."""

from __future__ import annotations

import pytest

from roadgaze.config import Config
from roadgaze.pipeline import Pipeline, create_detector
from roadgaze.synth import EyeRenderer, load_photo, parse_timeline, render_frames
from roadgaze.transport import vss_values
from roadgaze.types import EyeStatus, Frame, FrameRecord

FPS = 15.0
TIMELINE = "0:2,0;eyes=closed:1.5,0:2,0;eye_yaw=-30;eye_pitch=-25:4,0:1.5"
"""Road 2 s, a 1.5 s closure from 2.0 s, road, an eyes-only glance from 5.5 s to 9.5 s."""


@pytest.fixture(scope="module")
def records() -> list[FrameRecord]:
    config = Config()
    renderer = EyeRenderer(load_photo(), (640, 480), config=config)
    detector = create_detector(config)
    try:
        pipeline = Pipeline.from_config(config, detector)
        result = []
        for index, (row, image) in enumerate(
            render_frames(parse_timeline(TIMELINE), renderer, FPS)
        ):
            result.append(pipeline.process(Frame(index, float(row[0]), image)).record)
        return result
    finally:
        detector.close()


@pytest.mark.slow
def test_closures_and_an_eyes_only_glance_raise_their_alerts(records: list[FrameRecord]) -> None:
    alerts = [(alert.t_s, alert.label) for record in records for alert in record.alerts]
    labels = [label for _, label in alerts]
    assert labels == [
        "microsleep:warning",
        "cleared:info",
        "long_distraction:warning",
        "cleared:info",
    ]
    times = dict(zip(labels[::2], [t for t, _ in alerts][::2], strict=True))
    # The lids are shut 0.1 s after the segment starts: microsleep 1 s after that.
    assert 3.0 <= times["microsleep:warning"] <= 3.3
    assert 8.4 <= times["long_distraction:warning"] <= 8.8
    yaws = [r.sample.yaw_deg for r in records if r.sample.yaw_deg is not None]
    assert max(abs(y) for y in yaws) < 3.0  # the head never left the road


@pytest.mark.slow
def test_records_and_vss_during_the_closure_and_the_glance(records: list[FrameRecord]) -> None:
    config = Config()
    closed = records[round(3.0 * FPS)]
    assert closed.verdict.eyes.status is EyeStatus.CLOSED
    assert closed.verdict.eyes.closure_s == pytest.approx(0.9, abs=0.15)
    assert closed.verdict.eyes_on_road is False
    values = vss_values(closed, config.monitor)
    assert values["Vehicle.Driver.IsEyesOnRoad"] is False
    assert values["Vehicle.Driver.FatigueLevel"] > 80.0
    glance = records[round(8.0 * FPS)]
    assert glance.verdict.eyes.status is EyeStatus.OPEN
    assert glance.verdict.eyes.gaze_source == "eyes"
    assert glance.verdict.zone not in ("road", None)
    gaze = glance.verdict.eyes.gaze_yaw_deg
    assert gaze is not None and gaze < -12.0
    assert vss_values(glance, config.monitor)["Vehicle.Driver.DistractionLevel"] > 70.0
