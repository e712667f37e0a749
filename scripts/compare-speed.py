#!/usr/bin/env python3
"""Compare the live path's speed of two source trees on one clip, interleaved, against MediaPipe.

    .venv/bin/python scripts/compare-speed.py VIDEO --trees OLD/src NEW/src [--rounds 3]

Each round runs one child process per tree (alternating which goes first), with the tree first
on PYTHONPATH. A child does what `roadgaze bench` does: MediaPipe's FaceLandmarker alone on the
clip (VIDEO mode, one face, frames decoded first, only `detect_for_video` timed; code of its own,
the same for any tree), then the tree's loop over the clip with no outputs as its bench builds it
(`build_run`; `Pipeline.run` in a tree from before it), frames per second after a warm-up, then
MediaPipe alone again; the ratio is the pipeline's fps over the mean of the two raw passes, the
median ratio the raw passes' median call time over the pipeline's median time between frames
(load spikes move it less).
Every run is printed (a shared machine's load moves single runs), then the medians; progress on
stderr, the table on stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

WARMUP = 10


def raw_fps(video: str, model_path: str) -> tuple[float, float, float]:
    """MediaPipe alone: (fps, CPU ms per frame, median ms per call) over the timed calls."""
    import cv2
    import mediapipe as mp
    from mediapipe.tasks.python import vision
    from mediapipe.tasks.python.core.base_options import BaseOptions

    capture = cv2.VideoCapture(video)
    frames = []
    while True:
        ok, image = capture.read()
        if not ok:
            break
        frames.append(cv2.cvtColor(image, cv2.COLOR_BGR2RGB))
    fps = capture.get(cv2.CAP_PROP_FPS) or 30.0
    capture.release()
    options = vision.FaceLandmarkerOptions(
        base_options=BaseOptions(model_asset_path=model_path),
        running_mode=vision.RunningMode.VIDEO,
        num_faces=1,
    )
    landmarker = vision.FaceLandmarker.create_from_options(options)
    calls: list[float] = []
    cpu = 0.0
    for index, rgb in enumerate(frames):
        image = mp.Image(image_format=mp.ImageFormat.SRGB, data=rgb)
        cpu_before, before = time.process_time(), time.perf_counter()
        landmarker.detect_for_video(image, round(1000 * index / fps))
        if index >= WARMUP:
            calls.append(time.perf_counter() - before)
            cpu += time.process_time() - cpu_before
    landmarker.close()
    return len(calls) / sum(calls), 1e3 * cpu / len(calls), 1e3 * statistics.median(calls)


class Throughput:
    """Sink: fps and CPU ms per frame after the first WARMUP records."""

    def __init__(self) -> None:
        self.seen = 0
        self.start: tuple[float, float] | None = None
        self.last: tuple[float, float] | None = None
        self.intervals: list[float] = []

    def on_record(self, record: Any, frame: Any) -> None:
        self.seen += 1
        now = (time.perf_counter(), time.process_time())
        if self.seen == WARMUP + 1:
            self.start = now
        elif self.seen > WARMUP + 1:
            previous = self.last or self.start
            assert previous is not None
            self.intervals.append(now[0] - previous[0])
            self.last = now

    def on_alert(self, alert: Any) -> None:
        return None

    def close(self) -> None:
        return None


def child(video: str) -> None:
    import roadgaze
    from roadgaze.capture import open_source
    from roadgaze.config import Config
    from roadgaze.landmarks.model_store import resolve_model
    from roadgaze.pipeline import Pipeline, create_detector  # a tree from before the builder

    config = Config()
    model = str(resolve_model(config.model))
    before, before_cpu, before_median = raw_fps(video, model)
    probe = Throughput()
    try:
        from roadgaze.pipeline import RunOptions, build_run
    except ImportError:  # a tree from before the one builder: the loop as its bench ran it
        detector = create_detector(config)
        with open_source(video, config) as source:
            summary = Pipeline.from_config(config, detector).run(source, [probe])
        detector.close()
    else:
        options = RunOptions(video, command="bench", quiet=True)
        with build_run(config, options, sinks=(probe,)) as run:
            summary = run.run()
    after, after_cpu, after_median = raw_fps(video, model)
    assert probe.start is not None and probe.last is not None
    frames = probe.seen - WARMUP - 1
    pipeline_fps = frames / (probe.last[0] - probe.start[0])
    landmarks = summary.stages["landmarks"]
    result = {
        "tree": str(Path(roadgaze.__file__).parents[1]),
        "pipeline_fps": round(pipeline_fps, 2),
        "raw_fps": [round(before, 2), round(after, 2)],
        "ratio_to_raw": round(pipeline_fps / (0.5 * (before + after)), 4),
        "median_ratio_to_raw": round(
            0.5 * (before_median + after_median) / (1e3 * statistics.median(probe.intervals)), 4
        ),
        "cpu_ms_per_frame": round(1e3 * (probe.last[1] - probe.start[1]) / frames, 2),
        "raw_cpu_ms_per_frame": round(0.5 * (before_cpu + after_cpu), 2),
        "landmarks_median_ms": round(landmarks.median_ms, 2),
        "landmarks_p99_ms": round(landmarks.p99_ms, 2),
    }
    print(json.dumps(result), flush=True)


def run_child(video: str, tree: Path) -> dict[str, Any]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(tree), env.get("PYTHONPATH")]))
    command = [sys.executable, __file__, "--child", video]
    result = subprocess.run(
        command, env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, check=True
    )
    measured: dict[str, Any] = json.loads(result.stdout.strip().splitlines()[-1])
    print(f"compare-speed: {tree}: {measured}", file=sys.stderr, flush=True)
    return measured


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("video")
    parser.add_argument("--trees", nargs=2, type=Path, metavar=("OLD_SRC", "NEW_SRC"))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.video)
        return 0
    if args.trees is None:
        parser.error("--trees OLD_SRC NEW_SRC is required")
    runs: dict[Path, list[dict[str, Any]]] = {tree: [] for tree in args.trees}
    for number in range(args.rounds):
        order = args.trees if number % 2 == 0 else args.trees[::-1]
        for tree in order:
            runs[tree].append(run_child(args.video, tree))
    print("| tree | run | pipeline fps | raw fps (before, after) | ratio_to_raw | median ratio | "
          "CPU ms/frame (raw) | landmarks median / p99 ms |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    for tree, measured in runs.items():
        for number, run in enumerate(measured, 1):
            print(
                f"| {tree} | {number} | {run['pipeline_fps']} | {run['raw_fps']} | "
                f"{run['ratio_to_raw']} | {run['median_ratio_to_raw']} | "
                f"{run['cpu_ms_per_frame']} ({run['raw_cpu_ms_per_frame']})"
                f" | {run['landmarks_median_ms']} / {run['landmarks_p99_ms']} |"
            )
        ratios = [run["ratio_to_raw"] for run in measured]
        medians = [run["median_ratio_to_raw"] for run in measured]
        print(f"| {tree} | median | | | {statistics.median(ratios):.4f} | "
              f"{statistics.median(medians):.4f} | | |")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
