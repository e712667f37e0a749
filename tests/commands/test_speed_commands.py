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


def test_speed_track_and_replay_give_the_monitor_the_same_speed_at_every_frame(
    tmp_path: Path,
) -> None:
    """One track file through both paths, sample for sample:

    - `roadgaze replay drive.mp4`: the track found beside the video (`replay.run_options`, then
      the builder's `choose_speed`), asked at each frame's time by the loop;
    - `roadgaze speed --track drive.speed.csv`: what the command publishes (`speed_to_publish`,
      `publish_track` on a clock), each payload taken by the daemon's speed input
      (`SpeedInput`, the newest one when the loop asks, once per frame).

    The track is a CAN-like 20 Hz signal with jitter, decimals, a crossing of the 20 km/h active
    speed, a dropout (empty kmh), a gap longer than the hold and an end; no sample or hold's end
    falls on a frame time (30 fps), so delivery at 'the same instant' is never decided by float
    rounding.
    """
    from collections import deque

    from fakes import ListSource, ScriptedDetector
    from roadgaze.cli import build_parser
    from roadgaze.commands.replay import run_options
    from roadgaze.commands.speed import speed_to_publish
    from roadgaze.config import Config
    from roadgaze.pipeline import Pipeline, choose_speed
    from roadgaze.transport.speed import SpeedInput, publish_track

    rows = []
    for k in range(160):  # 0-8 s at 20 Hz
        t_s = 0.0 if k == 0 else round(0.05 * k + 0.001 + 0.003 * (k % 4), 3)
        if 3.0 < t_s < 3.5:
            continue  # no sample for 0.5 s: held
        if 5.0 < t_s < 7.6:
            continue  # no sample for 2.6 s: longer than the 2 s hold, unknown
        kmh = "" if 4.0 < t_s < 4.3 else f"{12.0 + 3.7 * k % 31 + 0.125 * (k % 8):.3f}"
        rows.append(f"{t_s:.3f},{kmh}\n")
    video = tmp_path / "drive.mp4"
    video.write_bytes(b"not read: the frames come from the test")
    track = tmp_path / "drive.speed.csv"
    track.write_text("t_s,kmh\n" + "".join(rows), encoding="utf-8")
    config = Config()
    parser = build_parser()
    fps, count = 30.0, 330  # 11 s: past the end of the last sample's hold

    replay_choice = choose_speed(config, run_options(parser.parse_args(["replay", str(video)])))
    assert replay_choice.track_path == track
    replayed = Pipeline(ScriptedDetector([0.0] * count), speed=replay_choice.speed)
    replay_verdicts = [p.record.verdict for p in replayed.frames(ListSource(count, fps))]

    published = speed_to_publish(parser.parse_args(["speed", "--track", str(track)]), config)
    clock = [0.0]

    def wait(seconds: float) -> bool:
        clock[0] += seconds
        return False

    puts: deque[tuple[float, bytes]] = deque()
    for _ in publish_track(published, lambda p: puts.append((clock[0], p)), wait, lambda: clock[0]):
        pass
    now = [0.0]
    bus = SpeedInput(config.zenoh.speed_timeout_s, clock=lambda: now[0])
    daemon = Pipeline(ScriptedDetector([0.0] * count), speed=bus.kmh)
    frames = daemon.frames(ListSource(count, fps))
    bus_verdicts = []
    for index in range(count):
        now[0] = index / fps
        while puts and puts[0][0] <= now[0]:
            bus.on_payload(puts.popleft()[1])  # the ring of one keeps the newest
        bus_verdicts.append(next(frames).record.verdict)

    replay_speeds = [v.speed_kmh for v in replay_verdicts]
    assert [v.speed_kmh for v in bus_verdicts] == replay_speeds
    assert [v.moving for v in bus_verdicts] == [v.moving for v in replay_verdicts]
    known = {speed for speed in replay_speeds if speed is not None}
    assert len(known) > 20 and min(known) < 20.0 < max(known)  # the gate opens and closes
    assert None in replay_speeds[125:135]  # the dropout (4.0-4.3 s)
    assert replay_speeds[100] is not None  # 3.33 s: held through the 0.5 s without a sample
    assert replay_speeds[210] is None and replay_speeds[-1] is None  # the long gap (7 s), the end
