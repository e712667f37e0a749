"""`replay` and `batch` gate alerts with a recorded drive's speed: a track beside the video, a
named track or a constant; a bad track ends in one line."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from roadgaze.cli import main

pytestmark = pytest.mark.usefixtures("restore_logging")

LAP_LOOK = "0:1.5,0/-35:4,0:1.5"
"""Into the lap for 4 s: a long distraction when moving."""


@pytest.fixture(scope="module")
def drive(tmp_path_factory: pytest.TempPathFactory, synthetic_clip: Callable[..., Any]) -> Path:
    """The look as `drive.mkv` in a folder of its own, with a 10 km/h track beside it."""
    clip, _ = synthetic_clip(LAP_LOOK)
    folder = tmp_path_factory.mktemp("speed-drive")
    video = folder / "drive.mkv"
    shutil.copy(clip, video)
    rows = "".join(f"{0.5 * i:g},10\n" for i in range(18))
    (folder / "drive.speed.csv").write_text("t_s,kmh\n" + rows, encoding="utf-8")
    return video


def alerts_of(path: Path) -> list[str]:
    lines = path.read_text(encoding="utf-8").splitlines()
    return [label for line in lines for label in json.loads(line)["alerts"]]


@pytest.mark.slow
def test_replay_takes_the_track_beside_the_video_or_a_constant(
    drive: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "slow.jsonl"
    assert main(["replay", str(drive), "--out", str(out), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert f"vehicle speed from {drive.with_name('drive.speed.csv')} (18 samples" in err
    assert alerts_of(out) == []  # 10 km/h: below the 20 km/h of every band
    fast = tmp_path / "fast.jsonl"
    args = ["replay", str(drive), "--out", str(fast), "--no-progress", "--speed-kmh", "70"]
    assert main(args) == 0
    assert "vehicle speed from constant 70 km/h" in capsys.readouterr().err
    assert "long_distraction:warning" in alerts_of(fast)


def test_a_bad_track_is_one_line(
    drive: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,kmh\n0,12\n0,13\n", encoding="utf-8")
    args = ["replay", str(drive), "--no-progress", "--speed-track", str(bad)]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "line 3: t_s 0 is not after the previous 0" in err
    assert main(["replay", str(drive), "--speed-track", str(bad), "--speed-kmh", "3"]) == 2
    assert "not both" in capsys.readouterr().err
    assert main(["batch", str(drive.parent), "--out", str(tmp_path), "--speed-kmh", "-1"]) == 2
    assert "within 0-400" in capsys.readouterr().err


@pytest.mark.slow
def test_batch_drive_uses_its_manifest_track(drive: Path, tmp_path: Path) -> None:
    pytest.importorskip("pyarrow")
    from roadgaze.config import Config
    from roadgaze.fleet import discover_drives
    from roadgaze.fleet.task import DriveTask, process_drive

    fast = tmp_path / "fast.speed.csv"
    fast.write_text("t_s,kmh\n" + "".join(f"{i:g},80\n" for i in range(8)), encoding="utf-8")
    manifest = tmp_path / "drives.csv"
    manifest.write_text(
        f"path,drive_id,speed_track\n{drive},fast,{fast.name}\n{drive},beside,\n", encoding="utf-8"
    )
    fast_drive, beside_drive = discover_drives(manifest)
    assert fast_drive.speed_track == fast and beside_drive.speed_track is None
    results = {
        d.drive_id: process_drive(DriveTask(drive=d, out_dir=tmp_path / "out", config=Config()))
        for d in (fast_drive, beside_drive)
    }
    assert results["fast"].status == "ok" and results["beside"].status == "ok"
    assert dict(results["fast"].alert_counts).get("long_distraction", 0) == 1
    # its own 10 km/h track beside the video: nothing
    assert sum(count for _, count in results["beside"].alert_counts) == 0
