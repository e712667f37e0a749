"""The driver a recording chose, read back with its frames: the recorder's `/roadgaze/driver`
message before each camera frame (in the recorded image's pixels), the reader's checks of an
untrusted file, the loop telling the detector, and the two-person clip judged on the same person
by its drive and by its recording's replay."""

from __future__ import annotations

import json
import logging
import subprocess
import sys
from pathlib import Path

import pytest

from fakes import ListSource, ScriptedDetector
from foxglove_helpers import pipeline_records, read_mcap
from repo_paths import VIDEOS, child_env
from roadgaze.capture import McapSource
from roadgaze.capture.mcap_driver import (
    DRIVER_TOPIC,
    DRIVERS_WAITING,
    RecordedDrivers,
    driver_message,
    parse_driver,
)
from roadgaze.config import Config, RecordConfig
from roadgaze.outputs.foxglove.channels import TOPIC_IMAGE
from roadgaze.outputs.foxglove.open import replay_recorder
from roadgaze.pipeline import Pipeline
from roadgaze.types import Frame, RecordedDriver

YAWS: list[float | None] = [0.0] * 6 + [None] * 3 + [10.0] * 6
"""A face, none for three frames, a face again."""


def record(path: Path, width_px: int) -> list[tuple[object, Frame]]:
    records = pipeline_records(YAWS)
    settings = RecordConfig(image_format="png", image_fps=1000.0, image_width_px=width_px)
    config = Config(record=settings)
    with replay_recorder(config, "numbered", path) as recorder:
        for frame_record, frame in records:
            recorder.on_record(frame_record, frame)
    return records  # type: ignore[return-value]


@pytest.mark.parametrize("width_px", [160, 80])
def test_each_camera_frame_carries_its_drivers_box_in_the_recorded_pixels(
    tmp_path: Path, width_px: int
) -> None:
    path = tmp_path / "drive.mcap"
    records = record(path, width_px)
    scale = width_px / 160  # the frames are 160 x 120
    contents = read_mcap(path)
    drivers = contents.json(DRIVER_TOPIC)
    stamps = [message.log_time for message in contents.messages[DRIVER_TOPIC]]
    assert stamps == [message.log_time for message in contents.messages[TOPIC_IMAGE]]
    with McapSource(path) as source:
        frames = list(source)
    assert len(frames) == len(records) == len(drivers)
    for frame, (frame_record, _), message in zip(frames, records, drivers, strict=True):
        features = frame_record.sample.features  # type: ignore[attr-defined]
        assert frame.recorded_driver is not None
        if features is None:
            assert message["box_px"] is None and frame.recorded_driver.box_px is None
            continue
        expected = [value * scale for value in features.box_px]
        assert frame.recorded_driver.box_px == pytest.approx(expected, abs=0.01)
        assert message["n_faces"] == 1 and message["driver_ambiguous"] == ""
        assert frame.image.shape[1] == width_px


@pytest.mark.parametrize(
    ("payload", "expected"),
    [
        (driver_message((1.0, 2.0, 30.0, 40.0), 2, ""), RecordedDriver((1.0, 2.0, 30.0, 40.0))),
        (driver_message(None, 0, ""), RecordedDriver(None)),
        ({"box_px": [1, 2, 30, 40]}, RecordedDriver((1.0, 2.0, 30.0, 40.0))),
        ({"box_px": [30, 2, 1, 40]}, None),  # x_min after x_max
        ({"box_px": [1, 2, 30]}, None),
        ({"box_px": [1, 2, 30, "40"]}, None),
        ({"box_px": [1, 2, 30, True]}, None),
        ({"box_px": [1, 2, 30, 1e300]}, None),
        ({"box_px": {"x": 1}}, None),
        ({"n_faces": 2}, None),
        ([1, 2, 3, 4], None),
        ("nothing", None),
    ],
)
def test_a_driver_message_is_read_only_when_well_formed(
    payload: object, expected: RecordedDriver | None
) -> None:
    assert parse_driver(json.dumps(payload).encode()) == expected


@pytest.mark.parametrize("data", [b"{", b"\xff\xfe", b"[" * 100_000, b" " * 5000 + b"{}"])
def test_broken_or_oversized_bytes_are_not_a_driver(data: bytes) -> None:
    assert parse_driver(data) is None


def test_driver_messages_wait_for_their_frame_in_bounded_memory(
    caplog: pytest.LogCaptureFixture,
) -> None:
    drivers = RecordedDrivers()
    box = json.dumps(driver_message((0.0, 0.0, 10.0, 10.0), 1, "")).encode()
    with caplog.at_level(logging.WARNING, logger="roadgaze.capture.mcap_driver"):
        for log_time in range(1000):
            drivers.note(log_time, box)
        drivers.note(1000, b"{broken")
        drivers.note(1001, b"{broken")
    assert len(drivers._waiting) == DRIVERS_WAITING
    assert drivers.take(999) == RecordedDriver((0.0, 0.0, 10.0, 10.0))
    assert drivers.take(999) is None and drivers.take(0) is None
    assert drivers.ignored == 2 and len(caplog.records) == 1


class Following(ScriptedDetector):
    """A scripted detector that notes what the loop tells it a recording chose."""

    def __init__(self, yaws_deg: list[float | None]) -> None:
        super().__init__(yaws_deg)
        self.followed: list[RecordedDriver | None] = []

    def follow(self, recorded: RecordedDriver | None) -> None:
        self.followed.append(recorded)


def test_the_loop_tells_the_detector_each_frames_recorded_driver() -> None:
    chosen = [RecordedDriver((1.0, 1.0, 9.0, 9.0)), None, RecordedDriver(None)]
    frames = [
        Frame(frame.index, frame.t_s, frame.image, recorded)
        for frame, recorded in zip(ListSource(3), chosen, strict=True)
    ]

    class Frames(ListSource):
        def __iter__(self):  # type: ignore[no-untyped-def]
            yield from frames

    detector = Following([0.0, 0.0, 0.0])
    list(Pipeline.from_config(Config(), detector).frames(Frames(3)))
    assert detector.followed == chosen


# ---------------------------------------------------------------- the two-person clip

TWO = VIDEOS / "head-pose-face-detection-female-and-male.gif"


def replay(source: Path, out: Path, *extra: str) -> list[dict[str, object]]:
    command = [sys.executable, "-m", "roadgaze", "replay", str(source), "--out", str(out)]
    result = subprocess.run(
        [*command, *extra],
        capture_output=True,
        text=True,
        timeout=600,
        env=child_env(),
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    return [json.loads(line) for line in out.read_text().splitlines()]


@pytest.mark.slow
@pytest.mark.skipif(
    not TWO.is_file(), reason="the evaluation videos are not present ($ROADGAZE_DATA/videos)"
)
def test_a_drive_and_its_recording_judge_the_same_person(tmp_path: Path) -> None:
    """Two faces of nearly the same size: the GIF's replay follows the man (the driver's seat of
    a left-hand-drive car, camera in front: the image's right), and so does the replay of its
    recording, on every recorded frame (JPEG recompression once made it follow the woman, with
    a long distraction "head in centre_stack")."""
    mcap = tmp_path / "x.mcap"
    drive = replay(TWO, tmp_path / "drive.jsonl", "--mcap", str(mcap))
    recording = replay(mcap, tmp_path / "recording.jsonl")
    by_time = {round(float(line["t_s"]), 3): line for line in drive}  # type: ignore[arg-type]
    assert len(recording) >= 20
    for line in recording:
        original = by_time[round(float(line["t_s"]), 3)]  # type: ignore[arg-type]
        assert line["face"] and original["face"] and line["n_faces"] == 2
        assert abs(float(line["yaw_raw_deg"]) - float(original["yaw_raw_deg"])) < 3.0  # type: ignore[arg-type]
        assert line["driver_ambiguous"] == original["driver_ambiguous"] == ""
    for lines in (drive, recording):
        assert [a for line in lines for a in line["alerts"]] == []  # type: ignore[attr-defined]
        assert all(3.0 <= float(line["yaw_raw_deg"]) <= 17.0 for line in lines)  # type: ignore[arg-type]
