"""`roadgaze bench VIDEO`: per-stage time, end-to-end fps, loop overhead and memory growth."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

from roadgaze.commands.options import check_seconds, common_options
from roadgaze.config import Config
from roadgaze.types import Frame, FrameRecord


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "bench",
        parents=[common_options()],
        help="time each pipeline stage on a video: median and p99 ms, fps, overhead ratio",
        description="Run the pipeline over a video as fast as possible, without outputs, and "
        "print per-stage median and p99 milliseconds (decode, landmarks, geometry, smoothing, "
        "total), end-to-end fps and overhead_ratio = median total frame time / median landmark "
        "time. --loop-seconds replays the video for that long; --memory adds resident-memory "
        "growth over the run.",
    )
    parser.add_argument("source", metavar="VIDEO", help="video file (or image folder)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--loop-seconds",
        type=float,
        metavar="S",
        help="replay the video in a loop for S seconds of wall time (default: one pass)",
    )
    parser.add_argument(
        "--memory", action="store_true", help="report resident memory (VmRSS) growth"
    )
    parser.add_argument(
        "--warmup",
        type=int,
        default=10,
        metavar="N",
        help="frames excluded from the timing statistics (model start-up), default 10",
    )
    parser.set_defaults(handler=run)


def resident_mb() -> float:
    """This process's resident memory (VmRSS) in MiB; NaN where /proc is not available."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return float("nan")


class MemoryProbe:
    """Samples VmRSS about once a second; the baseline is taken after `settle_s` of running."""

    def __init__(self, settle_s: float = 10.0) -> None:
        self._settle_s = settle_s
        self._start = time.monotonic()
        self._next = self._start
        self.baseline_mb: float | None = None
        self.last_mb = resident_mb()
        self.peak_mb = self.last_mb

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        now = time.monotonic()
        if now < self._next:
            return
        self._next = now + 1.0
        self.last_mb = resident_mb()
        self.peak_mb = max(self.peak_mb, self.last_mb)
        if self.baseline_mb is None and now - self._start >= self._settle_s:
            self.baseline_mb = self.last_mb

    def close(self) -> None:
        self.last_mb = resident_mb()

    @property
    def growth_mb(self) -> float | None:
        return None if self.baseline_mb is None else self.last_mb - self.baseline_mb


def run(args: argparse.Namespace, config: Config) -> int:
    from contextlib import closing

    from roadgaze.capture import FrameSource, LoopingSource, VideoFileSource, open_source
    from roadgaze.errors import ConfigError
    from roadgaze.pipeline import STAGES, Pipeline, StageTimings, create_detector

    if args.warmup < 0:
        raise ConfigError(f"--warmup must be >= 0, found {args.warmup}")
    check_seconds("--loop-seconds", args.loop_seconds)
    rss_start_mb = resident_mb()
    source: FrameSource
    if args.loop_seconds is not None:
        path = Path(args.source)
        if not path.is_file():
            raise ConfigError(f"--loop-seconds needs a video file, found '{args.source}'")
        source = LoopingSource(lambda: VideoFileSource(path), duration_s=args.loop_seconds)
    else:
        source = open_source(args.source, config)
    settle_s = min(10.0, 0.1 * (args.loop_seconds or 0.0))
    probe = MemoryProbe(settle_s=settle_s) if args.memory else None
    timings = StageTimings(skip_first=args.warmup)
    with source, closing(create_detector(config)) as detector:
        pipeline = Pipeline.from_config(config, detector)
        summary = pipeline.run(source, [probe] if probe else [], timings=timings)
    if timings.count == 0:
        raise ConfigError(
            f"{args.source} has {summary.frames} frames, not more than --warmup {args.warmup}; "
            "lower --warmup"
        )
    result: dict[str, Any] = {
        "source": args.source,
        "frames": summary.frames,
        "frames_timed": timings.count,
        "fps": round(summary.fps, 2),
        "overhead_ratio": round(summary.overhead_ratio, 4),
        "stages": {
            stage: {"median_ms": round(stats.median_ms, 3), "p99_ms": round(stats.p99_ms, 3)}
            for stage, stats in summary.stages.items()
        },
        "face_rate": round(summary.frames_with_face / summary.frames, 4) if summary.frames else 0,
    }
    if probe is not None:
        growth = probe.growth_mb
        result["memory"] = {
            "rss_start_mb": round(rss_start_mb, 1),
            "rss_baseline_mb": None if probe.baseline_mb is None else round(probe.baseline_mb, 1),
            "rss_end_mb": round(probe.last_mb, 1),
            "rss_peak_mb": round(probe.peak_mb, 1),
            "rss_growth_mb": None if growth is None else round(growth, 2),
            "wall_s": round(summary.wall_s, 1),
        }
    if args.json:
        print(json.dumps(result))
        return 0
    print(f"bench {args.source}: {summary.frames} frames ({timings.count} timed) "
          f"in {summary.wall_s:.1f} s")  # fmt: skip
    print(f"{'stage':<10} {'median ms':>10} {'p99 ms':>10}")
    for stage in STAGES:
        stats = summary.stages[stage]
        print(f"{stage:<10} {stats.median_ms:>10.3f} {stats.p99_ms:>10.3f}")
    print(f"fps            {summary.fps:.1f}")
    print(f"overhead_ratio {summary.overhead_ratio:.3f}")
    if probe is not None:
        memory = result["memory"]
        print(
            f"memory: start {memory['rss_start_mb']} MiB, baseline {memory['rss_baseline_mb']} "
            f"MiB, end {memory['rss_end_mb']} MiB, peak {memory['rss_peak_mb']} MiB, "
            f"growth {memory['rss_growth_mb']} MiB",
        )
    return 0
