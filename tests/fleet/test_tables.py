"""Parquet tables: schemas derived from the typed record, atomic writes, the drive recorder."""

from __future__ import annotations

from dataclasses import replace
from datetime import UTC, datetime
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from fakes import record_of
from roadgaze.config import MonitorConfig
from roadgaze.fleet.drives import Drive
from roadgaze.fleet.recorder import DriveRecorder
from roadgaze.fleet.tables import (
    AtomicParquetWriter,
    alerts_schema,
    frames_schema,
    read_drive_metadata,
    remove_temporary_files,
    temporary_path,
)
from roadgaze.monitor import initial_state, verdict_of
from roadgaze.outputs import records
from roadgaze.outputs.records import RECORD_FIELDS, FieldType
from roadgaze.types import Alert, AlertKind, AlertLevel, Gaze, PoseSample

CONSTANT = {"drive_id": "d1", "driver_id": "alice", "vehicle_id": None, "start_time": None}


def test_the_frames_schema_is_the_drive_metadata_then_every_record_field() -> None:
    schema = frames_schema()
    assert schema.names == ["drive_id", "driver_id", "vehicle_id", "start_time", *RECORD_FIELDS]
    assert schema.field("frame").type == pa.int64()
    assert schema.field("face").type == pa.bool_()
    assert schema.field("yaw_deg").type == pa.float64()
    assert schema.field("alerts").type == pa.list_(pa.string())
    assert schema.field("start_time").type == pa.timestamp("us", tz="UTC")


def test_a_field_added_to_the_typed_record_appears_in_parquet(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    extended = (*records.RECORD_SCHEMA, ("eyes_closed_s", FieldType.FLOAT))
    monkeypatch.setattr(records, "RECORD_SCHEMA", extended)
    path = tmp_path / "frames.parquet"
    with AtomicParquetWriter(path, frames_schema(), CONSTANT) as writer:
        writer.append({"t_s": 0.0, "frame": 0, "eyes_closed_s": 0.5})
        writer.commit({})
    table = pq.read_table(path)
    assert table.schema.field("eyes_closed_s").type == pa.float64()
    assert table.column("eyes_closed_s").to_pylist() == [0.5]


def test_the_hands_with_their_landmarks_go_to_parquet_as_a_list_of_structs(
    tmp_path: Path,
) -> None:
    import numpy as np

    from roadgaze.types import Hand, HandSide, PhoneJudgement

    landmarks = np.column_stack((np.arange(21.0) + 0.04, np.full(21, 7.26), np.zeros(21)))
    hand = Hand(HandSide.LEFT, 0.8, 0.9, landmarks.astype(np.float32), (0.0, 7.0, 20.0, 8.0))
    phone = PhoneJudgement(False, 0.1)
    found = PoseSample(0.0, 0, False, None, None, None, None, None, 0, hands=(hand,), phone=phone)
    path = tmp_path / "frames.parquet"
    with AtomicParquetWriter(path, frames_schema(), CONSTANT) as writer:
        writer.append(records.record_fields(record_of(found)))
        writer.append(records.record_fields(record_of(replace(found, hands=None, phone=None))))
        writer.commit({})
    [with_hand, stage_off] = pq.read_table(path).column("hands").to_pylist()
    assert stage_off is None
    [row] = with_hand
    assert (row["side"], row["side_score"], row["score"]) == ("left", 0.8, 0.9)
    assert row["landmarks_px"][1] == [1.0, 7.3, 0.0] and len(row["landmarks_px"]) == 21


def test_alerts_schema_has_every_alert_field_and_the_frame() -> None:
    names = alerts_schema().names
    assert names[:5] == ["drive_id", "driver_id", "vehicle_id", "start_time", "frame"]
    assert names[5:] == [name for name, _ in records.ALERT_SCHEMA]


def test_commit_writes_rows_in_batches_with_metadata_and_renames(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("roadgaze.fleet.tables.ROWS_PER_BATCH", 3)
    path = tmp_path / "frames" / "d1.parquet"
    start = datetime(2024, 5, 1, 6, 30, tzinfo=UTC)
    with AtomicParquetWriter(path, frames_schema(), {**CONSTANT, "start_time": start}) as writer:
        for index in range(7):
            writer.append({"t_s": index / 10, "frame": index, "alerts": ["vats:warning"]})
        assert not path.exists()
        assert temporary_path(path).exists()
        writer.commit({"fingerprint": {"size": 3}})
    table = pq.read_table(path)
    assert table.column("frame").to_pylist() == list(range(7))
    assert set(table.column("driver_id").to_pylist()) == {"alice"}
    assert table.column("start_time").to_pylist()[0] == start
    assert table.column("yaw_deg").null_count == 7
    assert pq.ParquetFile(path).metadata.num_row_groups == 3
    assert read_drive_metadata(path) == {"fingerprint": {"size": 3}}
    assert list(path.parent.iterdir()) == [path]


def test_a_writer_left_without_commit_leaves_the_old_file_and_no_temporary(tmp_path: Path) -> None:
    path = tmp_path / "d1.parquet"
    path.write_bytes(b"old")
    with AtomicParquetWriter(path, frames_schema(), CONSTANT) as writer:
        writer.append({"t_s": 0.0, "frame": 0})
    assert path.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d1.parquet"]
    assert read_drive_metadata(path) is None
    assert read_drive_metadata(tmp_path / "missing.parquet") is None


def test_leftover_temporary_files_are_removed(tmp_path: Path) -> None:
    (tmp_path / ".d1.parquet.123.tmp").write_bytes(b"half")
    (tmp_path / "d2.parquet").write_bytes(b"kept")
    assert remove_temporary_files(tmp_path) == 1
    assert [p.name for p in tmp_path.iterdir()] == ["d2.parquet"]


def sample(t_s: float, frame: int, face: bool = True) -> PoseSample:
    yaw = 40.0 if face else None
    return PoseSample(t_s, frame, face, yaw, yaw, 0.0, 1.0, None, int(face))


def test_the_recorder_counts_an_escalated_alert_once(tmp_path: Path) -> None:
    base = verdict_of(MonitorConfig(), initial_state(MonitorConfig()))
    unknown = replace(base, gaze=Gaze.UNKNOWN, on_road=None)
    off = replace(base, gaze=Gaze.OFF_ROAD, on_road=False)
    warning = Alert(AlertKind.LONG_DISTRACTION, AlertLevel.WARNING, 0.2, 40.0, 3.0, 3.0)
    critical = replace(warning, level=AlertLevel.CRITICAL, t_s=0.3, off_road_s=6.0)
    vats = Alert(AlertKind.VATS, AlertLevel.WARNING, 0.3, 40.0, 6.0, 10.0)
    cleared = Alert(AlertKind.CLEARED, AlertLevel.INFO, 0.4, 0.0, 6.5, 10.0)
    active = (AlertKind.LONG_DISTRACTION,)
    frames = [
        record_of(sample(0.1, 0, face=False), unknown),
        record_of(sample(0.2, 1), replace(off, off_road_s=3.0, active=active), (warning,)),
        record_of(
            sample(0.3, 2),
            replace(off, off_road_s=6.0, active=(*active, AlertKind.VATS)),
            (critical, vats),
        ),
        record_of(
            sample(0.4, 3),
            replace(base, gaze=Gaze.ON_ROAD, on_road=True, neutral_yaw_deg=1.5),
            (cleared,),
        ),
    ]
    with (
        AtomicParquetWriter(tmp_path / "f.parquet", frames_schema(), CONSTANT) as frame_writer,
        AtomicParquetWriter(tmp_path / "a.parquet", alerts_schema(), CONSTANT) as alert_writer,
    ):
        recorder = DriveRecorder(frame_writer, alert_writer)
        for record in frames:
            recorder.on_record(record, None)  # type: ignore[arg-type]
        result = recorder.result(Drive("d1", tmp_path / "x.mp4"), 0.1, None, 50.0, 0.2)
        assert alert_writer.rows == 4
    eye_kinds = ("microsleep", "sleep", "drowsy", "unresponsive", "degraded")
    eye_kinds += ("temporary_failure", "permanent_failure")  # alert/3's failure kinds
    eye_kinds += ("phone_use", "non_functional")  # alert/4
    assert dict(result.alert_counts) == {
        "long_distraction": 1,
        "vats": 1,
        "driver_unavailable": 0,
    } | dict.fromkeys(eye_kinds, 0)
    assert result.critical_alerts == 1
    assert (result.frames, result.frames_with_face) == (4, 3)
    assert result.duration_s == pytest.approx(0.4)
    assert result.longest_off_road_s == 6.0
    assert result.neutral_yaw_deg == 1.5
    assert result.off_road_ratio == pytest.approx(2 / 3)  # two off road of three with gaze known


def test_a_missing_video_is_a_failed_drive_with_one_line(tmp_path: Path) -> None:
    from roadgaze.config import Config
    from roadgaze.fleet import DriveTask, process_drive

    result = process_drive(DriveTask(Drive("gone", tmp_path / "gone.mp4"), tmp_path, Config()))
    assert (result.status, result.error) == ("failed", f"video file {tmp_path}/gone.mp4 not found")
    assert not (tmp_path / "frames").exists()


def test_fingerprints_match_on_size_and_mtime_or_on_the_content_hash() -> None:
    from roadgaze.fleet.task import fingerprints_match

    def print_of(size: int = 10, mtime_ns: int = 1, sha256: str | None = None) -> dict[str, object]:
        source: dict[str, object] = {"size": size, "mtime_ns": mtime_ns}
        if sha256 is not None:
            source["sha256"] = sha256
        return {"input": source, "version": "0.1.0", "config": "c", "drive": [None, None, None]}

    assert fingerprints_match(print_of(), print_of(), content_hash=False)
    assert not fingerprints_match(print_of(mtime_ns=2), print_of(), content_hash=False)
    assert not fingerprints_match(print_of(size=11), print_of(), content_hash=False)
    copied = print_of(mtime_ns=2, sha256="ab")  # a copy: new mtime, same content
    assert fingerprints_match(copied, print_of(sha256="ab"), content_hash=True)
    assert not fingerprints_match(copied, print_of(sha256="cd"), content_hash=True)
    assert not fingerprints_match(print_of(), print_of(sha256="ab"), content_hash=True)
    assert not fingerprints_match({**print_of(), "config": "d"}, print_of(), content_hash=False)
    assert not fingerprints_match(None, print_of(), content_hash=False)


def test_columns_known_only_at_the_end_are_filled_row_group_by_row_group(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("roadgaze.fleet.tables.ROWS_PER_BATCH", 3)
    path = tmp_path / "d1.parquet"
    with AtomicParquetWriter(path, frames_schema(), CONSTANT) as writer:
        for index in range(7):
            writer.append({"t_s": index / 10, "frame": index, "yaw_raw_deg": 2.0 * index})
        offline = [None, *(0.5 * index for index in range(1, 7))]
        writer.commit({"fingerprint": {"size": 7}}, {"yaw_offline_deg": offline})
    table = pq.read_table(path)
    assert table.column("yaw_offline_deg").to_pylist() == offline
    assert table.column("yaw_raw_deg").to_pylist() == [2.0 * index for index in range(7)]
    assert table.schema.remove_metadata().equals(frames_schema())
    assert pq.ParquetFile(path).metadata.num_row_groups == 3
    assert read_drive_metadata(path) == {"fingerprint": {"size": 7}}
    assert [p.name for p in tmp_path.iterdir()] == ["d1.parquet"]
