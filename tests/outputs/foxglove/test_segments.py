"""`run --record DIR`'s segments: rotated by size and by age, every closed one complete and
readable, the folder kept under its bound by removing the oldest first (logged), a part a
killed run left recovered when the folder is opened again, and a live run's segments never
taken over by another run (the prefix lock)."""

from __future__ import annotations

import logging
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from foxglove_helpers import pipeline_records, read_mcap
from repo_paths import child_env
from roadgaze.config import Config, RecordConfig, load_config
from roadgaze.errors import ConfigError
from roadgaze.outputs.foxglove.channels import TOPIC_RECORD
from roadgaze.outputs.foxglove.open import vehicle_recorder
from roadgaze.outputs.foxglove.recorder import FoxgloveRecorder
from roadgaze.outputs.foxglove.targets import MB, McapSegments

RECORDS = pipeline_records()
PREFIX = "roadgaze-car-0"


def record_slowly(folder: Path, record: RecordConfig, frame_s: float = 0.004) -> McapSegments:
    """Every record (and camera frame, when on) into segments in `folder`, `frame_s` apart in
    wall time; the vehicle's recorder, except that camera frames wait instead of dropping."""
    config = Config(record=record)
    segments = McapSegments(folder, record, bool(record.images), PREFIX)
    recorder = FoxgloveRecorder(
        [segments],
        config,
        images=bool(record.images),
        source="numbered",
        wall_clock_stamps=True,
        block_on_images=True,
    )
    with recorder:
        for sample, frame in RECORDS:
            recorder.on_record(sample, frame)
            time.sleep(frame_s)
    (segments,) = recorder.targets
    assert isinstance(segments, McapSegments)
    return segments


def frames_in(path: Path) -> list[int]:
    return [record["frame"] for record in read_mcap(path).json(TOPIC_RECORD)]


def test_segments_rotate_by_size_and_each_closed_one_is_complete(tmp_path: Path) -> None:
    settings = RecordConfig(
        segment_mb=0.1, max_disk_mb=100.0, flush_s=0.05, image_fps=30.0, images=True
    )
    segments = record_slowly(tmp_path, settings)
    closed = sorted(tmp_path.glob(f"{PREFIX}-*.mcap"))
    assert closed == segments.closed and len(closed) >= 3
    assert not list(tmp_path.glob("*.part"))
    frames = [frames_in(path) for path in closed]
    assert [frame for part in frames for frame in part] == list(range(len(RECORDS)))
    # Rotated before the next flush interval would take a segment over its size (within the
    # slack of the summary: the schemas and indexes written at the close).
    sizes = [path.stat().st_size for path in closed[:-1]]
    assert max(sizes) < 1.5 * settings.segment_mb * MB
    metadata = [read_mcap(path).metadata["roadgaze"] for path in closed]
    assert [int(entry["segment"]) for entry in metadata] == list(range(1, len(closed) + 1))
    assert len({entry["time_offset_ns"] for entry in metadata}) == 1


def test_segments_rotate_by_age(tmp_path: Path) -> None:
    settings = RecordConfig(segment_s=0.25, flush_s=0.05, images=False)
    segments = record_slowly(tmp_path, settings)  # 210 frames over about a second
    assert 3 <= len(segments.closed) <= 10
    assert [f for path in segments.closed for f in frames_in(path)] == list(range(len(RECORDS)))


def test_the_oldest_segments_are_removed_to_keep_the_folder_under_its_bound(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    settings = RecordConfig(
        segment_mb=0.06, max_disk_mb=0.15, flush_s=0.05, image_fps=30.0, images=True
    )
    stranger = tmp_path / "notes.mcap"
    stranger.write_bytes(b"not ours" * 10_000)
    with caplog.at_level(logging.WARNING, logger="roadgaze"):
        segments = record_slowly(tmp_path, settings)
    kept = segments.segments_on_disk()
    assert segments.removed and all(not path.exists() for path in segments.removed)
    assert segments.removed == segments.closed[: len(segments.removed)]  # oldest first
    assert kept == segments.closed[len(segments.removed) :]
    used = sum(path.stat().st_size for path in kept)
    assert used <= settings.max_disk_mb * MB
    assert stranger.exists()  # other files are never touched
    removed = [
        r.getMessage() for r in caplog.records if "removed the oldest segment" in r.getMessage()
    ]
    assert len(removed) == len(segments.removed)
    assert segments.removed[0].name in removed[0]
    kept_frames = [f for path in kept for f in frames_in(path)]
    assert kept_frames == list(range(kept_frames[0], len(RECORDS)))


def test_a_part_left_open_is_recovered_when_the_folder_is_opened(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    first = tmp_path / "first"
    segments = record_slowly(first, RecordConfig(flush_s=0.05, images=False))
    (complete,) = segments.closed
    data = complete.read_bytes()
    part = tmp_path / "again" / f"{PREFIX}-20260101T000000Z-0001.mcap.part"
    part.parent.mkdir()
    part.write_bytes(data[: len(data) * 2 // 3])  # cut inside the data, as a kill would
    with caplog.at_level(logging.WARNING, logger="roadgaze"):
        record_slowly(part.parent, RecordConfig(flush_s=0.05, images=False), frame_s=0.0)
    recovered = part.with_name(part.name.removesuffix(".part"))
    assert not part.exists() and recovered.exists()
    frames = frames_in(recovered)
    assert frames == list(range(len(frames))) and 0 < len(frames) < len(RECORDS)
    assert any(
        "recovered" in r.getMessage() and part.name in r.getMessage() for r in caplog.records
    )


def test_a_folder_that_cannot_be_made_is_one_line(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(Exception, match=r"^cannot record into .*file/sub: Not a directory$"):
        vehicle_recorder(Config(), "numbered", blocker / "sub", None)


def test_the_disk_bound_must_hold_two_segments() -> None:
    with pytest.raises(ConfigError, match=r"record\.max_disk_mb \(300\) must be at least 2 x"):
        load_config(overrides={"record.segment_mb": "256", "record.max_disk_mb": "300"}, environ={})


def test_copying_a_closed_segment_elsewhere_keeps_it_readable(tmp_path: Path) -> None:
    segments = record_slowly(tmp_path / "run", RecordConfig(flush_s=0.05, images=False))
    copy = tmp_path / "copy.mcap"
    shutil.copy(segments.closed[0], copy)
    assert frames_in(copy) == list(range(len(RECORDS)))


def test_a_second_run_with_the_same_vehicle_id_never_takes_over_the_first_ones_segment(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """Issue 34: a second `run --record` with the same vehicle id took the first one's open
    segment for one 'left open by an interrupted run': the first recording stopped with an
    error and the rest of its drive was never recorded. The second records as PREFIX.2 now."""
    settings = RecordConfig(flush_s=0.05, images=False)
    first = McapSegments(tmp_path, settings, False, PREFIX)
    recorder = FoxgloveRecorder(
        [first], Config(record=settings), images=False, source="first", wall_clock_stamps=True
    )
    with recorder:
        for sample, frame in RECORDS[:100]:
            recorder.on_record(sample, frame)
        time.sleep(0.2)  # flushed: a part with complete chunks, as a live run's is
        with caplog.at_level(logging.WARNING, logger="roadgaze"):
            second = record_slowly(tmp_path, settings, frame_s=0.0)
        for sample, frame in RECORDS[100:]:
            recorder.on_record(sample, frame)
    assert recorder.failure is None
    (own,) = first.closed
    assert frames_in(own) == list(range(len(RECORDS)))  # every frame of the first drive
    (other,) = second.closed
    assert second.prefix == f"{PREFIX}.2" and other.name.startswith(f"{PREFIX}.2-")
    assert frames_in(other) == list(range(len(RECORDS)))
    said = [r.getMessage() for r in caplog.records]
    assert not any("recovered" in line for line in said)
    assert any(f"another run (pid {os.getpid()}) is recording {PREFIX}'s" in line for line in said)
    assert first.segments_on_disk() == [own]  # each run's own segments only


def test_a_run_in_another_process_holds_its_prefix_until_it_ends(tmp_path: Path) -> None:
    from roadgaze.outputs.foxglove.segment_lock import claim_prefix, recording_pid

    holder = subprocess.Popen(
        [sys.executable, "-c",
         "import sys, pathlib; from roadgaze.outputs.foxglove.segment_lock import claim_prefix;"
         f"lock = claim_prefix(pathlib.Path({str(tmp_path)!r}), {PREFIX!r}); print('held', "
         "flush=True); sys.stdin.readline()"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=child_env(),
    )  # fmt: skip
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "held\n"
        part = tmp_path / f"{PREFIX}-20260101T000000Z-0001.mcap.part"
        assert recording_pid(part) == holder.pid
        lock, name = claim_prefix(tmp_path, PREFIX)
        assert name == f"{PREFIX}.2"
        lock.release()
    finally:
        holder.kill()  # however a run ends, its lock goes with it
        holder.wait(timeout=10)
    assert recording_pid(part) is None
    lock, name = claim_prefix(tmp_path, PREFIX)
    assert name == PREFIX
    lock.release()


def test_another_vehicles_segments_are_never_taken_for_this_ones(tmp_path: Path) -> None:
    """`roadgaze-car-*` also named car-0's files: vehicle `car` would recover car-0's open
    segment and remove its closed ones to make room."""
    longer = tmp_path / "roadgaze-car-0-20260101T000000Z-0001.mcap"
    longer.write_bytes(b"car-0's" * 10_000)
    longer_part = tmp_path / "roadgaze-car-0-20260101T000000Z-0002.mcap.part"
    longer_part.write_bytes(b"car-0's open segment")
    settings = RecordConfig(
        segment_mb=0.06, max_disk_mb=0.15, flush_s=0.05, image_fps=30.0, images=True
    )
    config = Config(record=settings)
    segments = McapSegments(tmp_path, settings, True, "roadgaze-car")
    with FoxgloveRecorder(
        [segments], config, images=True, source="car", wall_clock_stamps=True,
        block_on_images=True,
    ) as recorder:  # fmt: skip
        for sample, frame in RECORDS:
            recorder.on_record(sample, frame)
            time.sleep(0.004)
    assert segments.removed  # it did make room, from its own segments only
    assert longer.exists() and longer_part.read_bytes() == b"car-0's open segment"
