"""A local batch over synthetic drives, an empty and a corrupt file, checked against single
`roadgaze replay` runs frame by frame; resume by fingerprint; the command's exit status."""

from __future__ import annotations

import json
import os
import shutil
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest

from roadgaze.cli import main
from roadgaze.config import Config, load_config
from roadgaze.fleet import Drive, DriveTask, find_done, output_paths
from roadgaze.fleet.batch import LOCK_NAME, batch_lock
from roadgaze.outputs import RECORD_FIELDS

pytestmark = pytest.mark.slow


def replay(video: Path, out: Path) -> list[dict[str, Any]]:
    assert main(["replay", str(video), "--out", str(out), "--no-progress"]) == 0
    return [json.loads(line) for line in out.read_text().splitlines()]


def test_every_drive_matches_a_single_replay_frame_by_frame(
    local_batch: Any, tmp_path: Path
) -> None:
    for drive_id, video in local_batch.input.videos.items():
        expected = replay(video, tmp_path / f"{drive_id}.jsonl")
        frames_path, alerts_path = output_paths(local_batch.out_dir, drive_id)
        frames = pq.read_table(frames_path).to_pylist()
        assert len(frames) == len(expected) > 20
        for got, want in zip(frames, expected, strict=True):
            assert {name: got[name] for name in RECORD_FIELDS} == want
            assert (got["drive_id"], got["driver_id"], got["start_time"]) == (drive_id, None, None)
        alerts = pq.read_table(alerts_path).to_pylist()
        labels = [(a["frame"], f"{a['kind']}:{a['level']}") for a in alerts]
        assert labels == [(r["frame"], label) for r in expected for label in r["alerts"]]
        for alert in alerts:
            record = expected[alert["frame"]]
            assert alert["t_s"] == record["t_s"]
    glance = pq.read_table(output_paths(local_batch.out_dir, "glance")[1]).to_pylist()
    assert [a["kind"] for a in glance] == ["long_distraction", "cleared"]
    assert glance[1]["clears"] == ["long_distraction"]


def test_bad_files_are_recorded_with_their_error_and_do_not_stop_the_batch(
    local_batch: Any,
) -> None:
    outcome = local_batch.outcome
    status = {r.drive_id: (r.status, r.error) for r in outcome.results}
    assert status["empty"] == (
        "failed",
        f"video {local_batch.input.folder / 'empty.mp4'} is empty (0 bytes)",
    )
    assert status["corrupt"][0] == "failed" and "cannot read video" in status["corrupt"][1]
    assert {k for k, (s, _) in status.items() if s == "ok"} == set(local_batch.input.videos)
    assert not outcome.interrupted
    assert not any(output_paths(local_batch.out_dir, "corrupt")[0].parent.glob("corrupt*"))
    rows = {
        r["drive_id"]: r for r in pq.read_table(local_batch.out_dir / "summary.parquet").to_pylist()
    }
    assert rows["corrupt"]["status"] == "failed" and rows["corrupt"]["frames"] is None
    report = (local_batch.out_dir / "report.html").read_text()
    assert "is empty (0 bytes)" in report and "glance" in report
    assert list(local_batch.out_dir.rglob(".*")) == []  # the lock file too


def test_summary_figures_agree_with_the_frames(local_batch: Any) -> None:
    rows = pq.read_table(local_batch.out_dir / "summary.parquet").to_pylist()
    for row in rows:
        if row["status"] != "ok":
            continue
        frames = pq.read_table(output_paths(local_batch.out_dir, row["drive_id"])[0]).to_pylist()
        assert row["frames"] == len(frames)
        assert row["face_found_rate"] == round(sum(f["face"] for f in frames) / len(frames), 4)
        known = [f for f in frames if f["gaze"] != "unknown"]
        off = sum(f["gaze"] == "off_road" for f in known)
        assert row["off_road_ratio"] == round(off / len(known), 4)
        assert row["longest_off_road_s"] == max(f["off_road_s"] for f in frames)
        assert row["neutral_yaw_deg"] == frames[-1]["neutral_yaw_deg"]
        assert row["duration_s"] == pytest.approx(
            frames[-1]["t_s"] - frames[0]["t_s"] + 1 / 15, abs=1e-3
        )
        assert row["processing_fps"] > 0 and 0 < row["startup_s"] < row["wall_s"]
    glance = next(r for r in rows if r["drive_id"] == "glance")
    assert glance["alerts_long_distraction"] == 1
    assert glance["long_distraction_per_h"] == pytest.approx(3600 / glance["duration_s"], rel=1e-3)
    assert 3.0 <= glance["longest_off_road_s"] <= 5.0


def task_of(
    local_batch: Any, drive_id: str, config: Config | None = None, **values: Any
) -> DriveTask:
    drive = Drive(drive_id, local_batch.input.videos[drive_id])
    return DriveTask(drive, local_batch.out_dir, config or Config(), **values)


def test_a_drive_is_done_only_while_its_input_config_and_metadata_are_unchanged(
    local_batch: Any,
) -> None:
    done = find_done(task_of(local_batch, "right"))
    assert done is not None and done.resumed and done.status == "ok"
    other = load_config(overrides={"monitor.long_distraction_s": "2.5"})
    assert find_done(task_of(local_batch, "right", other)) is None
    assert find_done(task_of(local_batch, "right", content_hash=True)) is None  # no hash stored
    assert find_done(task_of(local_batch, "right", version="0.0.1")) is None
    moved = DriveTask(
        Drive("right", local_batch.input.videos["right"], driver_id="alice"),
        local_batch.out_dir,
        Config(),
    )
    assert find_done(moved) is None
    video = local_batch.input.videos["right"]
    stat = video.stat()
    try:
        os.utime(video, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1))
        assert find_done(task_of(local_batch, "right")) is None
    finally:
        os.utime(video, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert find_done(task_of(local_batch, "right")) is not None


def test_a_rerun_keeps_finished_drives_retries_failed_ones_and_exits_3(
    local_batch: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    shutil.copytree(local_batch.out_dir, out)
    frames = sorted((out / "frames").iterdir())
    before = [p.stat().st_mtime_ns for p in frames]
    capsys.readouterr()
    code = main(
        ["batch", str(local_batch.input.folder), "--out", str(out), "--json", "--no-progress"]
    )
    captured = capsys.readouterr()
    assert code == 3
    figures = json.loads(captured.out)
    assert (figures["resumed"], figures["processed"], figures["failed"]) == (3, 0, 2)
    assert [p.stat().st_mtime_ns for p in frames] == before
    assert "failed corrupt (" in captured.err and "failed empty (" in captured.err
    assert "Traceback" not in captured.err
    wrote = [
        line.split(": wrote ", 1)[1] for line in captured.err.splitlines() if ": wrote " in line
    ]
    assert wrote == [str(out / "summary.parquet"), str(out / "report.html")]  # the log's lines
    rows = pq.read_table(out / "summary.parquet").to_pylist()
    assert sum(r["resumed"] for r in rows) == 3


def test_a_manifest_drive_exits_0_with_its_metadata_in_every_table(
    local_batch: Any, tmp_path: Path
) -> None:
    manifest = tmp_path / "drives.csv"
    video = local_batch.input.videos["trip__road"]
    manifest.write_text(
        f"path,drive_id,driver_id,vehicle_id,start_time\n{video},d-7,alice,car-1,2024-05-01T10:00+02:00\n",
        encoding="utf-8",
    )
    out = tmp_path / "out"
    assert main(["batch", str(manifest), "--out", str(out), "--no-progress", "--workers", "1"]) == 0
    (row,) = pq.read_table(out / "summary.parquet").to_pylist()
    assert (row["drive_id"], row["driver_id"], row["vehicle_id"]) == ("d-7", "alice", "car-1")
    assert row["status"] == "ok" and row["start_time"] == datetime(2024, 5, 1, 8, 0, tzinfo=UTC)
    frames = pq.read_table(output_paths(out, "d-7")[0])
    assert set(frames.column("driver_id").to_pylist()) == {"alice"}
    assert set(frames.column("start_time").to_pylist()) == {row["start_time"]}
    expected = pq.read_table(output_paths(local_batch.out_dir, "trip__road")[0])
    assert frames.select(list(RECORD_FIELDS)).equals(expected.select(list(RECORD_FIELDS)))
    assert "alice" in (out / "report.html").read_text()


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["--workers", "0"], "--workers must be at least 1"),
        (["--retries", "-1"], "--retries must be 0 or more"),
        (["--ray-address", "auto"], "--ray-address needs --engine ray"),
    ],
)
def test_bad_options_are_one_line_and_exit_2(
    local_batch: Any,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    arguments: list[str],
    message: str,
) -> None:
    code = main(["batch", str(local_batch.input.folder), "--out", str(tmp_path), *arguments])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1


def test_a_missing_ray_says_how_to_install_it(
    local_batch: Any,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)
    code = main(["batch", str(local_batch.input.folder), "--out", str(tmp_path), "--engine", "ray"])
    err = capsys.readouterr().err
    assert code == 2 and "pip install 'roadgaze[ray]'" in err and len(err.strip().splitlines()) == 1


def test_a_missing_pyarrow_says_how_to_install_it_before_any_work(
    local_batch: Any,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """pyarrow is the `fleet` extra: a daemon-only install answers `batch` with one line."""
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    out = tmp_path / "out"
    code = main(["batch", str(local_batch.input.folder), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "pip install 'roadgaze[fleet]'" in err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


def test_a_folder_held_by_another_batch_is_refused(
    local_batch: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with batch_lock(tmp_path):
        code = main(["batch", str(local_batch.input.folder), "--out", str(tmp_path)])
    assert code == 2 and "another roadgaze batch is writing to" in capsys.readouterr().err


def test_the_lock_file_goes_with_the_batch_and_a_stale_one_is_taken_over(tmp_path: Path) -> None:
    stale = tmp_path / LOCK_NAME
    stale.write_text("")  # what a kill -9 leaves
    with batch_lock(tmp_path):
        assert stale.exists()
    assert not stale.exists()


def test_a_batch_that_locked_a_removed_lock_file_takes_a_fresh_one(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The race of removing a lock file: B opened it, A removed it and left, B then locks the
    removed file; B must notice and lock the path's file, or a third batch could run beside it."""
    import roadgaze.fleet.batch as batch_module

    real_flock = batch_module.fcntl.flock
    calls = []

    def flock_after_removal(descriptor: int, operation: int) -> None:
        calls.append(descriptor)
        if len(calls) == 1:
            (tmp_path / LOCK_NAME).unlink()  # A removes the file between B's open and lock
        real_flock(descriptor, operation)

    monkeypatch.setattr(batch_module.fcntl, "flock", flock_after_removal)
    with batch_lock(tmp_path):
        held = os.fstat(calls[-1])
        named = (tmp_path / LOCK_NAME).stat()
        assert len(calls) == 2 and (held.st_ino, held.st_dev) == (named.st_ino, named.st_dev)
