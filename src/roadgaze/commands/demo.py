"""`roadgaze demo`: the whole service on a synthetic drive, no camera or video needed."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import Any

from roadgaze.commands.options import common_options
from roadgaze.config import Config

log = logging.getLogger("roadgaze.demo")


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "demo",
        parents=[common_options()],
        help="see it work: a synthetic drive through the whole service, alerts over Zenoh",
        description="Render a short drive of a real face (road, a long look into the lap, a few "
        "short glances, back to the road), run the full service over it (landmarks, full-range "
        "yaw, pitch, smoother, monitor with zones, Zenoh publisher on 127.0.0.1) with a Zenoh "
        "subscriber in the same "
        "run, print each alert as the subscriber receives it, and write drive.mp4, truth.csv, "
        "frames.jsonl, alerts.jsonl, yaw.png and annotated.mp4 into the output folder. The alerts "
        "received and the summary go to stdout, progress and the log to stderr.",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("roadgaze-demo"),
        metavar="DIR",
        help="output folder (default ./roadgaze-demo/)",
    )
    parser.add_argument(
        "--photo", type=Path, help="portrait with one frontal face (default: skimage's astronaut)"
    )
    parser.add_argument(
        "--timeline",
        metavar="SPEC",
        help="the drive as YAW[/PITCH]:SECONDS keyframes (default: see docs/synth.md)",
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    """Alerts as the subscriber receives them and the closing summary go to stdout; progress,
    the log and the files written to stderr. The service's own log line per alert is left out:
    the subscriber's line tells the same event."""
    from roadgaze.demo import format_alert, run_demo
    from roadgaze.logs import log_written, records_dropped
    from roadgaze.synth import parse_timeline

    timeline = None if args.timeline is None else parse_timeline(args.timeline)

    def progress(text: str) -> None:
        log.info("demo: %s", text)

    def alert(message: dict[str, Any]) -> None:
        print(f"demo: {format_alert(message)}", flush=True)

    with records_dropped("roadgaze.demo", lambda record: hasattr(record, "alert")):
        result = run_demo(
            args.out,
            config,
            photo=args.photo,
            timeline=timeline,
            on_alert=alert,
            on_progress=progress,
        )
    print(
        f"demo: {result.frames} frames, face in {result.frames_with_face}, "
        f"{result.alerts_raised} alerts raised, {len(result.alerts_received)} received by the "
        f"subscriber; smoothed yaw vs truth MAE {result.yaw_mae_deg:.1f} deg"
    )
    print(
        f"demo: render {result.render_s:.1f} s, service {result.service_s:.1f} s, "
        f"total {result.total_s:.1f} s"
    )
    for path in result.files:
        log_written(path)
    if len(result.alerts_received) != result.alerts_raised:
        log.error("demo: the subscriber missed some alerts (see the log above)")
        return 1
    return 0
