"""`roadgaze run`: the monitoring daemon (camera or file -> yaw -> monitor -> Zenoh)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from roadgaze.commands.options import add_zenoh_options, common_options, with_zenoh_args
from roadgaze.config import Config


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "run",
        parents=[common_options()],
        help="run the monitoring daemon and publish yaw, alerts, liveliness and state on Zenoh",
        description="Read a camera (/dev/videoN or an index) or a video file (paced at its own "
        "rate), estimate head yaw per frame, run the inattention monitor and publish on Zenoh "
        "under vehicle/<id>/dms/. SIGINT/SIGTERM/SIGHUP finish the current frame, publish a "
        "final state, undeclare and exit 0 (a second signal: exit 1 at once). Exit 4 when some "
        "alerts never reached the bus (no link before the end, after waiting "
        "zenoh.delivery_wait_s; each is named). A lost camera and an unreachable Zenoh peer "
        "are retried and reported in the state (degraded), never fatal.",
    )
    parser.add_argument(
        "--source", required=True, metavar="FILE|/dev/videoN|N", help="video file or camera"
    )
    parser.add_argument(
        "--no-realtime",
        action="store_true",
        help="process a file as fast as possible instead of at its own frame rate",
    )
    parser.add_argument(
        "--record",
        type=Path,
        metavar="DIR",
        help="record MCAP segments into DIR, rotated by size and age, the folder kept under "
        "record.max_disk_mb (camera frames only with record.images=true; docs/foxglove.md)",
    )
    parser.add_argument(
        "--foxglove",
        metavar="[HOST:]PORT",
        help="serve the live view to the Foxglove app on PORT (loopback unless HOST is given: "
        "the stream shows the driver's face)",
    )
    add_zenoh_options(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.service.signals import StopFlag, signal_handlers

    if args.record is not None or args.foxglove is not None:
        from roadgaze.outputs.foxglove import require_foxglove

        require_foxglove("--record" if args.record is not None else "--foxglove")
    stop = StopFlag()
    # Handlers before the heavy imports: as PID 1 of a container, a SIGTERM arriving while
    # they load would otherwise be ignored (PID 1 has no default action).
    with signal_handlers(stop):
        from roadgaze.service.daemon import run_daemon

        return run_daemon(
            with_zenoh_args(config, args),
            args.source,
            stop=stop,
            realtime=not args.no_realtime,
            handle_signals=False,
            record_dir=args.record,
            foxglove=args.foxglove,
        )
