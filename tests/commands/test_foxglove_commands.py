"""`replay --mcap`, MCAP drives in `replay` and `batch`, `run --record --foxglove` and the
missing extra, end to end with real MediaPipe on a synthetic drive (a look away to the right
for 4.5 s: a long distraction, then cleared)."""

from __future__ import annotations

import json
import resource
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from foxglove_helpers import protobuf_message, read_mcap
from repo_paths import REPO, child_env
from roadgaze.cli import main
from roadgaze.daemon import EXIT_UNDELIVERED
from roadgaze.outputs import OFFLINE_FIELDS
from roadgaze.outputs.foxglove.channels import (
    TOPIC_ALERTS,
    TOPIC_IMAGE,
    TOPIC_RECORD,
    TOPIC_STATE,
)
from zenoh_helpers import LineReader, endpoint, free_port, stop_process

pytestmark = pytest.mark.slow
DRIVE = "0:1,-35:4.5,0:1"
PNG_EVERY_FRAME = ["--set", "record.image_format=png", "--set", "record.image_fps=1000"]


def read_jsonl(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


@pytest.fixture(scope="module")
def drive(synthetic_clip: Callable[[str], tuple[Path, Any]]) -> Path:
    return synthetic_clip(DRIVE)[0]


@pytest.fixture(scope="module")
def replayed(drive: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """`replay DRIVE --out frames.jsonl --mcap drive.mcap` (JPEG camera frames at 5 fps)."""
    folder = tmp_path_factory.mktemp("replayed")
    out, mcap = folder / "frames.jsonl", folder / "drive.mcap"
    args = ["replay", str(drive), "--out", str(out), "--mcap", str(mcap), "--no-progress"]
    assert main(args) == 0
    return out, mcap


def test_replay_mcap_holds_one_record_per_frame_in_time_order_and_decodable_images(
    replayed: tuple[Path, Path], restore_logging: None
) -> None:
    out, mcap = replayed
    lines = read_jsonl(out)
    contents = read_mcap(mcap)
    assert set(contents.schemas.values()) >= {
        "foxglove.CompressedImage", "foxglove.ImageAnnotations", "roadgaze.record",
        "roadgaze.limits", "roadgaze.alert/4", "roadgaze.state/6", "roadgaze.support/1",
    }  # fmt: skip
    records = contents.json(TOPIC_RECORD)
    streamed = [{**line, **dict.fromkeys(OFFLINE_FIELDS)} for line in lines]
    assert records == streamed  # the offline columns are filled in the files only
    stamps = [message.log_time for message in contents.messages[TOPIC_RECORD]]
    assert stamps == sorted(stamps) == [round(line["t_s"] * 1e9) for line in lines]
    images = contents.messages[TOPIC_IMAGE]
    assert len(images) == int(lines[-1]["t_s"] * 5.0 + 1e-9) + 1
    for message in images[::5]:
        image = protobuf_message(contents, TOPIC_IMAGE, message.data)
        picture = cv2.imdecode(np.frombuffer(image.data, np.uint8), cv2.IMREAD_COLOR)
        assert picture.shape == (320, 320, 3) and message.log_time in stamps
    alerts = contents.json(TOPIC_ALERTS)
    raised = [label for line in lines for label in line["alerts"]]
    assert [f"{a['kind']}:{a['level']}" for a in alerts] == raised and raised
    assert "long_distraction:warning" in raised
    assert len(contents.messages[TOPIC_STATE]) >= int(lines[-1]["t_s"])


def test_replaying_a_lossless_recording_gives_the_records_of_the_video(
    drive: Path, replayed: tuple[Path, Path], tmp_path: Path, restore_logging: None
) -> None:
    recording = tmp_path / "png.mcap"
    args = ["replay", str(drive), "--out", str(tmp_path / "v.jsonl"), "--mcap", str(recording)]
    assert main([*args, *PNG_EVERY_FRAME, "--no-progress"]) == 0
    out = tmp_path / "from-mcap.jsonl"
    assert main(["replay", str(recording), "--out", str(out), "--no-progress"]) == 0
    assert read_jsonl(out) == read_jsonl(replayed[0])


def test_replaying_a_jpeg_recording_stays_close_to_the_video(
    drive: Path, replayed: tuple[Path, Path], tmp_path: Path, restore_logging: None
) -> None:
    recording = tmp_path / "jpeg.mcap"
    args = ["replay", str(drive), "--out", str(tmp_path / "v.jsonl"), "--mcap", str(recording)]
    assert main([*args, "--set", "record.image_fps=1000", "--no-progress"]) == 0
    out = tmp_path / "from-mcap.jsonl"
    assert main(["replay", str(recording), "--out", str(out), "--no-progress"]) == 0
    video, again = read_jsonl(replayed[0]), read_jsonl(out)
    assert [r["t_s"] for r in again] == [r["t_s"] for r in video]
    yaw = np.array(
        [
            [v["yaw_deg"], a["yaw_deg"]]
            for v, a in zip(video, again, strict=True)
            if v["yaw_deg"] is not None and a["yaw_deg"] is not None
        ],
        float,
    )
    difference = np.abs(yaw[:, 0] - yaw[:, 1])
    assert len(yaw) >= 0.95 * len(video)
    assert np.median(difference) < 1.0 and difference.max() < 5.0
    zones = np.mean([v["zone"] == a["zone"] for v, a in zip(video, again, strict=True)])
    assert zones >= 0.95
    assert [a for r in again for a in r["alerts"]] == [a for r in video for a in r["alerts"]]


def test_batch_replays_mcap_drives_beside_videos(
    drive: Path, tmp_path: Path, restore_logging: None
) -> None:
    import pyarrow.parquet as pq

    folder = tmp_path / "fleet"
    folder.mkdir()
    shutil.copy(drive, folder / "video.mkv")
    recording = folder / "recorded.mcap"
    args = ["replay", str(drive), "--out", str(tmp_path / "v.jsonl"), "--mcap", str(recording)]
    assert main([*args, *PNG_EVERY_FRAME, "--no-progress"]) == 0
    out = tmp_path / "out"
    assert main(["batch", str(folder), "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    video = pq.read_table(out / "frames" / "video.parquet").to_pydict()
    recorded = pq.read_table(out / "frames" / "recorded.parquet").to_pydict()
    for column in ("t_s", "yaw_deg", "pitch_deg", "zone", "alerts", "yaw_offline_deg"):
        assert recorded[column] == video[column], column


FAKE_DAEMON = REPO / "tests" / "fake_daemon.py"


def test_run_records_and_serves_a_drive_to_its_end(drive: Path, tmp_path: Path) -> None:
    folder = tmp_path / "rec"
    result = subprocess.run(
        [sys.executable, "-m", "roadgaze", "run", "--source", str(drive), "--no-realtime",
         "--record", str(folder), "--foxglove", "127.0.0.1:0",
         "--zenoh-listen", endpoint(free_port()), "--set", "zenoh.delivery_wait_s=0"],
        capture_output=True, text=True, env=child_env(GLOG_minloglevel="2"), timeout=300,
        check=False,
    )  # fmt: skip
    # Nobody connected to the daemon: its alerts never reached the bus, and it says so (4).
    assert result.returncode == EXIT_UNDELIVERED, result.stderr[-2000:]
    assert "alerts never reached the zenoh bus" in result.stderr
    assert "foxglove: live view on ws://127.0.0.1:" in result.stderr
    (segment,) = folder.glob("roadgaze-car-0-*.mcap")
    contents = read_mcap(segment)
    assert TOPIC_IMAGE not in contents.schemas  # the vehicle records no camera frames by default
    records = contents.json(TOPIC_RECORD)
    assert [r["frame"] for r in records] == list(range(len(records))) and len(records) >= 95
    assert contents.metadata["roadgaze"]["time_base"] == "wall clock"
    assert not list(folder.glob("*.part"))


def test_a_recording_that_fails_stops_and_monitoring_goes_on(tmp_path: Path) -> None:
    """The disk limit hit (RLIMIT_FSIZE: writes beyond 300 kB fail with 'File too large'): one
    error line, the daemon keeps monitoring and stops cleanly (the state's problem: the
    recorder's tests)."""

    def limit_file_size() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (300_000, 300_000))

    daemon = subprocess.Popen(
        [sys.executable, str(FAKE_DAEMON), "--record", str(tmp_path / "rec"),
         "--set", "record.images=true", "--set", "record.image_fps=30",
         "--set", "record.flush_s=0.2", "--set", "zenoh.delivery_wait_s=0",
         "--zenoh-listen", endpoint(free_port())],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, preexec_fn=limit_file_size,
        env=child_env(PYTHONDONTWRITEBYTECODE="1"),
    )  # fmt: skip
    try:
        log = LineReader(daemon, daemon.stderr)
        lines = log.until("recording stopped (monitoring goes on)", 90.0)
        assert "cannot write MCAP" in lines[-1] and "File too large" in lines[-1]
        lines = log.until("alert long_distraction warning", 30.0)  # still monitoring
        assert not any("recording stopped" in line for line in lines[:-1])
        daemon.send_signal(signal.SIGTERM)
        assert daemon.wait(timeout=30.0) == EXIT_UNDELIVERED  # nobody connected for the alert
    finally:
        stop_process(daemon)


@pytest.mark.parametrize(
    ("args", "what"),
    [
        (["replay", "{drive}", "--mcap", "{tmp}/x.mcap", "--no-progress"], "--mcap"),
        (["run", "--source", "{drive}", "--record", "{tmp}/rec"], "--record"),
        (["run", "--source", "{drive}", "--foxglove", "8765"], "--foxglove"),
        (["bench", "{drive}", "--record"], "bench --record"),
        (["recover", "{tmp}/x.mcap.part"], "roadgaze recover"),
    ],
)
def test_without_the_extra_each_flag_is_one_line_naming_it(
    drive: Path, tmp_path: Path, args: list[str], what: str
) -> None:
    argv = [arg.format(drive=drive, tmp=tmp_path) for arg in args]
    code = (
        "import sys; sys.modules['foxglove'] = None\n"
        "from roadgaze.cli import main\n"
        f"sys.exit(main({argv!r}))\n"
    )
    started = time.monotonic()
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            env=child_env(), timeout=120, check=False)  # fmt: skip
    assert result.returncode == 2
    assert result.stderr.splitlines() == [
        f"roadgaze {argv[0]}: error: {what} needs the Foxglove SDK and the MCAP reader, which "
        "are not installed: pip install 'roadgaze[foxglove]'"
    ]
    assert time.monotonic() - started < 60.0  # said before any model or camera is opened
    assert not (tmp_path / "rec").exists()


def test_bench_record_reports_what_recording_costs(
    drive: Path, capsys: pytest.CaptureFixture[str], restore_logging: None
) -> None:
    args = ["bench", str(drive), "--record", "--no-raw", "--json", "--warmup", "5"]
    assert main(args) == 0
    cost = json.loads(capsys.readouterr().out)["recording"]
    assert [p["kind"] for p in cost["passes"]] == ["none", "records", "images"]
    frames = cost["passes"][0]["frames"]
    assert all(p["frames"] == frames for p in cost["passes"])
    records, images = cost["records"], cost["images"]
    assert records["total_ms_per_frame"] == pytest.approx(
        records["loop_thread_cpu_ms_per_frame"] + records["writer_thread_cpu_ms_per_frame"],
        abs=2e-4,
    )
    assert 0 < records["loop_thread_cpu_ms_per_frame"] < records["writer_thread_cpu_ms_per_frame"]
    assert cost["passes"][1]["images"] == 0 and cost["passes"][2]["images"] > 0
    # 5 of 15 fps are due; one the encoder could not take in time (a loaded machine) is dropped
    # and counted, never lost silently.
    for taken in [p for p in cost["passes"] if p["kind"] == "images"]:
        due = (taken["images"] + taken["images_dropped"]) / taken["frames"]
        assert due == pytest.approx(5.0 / 15.0, abs=0.025)
    assert images["image_thread_cpu_ms_per_image"] > 0 and len(cost["load_average_before"]) == 3
