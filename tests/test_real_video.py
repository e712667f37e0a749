"""Real video as regression tests: Intel's three sample GIFs (../shared/data/videos) through the
whole pipeline with the default settings. The female sweep never reads `lap` (uncalibrated eyes
and a neutral learned mid-sweep once put her there), the near-frontal man reads `road`, the
two-person clip keeps its driver, and the eye calibration is in the records and on the video."""

from __future__ import annotations

import itertools

import pytest

from repo_paths import VIDEOS
from roadgaze.capture.open import open_source
from roadgaze.config import Config
from roadgaze.outputs.annotate_eyes import eyes_line
from roadgaze.outputs.records import record_fields
from roadgaze.pipeline import Pipeline, create_detector
from roadgaze.types import EyeCalibrationStatus, FrameRecord

pytestmark = [
    pytest.mark.skipif(
        not VIDEOS.is_dir(), reason="../shared/data/videos not present (evaluation data)"
    ),
    pytest.mark.slow,
]
FEMALE = "head-pose-face-detection-female.gif"
MALE = "head-pose-face-detection-male.gif"
TWO = "head-pose-face-detection-female-and-male.gif"


@pytest.fixture(scope="module")
def clips() -> dict[str, list[FrameRecord]]:
    config = Config()
    result = {}
    for name in (FEMALE, MALE, TWO):
        detector = create_detector(config)
        try:
            pipeline = Pipeline.from_config(config, detector)
            with open_source(str(VIDEOS / name), config) as source:
                result[name] = [pipeline.process(frame).record for frame in source]
        finally:
            detector.close()
    return result


def test_the_female_sweep_is_never_in_the_lap(clips: dict[str, list[FrameRecord]]) -> None:
    records = clips[FEMALE]
    assert len(records) == 23 and all(r.sample.face for r in records)
    assert [r.verdict.zone for r in records if r.verdict.zone == "lap"] == []
    # Her head passes through ahead twice (frames 8-10 and 18-21, yaw -20..+17, pitch near her
    # road pitch): road, judged on the head pose (the sweep is too short to calibrate her eyes).
    for frame in (8, 9, 10, 18, 19, 20, 21):
        assert records[frame].verdict.zone == "road", frame
    assert {r.verdict.eyes.gaze_source for r in records} == {"head"}
    assert records[-1].verdict.eyes.calibration is EyeCalibrationStatus.NONE


def test_the_near_frontal_man_is_on_the_road(clips: dict[str, list[FrameRecord]]) -> None:
    records = clips[MALE]
    road = sum(1 for r in records if r.verdict.zone == "road")
    assert road >= 0.95 * len(records)
    states = [r.verdict.eyes.calibration for r in records]
    assert states[1] is EyeCalibrationStatus.LEARNING
    calibrated = [r.t_s for r in records if r.verdict.eyes.calibration.value == "calibrated"]
    assert calibrated and 2.9 <= calibrated[0] <= 3.2  # 3 s of open eyes on the road
    # His eyes read about 24 deg downward looking ahead: learned, not a glance into the lap.
    eye_pitch = [r.verdict.eyes.eye_pitch_deg for r in records[5:]]
    assert max(p for p in eye_pitch if p is not None) < -15.0
    assert all(r.verdict.eyes.status.value == "open" for r in records)


def test_the_two_person_clip_keeps_its_driver(clips: dict[str, list[FrameRecord]]) -> None:
    records = clips[TWO]
    assert all(r.sample.n_faces == 2 and r.sample.face for r in records)
    centres = [r.sample.features.x_center_px for r in records if r.sample.features is not None]
    assert len(centres) == len(records)
    steps = [abs(b - a) for a, b in itertools.pairwise(centres)]
    assert max(steps) < 20.0  # the same face every frame: no jump to the other person
    assert all(r.verdict.zone == "road" for r in records)
    # His slow blink (frames 42-47) is still a closure.
    assert [r.sample.frame for r in records if r.verdict.eyes.status.value == "closed"] == list(
        range(42, 48)
    )


def test_the_calibration_is_in_the_record_and_on_the_video(
    clips: dict[str, list[FrameRecord]],
) -> None:
    first, last = clips[MALE][1], clips[MALE][-1]
    assert record_fields(first)["eye_calibration"] == "learning"
    assert record_fields(last)["eye_calibration"] == "calibrated"
    assert "eyes learning" in eyes_line(first)
    assert "learning" not in eyes_line(last) and "calibrated" not in eyes_line(last)
