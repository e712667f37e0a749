"""`roadgaze replay VIDEO [--out frames.jsonl]`: the pipeline over a recording, a record per frame.

`add_arguments` declares the options, `run_options` turns them into the run's options, and
`run` has `roadgaze.pipeline.build_run` build the run (source, detector, bus, writers), runs the
loop and reports. Every sink reads the frame record, so a new output is one option and one sink
(in `roadgaze.pipeline.sinks`), in any order.
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roadgaze.commands.options import (
    add_speed_options,
    add_zenoh_options,
    common_options,
    with_zenoh_args,
)
from roadgaze.config import Config
from roadgaze.logs import log_written
from roadgaze.types import Alert, Frame, FrameRecord

if TYPE_CHECKING:
    from roadgaze.pipeline import RunOptions, RunSummary

log = logging.getLogger("roadgaze.replay")


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "replay",
        parents=[common_options()],
        help="run the pose pipeline over a video and write one record per frame",
        description="Run capture -> landmarks -> yaw, pitch, roll -> smoother -> monitor (zones) "
        "over a video file (or image folder, or camera) and write one JSON object per frame, to "
        "stdout unless --out names a file. The records are written line by line; at the normal "
        "end the files (not stdout) are rewritten once with the offline (RTS) yaw_offline_deg and "
        "pitch_offline_deg filled (alerts stay computed from the causal estimate). A progress bar "
        "with fps and ETA, the log (each alert once) and a closing summary go to stderr.",
    )
    add_arguments(parser)
    parser.set_defaults(handler=run)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "source", metavar="VIDEO", help="video file, image folder, /dev/videoN or camera index"
    )
    parser.add_argument(
        "--out",
        metavar="FILE",
        help="JSON-lines file, one object per frame (default, or '-': stdout)",
    )
    parser.add_argument("--csv", type=Path, metavar="FILE", help="the same records as CSV")
    parser.add_argument(
        "--annotate",
        type=Path,
        metavar="FILE",
        help="write the video with face boundaries, centre line, yaw gauge and state (.mp4)",
    )
    parser.add_argument(
        "--plot", type=Path, metavar="FILE", help="PNG of raw and smoothed yaw over time"
    )
    parser.add_argument(
        "--mcap",
        type=Path,
        metavar="FILE",
        help="MCAP recording for Foxglove: camera frames, annotations, records, alerts, state "
        "and logs ([record] settings; docs/foxglove.md; needs roadgaze[foxglove])",
    )
    parser.add_argument(
        "--realtime",
        action="store_true",
        help="pace the replay at the source's own rate (default: as fast as possible)",
    )
    parser.add_argument("--max-frames", type=int, metavar="N", help="stop after N frames")
    parser.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar on stderr (none either when the records go to a terminal)",
    )
    parser.add_argument(
        "--publish",
        action="store_true",
        help="publish yaw, alerts, liveliness and state on Zenoh, stamped with the video's time "
        "(exit 4 when some alerts never reached the bus, each named)",
    )
    add_speed_options(parser)
    add_zenoh_options(parser)


class ReplayStats:
    """Counts faces, the range of raw and smoothed yaw and the alerts, for the closing summary."""

    def __init__(self) -> None:
        self.frames = 0
        self.faces = 0
        self.raw_min_deg = math.inf
        self.raw_max_deg = -math.inf
        self.smoothed_min_deg = math.inf
        self.smoothed_max_deg = -math.inf
        self.alerts = 0

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        sample = record.sample
        self.frames += 1
        self.faces += sample.face
        if sample.yaw_raw_deg is not None:
            self.raw_min_deg = min(self.raw_min_deg, sample.yaw_raw_deg)
            self.raw_max_deg = max(self.raw_max_deg, sample.yaw_raw_deg)
        if sample.yaw_deg is not None:
            self.smoothed_min_deg = min(self.smoothed_min_deg, sample.yaw_deg)
            self.smoothed_max_deg = max(self.smoothed_max_deg, sample.yaw_deg)
        self.alerts += len(record.alerts)

    def on_alert(self, alert: Alert) -> None:
        self.alerts += 1

    def close(self) -> None:
        return None

    def describe(self) -> str:
        rate = 100.0 * self.faces / self.frames if self.frames else 0.0
        text = f"{self.frames} frames, face in {self.faces} ({rate:.0f}%)"
        if self.raw_min_deg <= self.raw_max_deg:
            text += f", raw yaw {self.raw_min_deg:+.1f}..{self.raw_max_deg:+.1f} deg"
        if self.smoothed_min_deg <= self.smoothed_max_deg:
            text += f", smoothed {self.smoothed_min_deg:+.1f}..{self.smoothed_max_deg:+.1f} deg"
        return text


def report(args: argparse.Namespace, summary: RunSummary, stats: ReplayStats) -> None:
    """The closing lines on stderr: the summary, the source's problems, the files written (each
    alert was logged once, when it was raised)."""
    alerts = stats.alerts
    log.info(
        "replay %s: %s; %d alert%s; %.1f fps",
        args.source,
        stats.describe(),
        alerts,
        "" if alerts == 1 else "s",
        summary.fps,
    )
    status = summary.source_status
    if status.message:
        log.warning("replay %s: %s", args.source, status.message)
    if status.frames_dropped:
        log.warning("replay %s: %d frames dropped", args.source, status.frames_dropped)
    for name in ("out", "csv", "plot", "annotate", "mcap"):
        value = getattr(args, name)
        if value is not None and value != "-":
            log_written(value)


def run_options(args: argparse.Namespace) -> RunOptions:
    """The run the options ask for (`roadgaze.pipeline.build_run`)."""
    from roadgaze.pipeline import RunOptions

    to_stdout = args.out in (None, "-")
    records_on_terminal = to_stdout and sys.stdout.isatty()
    # On a terminal the records show the progress.
    with_bar = not args.no_progress and not records_on_terminal
    return RunOptions(
        args.source,
        command="replay",
        publish=args.publish,
        speed_track=args.speed_track,
        speed_kmh=args.speed_kmh,
        track_beside=True,
        records="-" if to_stdout else args.out,
        csv=args.csv,
        plot=args.plot,
        annotate=args.annotate,
        mcap=args.mcap,
        progress="replay" if with_bar else None,
        max_frames=args.max_frames,
        realtime=args.realtime,
        inputs={"--config": args.config},
    )


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.errors import ConfigError
    from roadgaze.pipeline import EXIT_UNDELIVERED, build_run
    from roadgaze.service.signals import sigterm_as_interrupt

    if args.max_frames is not None and args.max_frames < 1:
        raise ConfigError(f"--max-frames must be at least 1, found {args.max_frames}")
    if args.mcap is not None:
        from roadgaze.outputs.foxglove import require_foxglove

        require_foxglove("--mcap")
    config = with_zenoh_args(config, args)
    stats = ReplayStats()
    with sigterm_as_interrupt(), build_run(config, run_options(args), sinks=(stats,)) as replay:
        summary = replay.run(realtime=args.realtime, max_frames=args.max_frames)
    fill_offline(args, config)
    report(args, summary, stats)
    if replay.undelivered():
        return EXIT_UNDELIVERED  # the warning naming them was logged when the link closed
    return 0


def fill_offline(args: argparse.Namespace, config: Config) -> None:
    """At the normal end of a replay: the offline columns of the written record files (not of
    stdout), each file rewritten atomically; a file that cannot be done keeps its nulls."""
    from roadgaze.errors import RoadgazeError
    from roadgaze.outputs import fill_offline_columns

    # Each file in the format its option writes, whatever its name (`--out rec.csv` is JSON).
    paths = [(Path(args.out), False)] if args.out is not None and args.out != "-" else []
    paths += [(args.csv, True)] if args.csv is not None else []
    for path, csv_format in paths:
        try:
            fill_offline_columns(path, config.smoothing, csv_format)
        except RoadgazeError as exc:
            log.warning("replay %s: offline columns left null: %s", args.source, exc)
            continue
        log.debug("replay %s: offline columns filled in %s", args.source, path)
