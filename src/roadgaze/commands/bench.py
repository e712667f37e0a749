"""`roadgaze bench VIDEO`: per-stage time, throughput against raw MediaPipe, latency, memory."""

from __future__ import annotations

import argparse
import json
import logging
import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roadgaze.commands.options import check_seconds, common_options
from roadgaze.config import Config

if TYPE_CHECKING:
    from roadgaze.benchmark import LatencyResult, RawResult
    from roadgaze.capture import FrameSource
    from roadgaze.pipeline import RunSummary, StageStats, StageTimings

log = logging.getLogger("roadgaze.bench")

LATENCY_MARGIN_MS = 2.0
"""The latency target: p99 capture-to-delivery at most the landmark stage's p99 plus this."""


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "bench",
        parents=[common_options()],
        help="time each pipeline stage on a video: ms per stage, fps, ratio to raw MediaPipe",
        description="Run the pipeline over a video as fast as possible, without outputs, and "
        "print per-stage median and p99 milliseconds (decode, landmarks, geometry, smoothing, "
        "monitor, sinks, total), end-to-end fps and overhead_ratio = median total frame time / "
        "median landmark time. In the same process MediaPipe's FaceLandmarker runs alone on the "
        "same frames (VIDEO mode, one face, frames decoded beforehand, only detect_for_video "
        "timed; before and after each pipeline pass): raw_mediapipe_fps and ratio_to_raw = the "
        "pipeline's fps after the warm-up / the raw fps of the passes around it. --latency adds "
        "a pass at the video's own frame rate (as a camera delivers frames) that publishes every "
        "frame on Zenoh over loopback and measures capture-to-delivery at a subscriber, against "
        "that pass's landmark p99 + 2 ms. --loop-seconds replays the video for that long; "
        "--memory adds resident-memory growth over the run. Results go to stdout, logs to stderr.",
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
    parser.add_argument(
        "--latency",
        action="store_true",
        help="add a pass at the video's frame rate publishing each frame's yaw message on Zenoh "
        "(loopback) and report capture-to-delivery p50/p99 ms at a subscriber in another process",
    )
    parser.add_argument(
        "--repeat",
        type=int,
        default=1,
        metavar="N",
        help="N pipeline passes, each between two raw passes; ratio_to_raw is the median of the "
        "N ratios (on a shared machine, repeat to see the spread)",
    )
    parser.add_argument(
        "--no-raw", action="store_true", help="skip the raw MediaPipe passes (no ratio_to_raw)"
    )
    parser.add_argument("--record", action="store_true", help="add --repeat rounds of passes "
                        "without a recorder, recording records and alerts to MCAP, and camera "
                        "frames too; report the cost per frame (roadgaze[foxglove])")  # fmt: skip
    parser.add_argument(
        "--engines",
        action="store_true",
        help="compare the landmark engines: --repeat rounds of a raw FaceLandmarker pass and one "
        "pipeline pass per engine (litert, mediapipe), interleaved; medians and the load average",
    )
    parser.add_argument("--phone", action="store_true", help="CPU per frame with phone "
                        "detection ([hands]) off and on: --repeat interleaved rounds")  # fmt: skip
    parser.set_defaults(handler=run)


def open_bench_source(args: argparse.Namespace, config: Config) -> FrameSource:
    """The source of the timed pass: the file, or the file looped for --loop-seconds."""
    from roadgaze.capture import LoopingSource, VideoFileSource, open_source
    from roadgaze.errors import ConfigError

    if args.loop_seconds is None:
        return open_source(args.source, config)
    path = Path(args.source)
    if not path.is_file():
        raise ConfigError(f"--loop-seconds needs a video file, found '{args.source}'")
    return LoopingSource(lambda: VideoFileSource(path), duration_s=args.loop_seconds)


def raw_pass(args: argparse.Namespace, config: Config, number: int, count: int) -> RawResult:
    """One raw-MediaPipe pass over the source's frames (one pass of a looped file)."""
    from roadgaze.benchmark import raw_mediapipe_pass
    from roadgaze.capture import open_source
    from roadgaze.landmarks.model_store import resolve_model

    log.info("raw MediaPipe pass %d of %d", number, count)
    with open_source(args.source, config) as source:
        return raw_mediapipe_pass(
            source, resolve_model(config.model), config.landmarks, args.warmup
        )


@dataclass(frozen=True, slots=True)
class PassResult:
    """One timed pass of the pipeline."""

    summary: RunSummary
    fps: float | None
    """After the warm-up (`ThroughputProbe`)."""
    cpu_ms_per_frame: float | None
    median_interval_ms: float | None
    engine: str | None = None
    """The landmark engine that ran."""


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.benchmark import MemoryProbe, resident_mb
    from roadgaze.benchmark.report import format_result
    from roadgaze.errors import ConfigError
    from roadgaze.pipeline import StageTimings

    if args.warmup < 0:
        raise ConfigError(f"--warmup must be >= 0, found {args.warmup}")
    check_seconds("--loop-seconds", args.loop_seconds)
    if args.repeat < 1:
        raise ConfigError(f"--repeat must be at least 1, found {args.repeat}")
    if args.record:
        from roadgaze.outputs.foxglove import require_foxglove

        require_foxglove("bench --record")
    if args.engines:
        return engines_run(args, config)
    if args.phone:
        from roadgaze.benchmark.phone import phone_cost

        return phone_cost(args, config, pipeline_pass)
    rss_start_mb = resident_mb()
    with open_bench_source(args, config) as first_source:
        live = first_source.info.live
    do_raw = not args.no_raw and not live
    if live and not args.no_raw:
        log.info("a live source cannot be replayed: no raw MediaPipe pass")
    settle_s = min(10.0, 0.1 * (args.loop_seconds or 0.0))
    memory = MemoryProbe(settle_s=settle_s) if args.memory else None
    timings = StageTimings()
    raw_passes: list[RawResult] = []
    passes: list[PassResult] = []
    latency = None
    if do_raw:
        raw_passes.append(raw_pass(args, config, 1, args.repeat + 1))
    for number in range(1, args.repeat + 1):
        timings.skip_next(args.warmup)
        passes.append(pipeline_pass(args, config, [memory] if memory else [], timings))
        if do_raw:
            raw_passes.append(raw_pass(args, config, number + 1, args.repeat + 1))
    if args.latency:
        latency = latency_pass(args, config)
    recording = recording_cost(args, config) if args.record else None
    if timings.count == 0:
        frames = passes[0].summary.frames
        raise ConfigError(
            f"{args.source} has {frames} frames, not more than --warmup {args.warmup}; "
            "lower --warmup"
        )
    result = bench_result(args.source, passes, timings, raw_passes, latency)
    if recording is not None:
        result["recording"] = recording
    if memory is not None:
        growth = memory.growth_mb
        result["memory"] = {
            "rss_start_mb": round(rss_start_mb, 1),
            "rss_baseline_mb": None if memory.baseline_mb is None else round(memory.baseline_mb, 1),
            "rss_end_mb": round(memory.last_mb, 1),
            "rss_peak_mb": round(memory.peak_mb, 1),
            "rss_growth_mb": None if growth is None else round(growth, 2),
            "wall_s": round(sum(p.summary.wall_s for p in passes), 1),
        }
    print(json.dumps(result) if args.json else format_result(result))
    return 0


def engines_run(args: argparse.Namespace, config: Config) -> int:
    """`--engines`: both engines and raw FaceLandmarker, interleaved (`benchmark.engines`)."""
    from roadgaze.benchmark.engines import EnginePass, compare_engines, format_engines
    from roadgaze.benchmark.raw import litert_models_pass
    from roadgaze.pipeline import StageTimings

    def engine_pass(name: str) -> EnginePass:
        landmarks = config.landmarks.model_copy(update={"engine": name})
        timings = StageTimings(skip_first=args.warmup)
        result = pipeline_pass(
            args, config.model_copy(update={"landmarks": landmarks}), [], timings
        )
        stages = {stage: (s.median_ms, s.p99_ms) for stage, s in timings.stats().items()}
        return EnginePass(result.fps, result.cpu_ms_per_frame, stages, result.engine or name)

    raws = iter(range(1, args.repeat + 2))
    result = compare_engines(
        args.repeat,
        engine_pass,
        lambda: raw_pass(args, config, next(raws), args.repeat + 1),
        litert_models_pass(args.source, config, args.warmup),
    )
    result = {"source": args.source, "default_engine": config.landmarks.engine, **result}
    print(json.dumps(result) if args.json else "\n".join(format_engines(result)))
    return 0


def pipeline_pass(
    args: argparse.Namespace,
    config: Config,
    sinks: list[Any],
    timings: StageTimings,
) -> PassResult:
    """One pass of the loop as fast as it goes, built by `build_run` with a fresh detector
    (model start-up not timed) and no outputs but `sinks`."""
    from roadgaze.benchmark import ThroughputProbe
    from roadgaze.pipeline import RunOptions, build_run

    throughput = ThroughputProbe(args.warmup)
    options = RunOptions(args.source, command="bench", quiet=True)
    source = open_bench_source(args, config)
    with build_run(config, options, source=source, sinks=[*sinks, throughput]) as run:
        log.info("pipeline pass over %s", args.source)
        summary = run.run(timings=timings)
        engine = getattr(run.pipeline.detector, "engine", None)
    return PassResult(
        summary,
        throughput.fps,
        throughput.cpu_ms_per_frame,
        throughput.median_interval_ms,
        engine,
    )


@dataclass(frozen=True, slots=True)
class LatencyPass:
    """The latency pass: capture to delivery, and the same frames' landmark stage."""

    latency: LatencyResult
    stages: dict[str, StageStats]
    """This pass's per-stage times (the first `--warmup` frames left out)."""

    @property
    def landmarks(self) -> StageStats | None:
        return self.stages.get("landmarks")


def latency_pass(args: argparse.Namespace, config: Config) -> LatencyPass:
    """One pass that publishes every frame on loopback Zenoh to a subscriber, with frames coming
    at the video's own frame rate as a camera delivers them (a camera: at its own rate). A pass
    as fast as possible would measure how long a frame waits for the cores, not the live path."""
    from roadgaze.benchmark import measure_latency
    from roadgaze.pipeline import StageTimings

    timings = StageTimings(skip_first=args.warmup)
    with measure_latency(config, args.source, open_bench_source(args, config)) as rig:
        log.info("pipeline pass over %s at its frame rate", args.source)
        published = rig.run.run(timings=timings, realtime=True).frames
        rig.probe.wait_for_count(published, 5.0)
        latency = rig.probe.result(published, skip_first=args.warmup)
    return LatencyPass(latency, timings.stats())


def recording_cost(args: argparse.Namespace, config: Config) -> dict[str, Any]:
    """`--record`: the recording passes (`roadgaze.benchmark.recording`)."""
    from roadgaze.benchmark.recording import recording_cost as cost

    def run_pass(sinks: Sequence[Any], timings: StageTimings) -> tuple[RunSummary, float | None]:
        result = pipeline_pass(args, config, list(sinks), timings)
        return result.summary, result.cpu_ms_per_frame

    return cost(run_pass, config, args.source, args.repeat, args.warmup)


def _round(value: float | None, digits: int) -> float | None:
    """`value` rounded; None (JSON null) for None, NaN or infinity."""
    return None if value is None or not math.isfinite(value) else round(value, digits)


def bench_result(
    source: str,
    passes: list[PassResult],
    timings: StageTimings,
    raw_passes: list[RawResult],
    latency_run: LatencyPass | None,
) -> dict[str, Any]:
    """The JSON object `bench --json` prints (the keys of earlier versions kept)."""
    stages = timings.stats()
    frames = sum(p.summary.frames for p in passes)
    wall_s = sum(p.summary.wall_s for p in passes)
    with_face = sum(p.summary.frames_with_face for p in passes)
    total, landmarks = stages.get("total"), stages.get("landmarks")
    overhead = total.median_ms / landmarks.median_ms if total and landmarks else math.nan
    pipeline_fps = _median([p.fps for p in passes])
    cpu_ms = _median([p.cpu_ms_per_frame for p in passes])
    interval_ms = _median([p.median_interval_ms for p in passes])
    result: dict[str, Any] = {
        "source": source,
        "frames": frames,
        "frames_timed": timings.count,
        "fps": round(frames / wall_s, 2) if wall_s > 0 else 0.0,
        "overhead_ratio": round(overhead, 4),
        "stages": {
            stage: {"median_ms": round(stats.median_ms, 3), "p99_ms": round(stats.p99_ms, 3)}
            for stage, stats in stages.items()
        },
        "face_rate": round(with_face / frames, 4) if frames else 0,
        "passes": len(passes),
        "pipeline_fps": _round(pipeline_fps, 2),
        "cpu_ms_per_frame": _round(cpu_ms, 3),
        "raw_mediapipe_fps": None,
        "ratio_to_raw": None,
    }
    raw = sum(raw_passes[1:], raw_passes[0]) if raw_passes else None
    if raw is not None and raw.frames_timed:
        # Each pipeline pass against the mean of the raw passes just before and after it.
        ratios = [
            p.fps / (0.5 * (before.fps + after.fps))
            for p, before, after in zip(passes, raw_passes, raw_passes[1:], strict=False)
            if p.fps is not None and before.fps > 0 and after.fps > 0
        ]
        result["raw_mediapipe_fps"] = round(raw.fps, 2)
        result["ratio_to_raw"] = _round(_median(ratios), 4)
        result["raw_mediapipe"] = {
            "frames_timed": raw.frames_timed,
            "median_ms": round(raw.percentile_ms(50), 3),
            "p99_ms": round(raw.percentile_ms(99), 3),
            "cpu_ms_per_frame": round(raw.cpu_ms_per_frame, 3),
            "passes_fps": [round(fps, 2) for fps in raw.passes_fps],
            "pipeline_passes_fps": [_round(p.fps, 2) for p in passes],
            "ratios": [round(ratio, 4) for ratio in ratios],
            "cpu_ratio_to_raw": None if not cpu_ms else round(raw.cpu_ms_per_frame / cpu_ms, 4),
            "median_ratio_to_raw": None
            if not interval_ms
            else round(raw.percentile_ms(50) / interval_ms, 4),
        }
    if latency_run is not None:
        latency, pass_landmarks = latency_run.latency, latency_run.landmarks
        target_ms = None if pass_landmarks is None else pass_landmarks.p99_ms + LATENCY_MARGIN_MS
        result["latency"] = {
            "paced": True,
            "stages": {
                stage: {"median_ms": round(stats.median_ms, 3), "p99_ms": round(stats.p99_ms, 3)}
                for stage, stats in latency_run.stages.items()
            },
            "landmarks_p50_ms": None
            if pass_landmarks is None
            else _round(pass_landmarks.median_ms, 3),
            "landmarks_p99_ms": None
            if pass_landmarks is None
            else _round(pass_landmarks.p99_ms, 3),
            "published": latency.published,
            "received": latency.received,
            "p50_ms": _round(latency.p50_ms, 3),
            "p99_ms": _round(latency.p99_ms, 3),
            "max_ms": _round(latency.max_ms, 3),
            "to_publish_p50_ms": _round(latency.to_publish_p50_ms, 3),
            "to_publish_p99_ms": _round(latency.to_publish_p99_ms, 3),
            "delivery_p50_ms": _round(latency.delivery_p50_ms, 3),
            "delivery_p99_ms": _round(latency.delivery_p99_ms, 3),
            "target_p99_ms": _round(target_ms, 3),
            "meets_target": None if target_ms is None else bool(latency.p99_ms <= target_ms),
        }
    return result


def _median(values: Sequence[float | None]) -> float | None:
    known = [value for value in values if value is not None]
    return float(statistics.median(known)) if known else None
