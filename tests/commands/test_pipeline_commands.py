"""`roadgaze replay` and `roadgaze bench` end to end: real MediaPipe on the real GIF videos."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from repo_paths import VIDEOS
from roadgaze.cli import main

needs_videos = pytest.mark.skipif(
    not VIDEOS.is_dir(), reason="the evaluation videos ($ROADGAZE_DATA/videos) not present"
)
GIFS = {
    "head-pose-face-detection-female.gif": 23,
    "head-pose-face-detection-male.gif": 62,
    "head-pose-face-detection-female-and-male.gif": 56,
}


def read_jsonl(path: Path) -> list[dict[str, object]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


@needs_videos
@pytest.mark.slow
@pytest.mark.parametrize(("name", "frames"), GIFS.items())
def test_replay_writes_one_record_per_frame(tmp_path: Path, name: str, frames: int) -> None:
    out = tmp_path / "frames.jsonl"
    assert main(["replay", str(VIDEOS / name), "--out", str(out), "--no-progress"]) == 0
    records = read_jsonl(out)
    assert [r["frame"] for r in records] == list(range(frames))
    times = [float(r["t_s"]) for r in records]  # type: ignore[arg-type]
    assert all(b > a for a, b in itertools.pairwise(times))
    for record in records:
        for key in ("t_s", "frame", "face", "yaw_raw_deg", "yaw_deg", "yaw_rate_dps"):
            assert key in record
        assert {"yaw_std_deg", "x_left", "x_right", "x_center"} <= set(record)
        if not record["face"]:
            assert record["yaw_raw_deg"] is None
    assert sum(bool(r["face"]) for r in records) >= 0.9 * frames


@needs_videos
@pytest.mark.slow
def test_replay_female_sweeps_to_both_sides_with_all_outputs(tmp_path: Path) -> None:
    out, table = tmp_path / "frames.jsonl", tmp_path / "frames.csv"
    plot, video = tmp_path / "yaw.png", tmp_path / "annotated.mp4"
    code = main(
        [
            "replay",
            str(VIDEOS / "head-pose-face-detection-female.gif"),
            "--out",
            str(out),
            "--csv",
            str(table),
            "--plot",
            str(plot),
            "--annotate",
            str(video),
            "--no-progress",
        ]
    )
    assert code == 0
    raw = np.array([r["yaw_raw_deg"] for r in read_jsonl(out)], dtype=float)
    smoothed = np.array([r["yaw_deg"] for r in read_jsonl(out)], dtype=float)
    assert np.nanmin(raw) < -30.0 and np.nanmax(raw) > 30.0
    assert np.nanmin(smoothed) < -30.0 and np.nanmax(smoothed) > 30.0
    assert len(table.read_text().splitlines()) == 24
    assert cv2.imread(str(plot)) is not None
    capture = cv2.VideoCapture(str(video))
    assert capture.get(cv2.CAP_PROP_FRAME_COUNT) == 23
    capture.release()


@needs_videos
@pytest.mark.slow
def test_bench_json_on_a_640x480_clip(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    capture = cv2.VideoCapture(str(VIDEOS / "head-pose-face-detection-female.gif"))
    clip = tmp_path / "clip640.mp4"
    writer = cv2.VideoWriter(str(clip), cv2.VideoWriter.fourcc(*"mp4v"), 30.0, (640, 480))
    for _ in range(12):
        ok, image = capture.read()
        assert ok
        canvas = np.zeros((480, 640, 3), np.uint8)
        canvas[60:420] = cv2.resize(image, (640, 360))
        writer.write(canvas)
    writer.release()
    capture.release()
    capsys.readouterr()
    assert main(["bench", str(clip), "--json", "--warmup", "2"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["frames"] == 12 and result["frames_timed"] == 10
    assert result["fps"] > 0
    assert set(result["stages"]) >= {
        "decode",
        "enhance",
        "landmarks",
        "geometry",
        "smoothing",
        "total",
    }
    for stats in result["stages"].values():
        assert 0 <= stats["median_ms"] <= stats["p99_ms"]
    total, landmarks = result["stages"]["total"], result["stages"]["landmarks"]
    assert result["overhead_ratio"] == pytest.approx(
        total["median_ms"] / landmarks["median_ms"], rel=1e-3
    )
    # MediaPipe alone on the same frames, before and after the pipeline's pass.
    raw = result["raw_mediapipe"]
    assert raw["frames_timed"] == 2 * 10 and len(raw["passes_fps"]) == 2
    assert result["raw_mediapipe_fps"] > 0 and result["pipeline_fps"] > 0
    assert result["ratio_to_raw"] == pytest.approx(
        result["pipeline_fps"] / (sum(raw["passes_fps"]) / 2), rel=0.01
    )
    assert 0 < raw["median_ms"] <= raw["p99_ms"]
    assert "latency" not in result


@needs_videos
@pytest.mark.slow
def test_bench_latency_through_a_loopback_subscriber(capsys: pytest.CaptureFixture[str]) -> None:
    video = VIDEOS / "head-pose-face-detection-female.gif"
    args = [
        "bench",
        str(video),
        "--json",
        "--warmup",
        "2",
        "--latency",
        "--no-raw",
        "--repeat",
        "2",
    ]
    assert main(args) == 0
    captured = capsys.readouterr()
    result = json.loads(captured.out)
    assert "link down" not in captured.err  # a normal finish is no link loss
    assert result["passes"] == 2 and result["frames"] == 2 * 23
    assert result["raw_mediapipe_fps"] is None and result["ratio_to_raw"] is None
    # One more pass, at the clip's own frame rate as a camera would deliver it, publishes.
    latency = result["latency"]
    assert latency["paced"] is True
    assert latency["published"] == latency["received"] == 23
    assert 0 < latency["p50_ms"] <= latency["p99_ms"] <= latency["max_ms"]
    # Delivery cannot be faster than the landmark stage that precedes it.
    assert 0 < latency["landmarks_p50_ms"] <= latency["landmarks_p99_ms"]
    assert latency["p50_ms"] >= latency["landmarks_p50_ms"]
    assert latency["stages"]["landmarks"]["p99_ms"] == latency["landmarks_p99_ms"]
    assert set(latency["stages"]) == set(result["stages"])
    assert latency["target_p99_ms"] == pytest.approx(latency["landmarks_p99_ms"] + 2.0, abs=2e-3)
    assert latency["meets_target"] == (latency["p99_ms"] <= latency["target_p99_ms"])
    # The two parts: in the loop up to the publish (at least the landmark stage), then Zenoh.
    # The publish is stamped when the put has returned; on a loaded machine the subscriber in the
    # other process can log the arrival first (the loop's thread descheduled between the two), so
    # the delivery part may read a fraction of a millisecond below zero, never more; so may the
    # whole against its first part (medians of frames whose delivery reads below zero).
    assert -1.0 < latency["delivery_p50_ms"] < latency["p50_ms"]
    assert latency["to_publish_p50_ms"] >= latency["landmarks_p50_ms"]
    assert latency["to_publish_p50_ms"] < latency["p50_ms"] + 1.0


@pytest.mark.parametrize(
    ("content", "message"),
    [(None, "no video file, image folder or camera"), (b"garbage" * 100, "cannot read video")],
)
def test_replay_bad_input_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: bytes | None, message: str
) -> None:
    path = tmp_path / "input.mp4"
    if content is not None:
        path.write_bytes(content)
    code = main(["replay", str(path), "--out", str(tmp_path / "o.jsonl"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    assert message in err
    assert "Traceback" not in err
