"""Stopping and killing a batch: SIGTERM stops cleanly (exit 130), SIGKILL leaves no half file
under a real name, and the next run keeps the finished drives and does the rest. Also a worker
process that dies on a drive: the drive fails after its retries, the batch goes on."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest

from fakes import die_on_crash_drives
from repo_paths import child_env
from roadgaze.config import Config
from roadgaze.fleet import Drive, DriveTask, LocalEngine
from roadgaze.service.signals import StopFlag

pytestmark = pytest.mark.slow

DRIVES = 4


def start_batch(folder: Path, out: Path) -> subprocess.Popen[str]:
    command = [sys.executable, "-m", "roadgaze", "batch", str(folder), "--out", str(out)]
    return subprocess.Popen(
        [*command, "--workers", "1", "--no-progress", "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=child_env(),
        start_new_session=True,
    )


def finished(out: Path) -> list[Path]:
    folder = out / "frames"
    return sorted(folder.glob("[!.]*.parquet")) if folder.is_dir() else []


def wait_until(condition: Callable[[], bool], process: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + 180.0
    while not condition():
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "batch made no progress in 180 s"
        time.sleep(0.05)


def assert_complete(out: Path, frames: int) -> None:
    """Every file under a real name is a whole Parquet file with every frame."""
    for path in finished(out):
        assert pq.read_table(path).num_rows == frames
        assert pq.read_metadata(out / "alerts" / path.name).num_rows >= 0


def test_stop_kill_and_resume(synthetic_clip: Any, tmp_path: Path) -> None:
    clip, truth = synthetic_clip("0:1,30:1")
    folder = tmp_path / "drives"
    folder.mkdir()
    for index in range(DRIVES):
        shutil.copy(clip, folder / f"drive{index}.mkv")
    out = tmp_path / "out"

    stopped = start_batch(folder, out)
    wait_until(lambda: len(finished(out)) >= 1, stopped)
    stopped.send_signal(signal.SIGTERM)
    _, err = stopped.communicate(timeout=120)
    assert stopped.returncode == 130, err
    assert "run the same command again to continue" in err and "Traceback" not in err
    assert list(out.rglob(".*")) == []  # the lock file too
    done_first = len(finished(out))
    assert 1 <= done_first < DRIVES
    assert_complete(out, len(truth))
    statuses = [r["status"] for r in pq.read_table(out / "summary.parquet").to_pylist()]
    assert statuses.count("ok") == done_first
    assert set(statuses) <= {"ok", "interrupted", "pending"}

    killed = start_batch(folder, out)
    wait_until(lambda: len(finished(out)) > done_first, killed)
    with contextlib.suppress(ProcessLookupError):  # it may have finished meanwhile
        os.killpg(killed.pid, signal.SIGKILL)
    killed.communicate(timeout=60)
    done_second = len(finished(out))
    assert_complete(out, len(truth))

    resumed = start_batch(folder, out)
    stdout, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err
    figures = json.loads(stdout)
    assert figures["resumed"] == done_second
    assert figures["processed"] == DRIVES - done_second
    assert len(finished(out)) == DRIVES
    assert_complete(out, len(truth))
    assert list(out.rglob(".*")) == []  # the lock file too


def test_a_worker_that_dies_fails_its_drive_after_the_retries_and_the_batch_goes_on(
    tmp_path: Path,
) -> None:
    names = ["ok1", "crash", "ok2"]
    tasks = [DriveTask(Drive(name, tmp_path / f"{name}.mp4"), tmp_path, Config()) for name in names]
    engine = LocalEngine(tmp_path / "batch.log", workers=1, retries=1, function=die_on_crash_drives)
    with engine:
        results = {r.drive_id: r for r in engine.run(tasks, StopFlag())}
    assert (results["ok1"].status, results["ok2"].status) == ("ok", "ok")
    assert results["crash"].status == "failed"
    assert "worker process died 2 times" in (results["crash"].error or "")
    # Each death is said on stderr and in batch.log, and counted for the summary.
    assert (engine.worker_deaths, engine.retried) == (2, 1)
    batch_log = (tmp_path / "batch.log").read_text()
    assert batch_log.count("a worker process died while running drive crash") == 2
    assert "try 1 of 2" in batch_log and "giving up on it (--retries)" in batch_log
