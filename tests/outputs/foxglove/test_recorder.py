"""The recorder sink writing one MCAP file, read back with the `mcap` reader: the channels and
their schemas, one record per frame, capture-time stamps in order, decodable camera frames,
alerts and logs; images dropped (counted) but records never; a failed write in one line."""

from __future__ import annotations

import errno
import itertools
import logging
import threading
import time
from pathlib import Path

import cv2
import jsonschema
import numpy as np
import pytest

from foxglove_helpers import pipeline_records, protobuf_message, read_mcap
from roadgaze.config import Config, RecordConfig
from roadgaze.errors import RoadgazeError
from roadgaze.outputs import RECORD_FIELDS
from roadgaze.outputs.foxglove import recorder as recorder_module
from roadgaze.outputs.foxglove.channels import (
    TOPIC_ALERTS,
    TOPIC_ANNOTATIONS,
    TOPIC_DRIVER,
    TOPIC_IMAGE,
    TOPIC_LIMITS,
    TOPIC_LOG,
    TOPIC_RECORD,
    TOPIC_STATE,
    TOPIC_SUPPORT,
    TOPICS,
)
from roadgaze.outputs.foxglove.open import replay_recorder, vehicle_recorder
from roadgaze.outputs.foxglove.recorder import FoxgloveRecorder
from roadgaze.outputs.foxglove.targets import TrackedFile
from roadgaze.outputs.records import record_fields
from roadgaze.transport import json_schemas

RECORDS = pipeline_records()


def config_with(**record: object) -> Config:
    return Config(record=RecordConfig(**record))  # type: ignore[arg-type]


def record_all(
    path: Path, config: Config, state: bytes | None = b'{"s": 1}', **kwargs: object
) -> FoxgloveRecorder:
    recorder = replay_recorder(
        config,
        "numbered",
        path,
        state=(lambda: state) if state is not None else None,
        **kwargs,  # type: ignore[arg-type]
    )
    with recorder:
        for record, frame in RECORDS:
            recorder.on_record(record, frame)
    return recorder


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, FoxgloveRecorder]:
    path = tmp_path_factory.mktemp("mcap") / "drive.mcap"
    return path, record_all(path, config_with(image_fps=5.0))


def test_each_channel_has_its_well_known_or_own_schema(
    recording: tuple[Path, FoxgloveRecorder],
) -> None:
    contents = read_mcap(recording[0])
    assert contents.schemas == {
        TOPIC_IMAGE: "foxglove.CompressedImage",
        TOPIC_ANNOTATIONS: "foxglove.ImageAnnotations",
        TOPIC_RECORD: "roadgaze.record",
        TOPIC_LIMITS: "roadgaze.limits",
        TOPIC_ALERTS: "roadgaze.alert/4",
        TOPIC_STATE: "roadgaze.state/6",
        TOPIC_SUPPORT: "roadgaze.support/1",
        TOPIC_DRIVER: "roadgaze.driver/1",
    }
    assert contents.encodings[TOPIC_IMAGE] == ("protobuf", "protobuf")
    assert contents.encodings[TOPIC_RECORD] == ("jsonschema", "json")
    import json

    alert_schema = json.loads(contents.schema_data[TOPIC_ALERTS])
    assert alert_schema == json_schemas()["alert"]  # what `roadgaze schema alert` prints
    support_schema = json.loads(contents.schema_data[TOPIC_SUPPORT])
    assert support_schema == json_schemas()["support"]
    supports, records = contents.json(TOPIC_SUPPORT), contents.json(TOPIC_RECORD)
    assert supports and len(supports) == len(records)  # one per frame
    assert [m["seq"] for m in supports] == list(range(len(supports)))
    assert [m["forward"]["level"] for m in supports] == [r["support_forward"] for r in records]


def test_one_record_per_frame_equal_to_the_jsonl_record(
    recording: tuple[Path, FoxgloveRecorder],
) -> None:
    contents = read_mcap(recording[0])
    records = contents.json(TOPIC_RECORD)
    assert contents.counts[TOPIC_RECORD] == len(RECORDS) == len(records)
    assert records == [record_fields(record) for record, _ in RECORDS]
    schema = __import__("json").loads(contents.schema_data[TOPIC_RECORD])
    assert list(schema["properties"]) == list(RECORD_FIELDS)
    for record in records[::20]:
        jsonschema.validate(record, schema)


def test_every_message_is_stamped_with_its_frames_capture_time(
    recording: tuple[Path, FoxgloveRecorder],
) -> None:
    contents = read_mcap(recording[0])
    frame_ns = [round(record.t_s * 1e9) for record, _ in RECORDS]
    stamps = [message.log_time for message in contents.messages[TOPIC_RECORD]]
    assert stamps == frame_ns
    image_ns = [message.log_time for message in contents.messages[TOPIC_IMAGE]]
    annotation_ns = [message.log_time for message in contents.messages[TOPIC_ANNOTATIONS]]
    assert annotation_ns == image_ns  # drawn on the camera frames
    for topic in TOPICS:
        assert all(m.publish_time == m.log_time for m in contents.messages[topic])
    for topic in (TOPIC_IMAGE, TOPIC_LIMITS, TOPIC_ALERTS, TOPIC_STATE):
        stamps = [message.log_time for message in contents.messages[topic]]
        assert stamps == sorted(stamps) and set(stamps) <= set(frame_ns), topic


def test_camera_frames_at_the_image_rate_decode_to_the_frames(
    recording: tuple[Path, FoxgloveRecorder],
) -> None:
    contents = read_mcap(recording[0])
    images = contents.messages[TOPIC_IMAGE]
    duration_s = RECORDS[-1][0].t_s
    assert len(images) == int(duration_s * 5.0 + 1e-9) + 1 == recording[1].images_written
    frames = {round(record.t_s * 1e9): frame for record, frame in RECORDS}
    for message in images:
        image = protobuf_message(contents, TOPIC_IMAGE, message.data)
        assert image.format == "jpeg" and image.frame_id == "driver_camera"
        assert image.timestamp.seconds * 10**9 + image.timestamp.nanos == message.log_time
        decoded = cv2.imdecode(np.frombuffer(image.data, np.uint8), cv2.IMREAD_COLOR)
        original = frames[message.log_time].image
        assert decoded.shape == original.shape
        assert np.abs(decoded.astype(int) - original).mean() < 3.0  # JPEG at quality 80


def test_annotations_draw_the_face_in_image_pixels(
    recording: tuple[Path, FoxgloveRecorder],
) -> None:
    contents = read_mcap(recording[0])
    image_stamps = {message.log_time for message in contents.messages[TOPIC_IMAGE]}
    record, _ = RECORDS[0]
    first = protobuf_message(
        contents, TOPIC_ANNOTATIONS, contents.messages[TOPIC_ANNOTATIONS][0].data
    )
    assert contents.messages[TOPIC_ANNOTATIONS][0].log_time in image_stamps
    box, left, _, centre, landmarks = first.points
    x_min, y_min, x_max, y_max = record.sample.features.box_px
    corners = [(x_min, y_min), (x_max, y_min), (x_max, y_max), (x_min, y_max)]
    assert [(p.x, p.y) for p in box.points] == corners
    # No roll: the boundaries are vertical lines at the roll-removed x.
    assert [p.x for p in centre.points] == pytest.approx([record.sample.features.x_center_px] * 2)
    assert [p.x for p in left.points] == pytest.approx([record.sample.features.x_left_px] * 2)
    assert len(landmarks.points) == 25
    assert "zone road" in first.texts[0].text
    turned = [
        protobuf_message(contents, TOPIC_ANNOTATIONS, message.data)
        for message in contents.messages[TOPIC_ANNOTATIONS]
    ]
    assert any(len(a.texts) == 2 and a.texts[1].text.startswith("ACTIVE: ") for a in turned)


def test_limits_are_the_road_zone_around_the_neutral_and_the_thresholds(
    recording: tuple[Path, FoxgloveRecorder],
) -> None:
    monitor = Config().monitor
    contents = read_mcap(recording[0])
    limits = contents.json(TOPIC_LIMITS)
    stamps = [message.log_time for message in contents.messages[TOPIC_LIMITS]]
    at = {round(record.t_s * 1e9): record for record, _ in RECORDS}
    # Logged when the learned neutral moves, and at least every state interval (1 s).
    changed = [
        round(b.t_s * 1e9)
        for (a, _), (b, _) in itertools.pairwise(RECORDS)
        if (a.verdict.neutral_yaw_deg, a.verdict.neutral_pitch_deg)
        != (b.verdict.neutral_yaw_deg, b.verdict.neutral_pitch_deg)
    ]
    assert stamps[0] == 0 and set(changed) <= set(stamps)
    assert max(b - a for a, b in itertools.pairwise(stamps)) <= 1_000_000_000
    for stamp, limit in zip(stamps, limits, strict=True):
        record = at[stamp]
        neutral = record.verdict.neutral_yaw_deg
        assert limit["yaw_min_deg"] == pytest.approx(
            neutral - monitor.road_half_width_deg, abs=1e-3
        )
        assert limit["yaw_max_deg"] == pytest.approx(
            neutral + monitor.road_half_width_deg, abs=1e-3
        )
        low, high = monitor.road_pitch_deg
        assert limit["pitch_min_deg"] == pytest.approx(
            record.verdict.neutral_pitch_deg + low - monitor.hysteresis_deg, abs=1e-3
        )
        assert limit["pitch_max_deg"] == pytest.approx(
            record.verdict.neutral_pitch_deg + high + monitor.hysteresis_deg, abs=1e-3
        )
        assert limit["long_distraction_s"] == monitor.long_distraction_s
        assert limit["vats_threshold_s"] == monitor.vats_threshold_s


def test_alerts_are_the_monitors_alerts_as_alert_messages(
    recording: tuple[Path, FoxgloveRecorder],
) -> None:
    raised = [(alert, record.t_s) for record, _ in RECORDS for alert in record.alerts]
    assert len(raised) >= 2  # a long distraction, then its escalation or clearing
    alerts = read_mcap(recording[0]).json(TOPIC_ALERTS)
    assert [(a["kind"], a["level"], a["t_s"]) for a in alerts] == [
        (alert.kind.value, alert.level.value, alert.t_s) for alert, _ in raised
    ]
    assert [a["seq"] for a in alerts] == list(range(len(alerts)))
    for alert in alerts:
        jsonschema.validate(alert, json_schemas()["alert"])


def test_state_every_second_and_at_the_end(recording: tuple[Path, FoxgloveRecorder]) -> None:
    states = read_mcap(recording[0]).messages[TOPIC_STATE]
    duration_s = RECORDS[-1][0].t_s
    assert len(states) == int(duration_s / 1.0) + 1 + 1
    assert all(message.data == b'{"s": 1}' for message in states)


def test_metadata_names_the_time_base_and_the_configuration(
    recording: tuple[Path, FoxgloveRecorder],
) -> None:
    metadata = read_mcap(recording[0]).metadata
    assert metadata["roadgaze"]["time_offset_ns"] == "0"
    assert metadata["roadgaze"]["time_base"] == "source"
    assert Config.model_validate(
        {name: __import__("json").loads(text) for name, text in metadata["roadgaze.config"].items()}
    ) == config_with(image_fps=5.0)


def test_log_lines_are_recorded_with_their_level(tmp_path: Path) -> None:
    path = tmp_path / "log.mcap"
    recorder = replay_recorder(Config(), "numbered", path)
    with recorder:
        for index, (record, frame) in enumerate(RECORDS[:10]):
            recorder.on_record(record, frame)
            if index == 4:
                logging.getLogger("roadgaze.test").warning("camera %s lost", "X")
                time.sleep(0.05)
    contents = read_mcap(path)
    (message,) = contents.messages[TOPIC_LOG]
    line = protobuf_message(contents, TOPIC_LOG, message.data)
    assert line.message == "camera X lost" and line.name == "roadgaze.test" and line.level == 3
    assert message.log_time == round(RECORDS[4][0].t_s * 1e9)


def test_without_images_there_is_no_camera_channel(tmp_path: Path) -> None:
    path = tmp_path / "no-images.mcap"
    recorder = record_all(path, config_with(images=False))
    contents = read_mcap(path)
    assert TOPIC_IMAGE not in contents.schemas and recorder.images_written == 0
    assert contents.counts[TOPIC_RECORD] == len(RECORDS)


def test_png_images_are_the_frames_exactly_and_scaled_down_when_wider(tmp_path: Path) -> None:
    path = tmp_path / "png.mcap"
    record_all(path, config_with(image_format="png", image_fps=1000.0, image_width_px=80))
    contents = read_mcap(path)
    assert contents.counts[TOPIC_IMAGE] == len(RECORDS)
    message = contents.messages[TOPIC_IMAGE][7]
    image = protobuf_message(contents, TOPIC_IMAGE, message.data)
    decoded = cv2.imdecode(np.frombuffer(image.data, np.uint8), cv2.IMREAD_COLOR)
    expected = cv2.resize(RECORDS[7][1].image, (80, 60), interpolation=cv2.INTER_AREA)
    assert image.format == "png" and np.array_equal(decoded, expected)
    annotations = protobuf_message(
        contents, TOPIC_ANNOTATIONS, contents.messages[TOPIC_ANNOTATIONS][7].data
    )
    x_min = RECORDS[7][0].sample.features.box_px[0]
    assert annotations.points[0].points[0].x == pytest.approx(x_min * 0.5)


def test_a_busy_image_thread_drops_camera_frames_never_records(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    release = threading.Event()
    real = recorder_module.encode_image

    def slow(*args: object) -> bytes:
        release.wait(5.0)
        return real(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(recorder_module, "encode_image", slow)
    path = tmp_path / "drops.mcap"
    recorder = replay_recorder(
        config_with(image_fps=1000.0, queue_frames=8), "numbered", path, block_on_images=False
    )
    with recorder:
        for record, frame in RECORDS:
            recorder.on_record(record, frame)
        release.set()
    contents = read_mcap(path)
    assert contents.counts[TOPIC_RECORD] == len(RECORDS)
    assert recorder.images_written == contents.counts[TOPIC_IMAGE] <= 1 + 2
    assert recorder.images_dropped == len(RECORDS) - recorder.images_written
    assert {m.log_time for m in contents.messages[TOPIC_IMAGE]} <= {
        m.log_time for m in contents.messages[TOPIC_RECORD]
    }


def test_a_replay_read_flat_out_waits_for_its_images_instead(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    real = recorder_module.encode_image

    def slow(*args: object) -> bytes:
        time.sleep(0.002)
        return real(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(recorder_module, "encode_image", slow)
    recorder = record_all(
        tmp_path / "all.mcap", config_with(image_fps=1000.0), block_on_images=True
    )
    assert recorder.images_written == len(RECORDS) and recorder.images_dropped == 0


def test_a_failed_write_ends_a_replay_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A disk that fills up after 20 kB: the operating system's reason, once, from the loop."""
    written = [0]
    real = TrackedFile.write

    def filling(self: TrackedFile, data: bytes | bytearray) -> int:
        written[0] += len(data)
        if written[0] > 20_000:
            self.error = self.error or OSError(errno.ENOSPC, "No space left on device")
            raise self.error
        return real(self, data)

    monkeypatch.setattr(TrackedFile, "write", filling)
    path = tmp_path / "full.mcap"
    recorder = replay_recorder(config_with(flush_s=0.05, image_fps=30.0), "numbered", path)
    message = rf"^cannot write MCAP {path}: No space left on device$"
    with pytest.raises(RoadgazeError, match=message), recorder:
        for record, frame in RECORDS:
            recorder.on_record(record, frame)
            time.sleep(0.002)
    assert recorder.failure is not None and 0 < recorder.records_written < len(RECORDS)


def test_a_stopped_recording_is_a_problem_of_the_services_state(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from roadgaze.transport import Health, Keys

    def full(self: TrackedFile, data: bytes | bytearray) -> int:
        self.error = OSError(errno.ENOSPC, "No space left on device")
        raise self.error

    config = config_with(flush_s=0.05)
    health = Health(config, Keys.from_config(config.zenoh), None, "numbered")
    recorder = vehicle_recorder(config, "numbered", tmp_path, None, health.state_json)
    health.problem_checks.append(recorder.problem)
    assert health.state_message().problems == []
    monkeypatch.setattr(TrackedFile, "write", full)
    with recorder:
        for record, frame in RECORDS[:30]:
            health.on_record(record, frame)
            recorder.on_record(record, frame)  # never raises on the vehicle
            time.sleep(0.01)
    state = health.state_message()
    assert state.status == "degraded"
    assert any(
        p.startswith("recording stopped: cannot write MCAP")
        and p.endswith("No space left on device")
        for p in state.problems
    )
