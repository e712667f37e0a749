"""`roadgaze batch INPUT --out DIR`: replay a fleet's drives as Parquet, resumable, with a report.

Exit status: 0 when every drive succeeded, 3 when some failed (listed on stderr), 2 for bad
arguments (one line on stderr), 130 when stopped by Ctrl-C or SIGTERM (run it again to go on).
"""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roadgaze.commands.options import add_speed_options, common_options
from roadgaze.config import Config
from roadgaze.errors import ConfigError
from roadgaze.logs import log_written

if TYPE_CHECKING:
    from roadgaze.fleet import BatchOutcome

log = logging.getLogger(__name__)

EXIT_SOME_FAILED = 3
EXIT_INTERRUPTED = 130
FAILED_LISTED = 20
"""Failed drives named on stderr; the rest are in summary.parquet and report.html."""


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "batch",
        parents=[common_options()],
        help="replay many recorded drives to Parquet, resumable, with a fleet summary and report",
        description="Run the pipeline over every video under a folder (searched recursively) or "
        "listed in a CSV manifest (columns: path, and optionally drive_id, driver_id, "
        "vehicle_id, start_time, speed_track). A drive's vehicle speed comes from its speed_track, "
        "else from <stem>.speed.csv or .speed.parquet beside its video (t_s,kmh), else it is "
        "unknown (taken as moving); --speed-kmh sets one for all. Writes "
        "DIR/frames/<drive_id>.parquet, "
        "DIR/alerts/<drive_id>.parquet, DIR/summary.parquet and DIR/report.html. A re-run skips "
        "drives whose outputs match their input and configuration. Exit status 0 when all "
        "drives succeeded, 3 when some failed, 2 for bad arguments, 130 when stopped.",
    )
    parser.add_argument(
        "input", type=Path, metavar="INPUT", help="folder of videos or CSV manifest"
    )
    parser.add_argument("--out", type=Path, required=True, metavar="DIR", help="output folder")
    parser.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="local: worker processes (default: one per core); ray: drives in flight "
        "(default: the cluster's CPUs)",
    )
    parser.add_argument(
        "--engine", choices=["local", "ray"], default="local", help="where drives run"
    )
    parser.add_argument(
        "--ray-address",
        metavar="ADDR",
        help="Ray cluster to use (e.g. 10.0.0.5:6379, ray://head:10001 or auto); default "
        "RAY_ADDRESS, else a local Ray instance",
    )
    parser.add_argument(
        "--ray-timeout",
        type=float,
        default=30.0,
        metavar="S",
        help="fail (exit 2, naming the address) when no Ray cluster answers at the address in S "
        "seconds (default 30)",
    )
    parser.add_argument(
        "--hash",
        action="store_true",
        help="recognise unchanged inputs by their SHA-256 instead of size and modification time",
    )
    parser.add_argument(
        "--retries",
        type=int,
        default=2,
        metavar="N",
        help="tries again when a worker process dies on a drive (default 2)",
    )
    parser.add_argument("--json", action="store_true", help="print the run's figures as JSON")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    add_speed_options(parser, track=False)
    parser.set_defaults(handler=run)


FLEET_MISSING = (
    "roadgaze batch writes Parquet and needs pyarrow, which is not installed: "
    "pip install 'roadgaze[fleet]'"
)


def run(args: argparse.Namespace, config: Config) -> int:
    try:
        import pyarrow  # noqa: F401  (only asked whether it is there)
    except ImportError:
        raise ConfigError(FLEET_MISSING) from None
    from roadgaze.fleet import BatchOptions, discover_drives, run_batch

    if args.workers is not None and args.workers < 1:
        raise ConfigError(f"--workers must be at least 1, found {args.workers}")
    if args.retries < 0:
        raise ConfigError(f"--retries must be 0 or more, found {args.retries}")
    if not 0 < args.ray_timeout <= 3600:
        raise ConfigError(f"--ray-timeout must be within 0-3600 s, found {args.ray_timeout:g}")
    if args.speed_kmh is not None:
        from roadgaze.capture.speed_track import recorded_speed

        recorded_speed(None, constant_kmh=args.speed_kmh)  # a bad speed said before any work
    if args.ray_address is not None and args.engine != "ray":
        raise ConfigError("--ray-address needs --engine ray")
    if args.engine == "ray":
        from roadgaze.fleet.executors import import_ray

        import_ray(args.ray_address)  # a missing Ray is a bad argument, said before any work
    drives = discover_drives(args.input)
    out_dir = args.out.resolve()
    if out_dir.is_file():
        raise ConfigError(f"--out {args.out} is a file; pass a folder")
    options = BatchOptions(
        out_dir=out_dir,
        engine=args.engine,
        workers=args.workers,
        ray_address=args.ray_address,
        ray_timeout_s=args.ray_timeout,
        content_hash=args.hash,
        retries=args.retries,
        progress=not args.no_progress,
        speed_kmh=args.speed_kmh,
    )
    outcome = run_batch(drives, config, options)
    report(outcome, out_dir)
    if args.json:
        print(json.dumps(outcome.to_json()), flush=True)
    if outcome.interrupted:
        return EXIT_INTERRUPTED
    return EXIT_SOME_FAILED if outcome.failed else 0


def report(outcome: BatchOutcome, out_dir: Path) -> None:
    """The closing lines on stderr, through the log: counts, pace, failed drives, the outputs."""
    figures = outcome.to_json()
    log.info(
        "batch: %s of %s drives ok (%s processed, %s kept from an earlier run), %s failed; "
        "%s frames in %.1f s = %.1f frames/s on %s with %s worker%s",
        figures["ok"],
        figures["drives"],
        figures["processed"],
        figures["resumed"],
        figures["failed"],
        figures["frames"],
        outcome.wall_s,
        outcome.frames_per_s,
        outcome.engine,
        outcome.workers,
        "" if outcome.workers == 1 else "s",
    )
    if figures["worker_deaths"]:
        log.warning(
            "batch: %s worker process deaths, %s drives tried again (see batch.log)",
            figures["worker_deaths"],
            figures["retries"],
        )
    for result in outcome.failed[:FAILED_LISTED]:
        log.warning("batch: failed %s (%s): %s", result.drive_id, result.path, result.error)
    if len(outcome.failed) > FAILED_LISTED:
        more = len(outcome.failed) - FAILED_LISTED
        log.warning("batch: ... and %s more failed (see the report)", more)
    if outcome.interrupted:
        left = figures["interrupted"] + figures["pending"]
        log.warning(
            "batch: stopped; %s drives not done; run the same command again to continue", left
        )
    log_written(out_dir / "summary.parquet")
    log_written(out_dir / "report.html")
