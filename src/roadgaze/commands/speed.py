"""`roadgaze speed --kmh N | --track FILE`: put a vehicle speed on the bus, for bench tests in a
car without a CAN bus, or on a desk."""

from __future__ import annotations

import argparse
import logging
import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from roadgaze.commands.options import check_seconds, common_options, zenoh_config_from_args
from roadgaze.config import Config

if TYPE_CHECKING:
    from roadgaze.speed import SpeedTrack

log = logging.getLogger("roadgaze.speed")


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "speed",
        parents=[common_options()],
        help="publish a constant speed or a speed track on the speed key at 10 Hz",
        description='Publish {"kmh": N} on the vehicle\'s speed key (zenoh.speed_key, '
        "vehicle/ID/speed) 10 times a second, as a CAN gateway would: a constant (--kmh) until "
        "SIGINT or SIGTERM, or a track (--track, CSV or Parquet with columns t_s,kmh) to its end "
        "(--loop: again and again). A track is held exactly as `replay --speed-track` holds it "
        "(each sample for zenoh.speed_timeout_s at most, never interpolated) and put also at "
        'each instant it changes; an unknown speed is put as {"kmh": null}. It connects as a '
        "client to the rendezvous (tcp/127.0.0.1:7447) or --zenoh-connect, and waits for a "
        "router or daemon there; on a secured bus pass the speed provider's file of `roadgaze "
        "security init` with --zenoh-config. The daemon takes a speed older than "
        "zenoh.speed_timeout_s (2 s) as unknown (moving).",
    )
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--kmh", type=float, metavar="N", help="a constant speed in km/h (0-400)")
    what.add_argument(
        "--track", type=Path, metavar="FILE", help="a speed track: CSV or Parquet, t_s,kmh rows"
    )
    parser.add_argument("--loop", action="store_true", help="repeat the track")
    parser.add_argument(
        "--duration", type=float, metavar="S", help="stop after S seconds (default: never)"
    )
    group = parser.add_argument_group("zenoh")
    group.add_argument("--vehicle-id", metavar="ID", help="vehicle id in the speed key")
    group.add_argument(
        "--zenoh-config",
        type=Path,
        metavar="FILE",
        help="a Zenoh configuration file, e.g. the speed provider's of `roadgaze security init`",
    )
    group.add_argument(
        "--zenoh-connect",
        action="append",
        metavar="ENDPOINT",
        help="endpoint to connect to, e.g. tcp/127.0.0.1:7447 (repeatable)",
    )
    parser.set_defaults(handler=run)


def speed_to_publish(args: argparse.Namespace, config: Config) -> SpeedTrack:
    """The constant (`--kmh`, held for ever) or the track (`--track`, read and held exactly as
    `replay` reads it: `roadgaze.speed`)."""
    from roadgaze.speed import SpeedTrack, read_speed_track

    if args.track is None:
        return SpeedTrack.constant(args.kmh)
    return read_speed_track(
        args.track,
        config.zenoh.speed_timeout_s,
        max_rows=config.capture.speed_track_max_rows,
    )


class Totals:
    """What was put, for the closing line."""

    def __init__(self) -> None:
        self.count = 0
        self.unknown = 0
        self.last_kmh: float | None = None
        self.started_s = time.monotonic()

    def add(self, kmh: float | None) -> None:
        self.count += 1
        self.unknown += kmh is None
        self.last_kmh = kmh

    def describe(self) -> str:
        if not self.count:
            return "no speed published (stopped before a link to the bus)"
        last = "unknown" if self.last_kmh is None else f"{self.last_kmh:g} km/h"
        unknown = f"; {self.unknown} unknown, put as null" if self.unknown else ""
        elapsed_s = time.monotonic() - self.started_s
        return f"{self.count} speeds published, the last {last} ({elapsed_s:.1f} s{unknown})"


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.errors import ConfigError, TransportError
    from roadgaze.service.signals import StopFlag, signal_handlers
    from roadgaze.transport import Keys, open_session, plan_session
    from roadgaze.transport.speed import SPEED_RATE_HZ, publish_track

    check_seconds("--duration", args.duration)
    track = speed_to_publish(args, config)
    zconf = zenoh_config_from_args(config.zenoh, args)
    key = Keys.from_config(zconf).speed
    if key is None:
        raise ConfigError("zenoh.speed_key is empty: there is no speed key to publish on")
    plan = plan_session(zconf, "consumer")
    stop = StopFlag()
    totals = Totals()
    with signal_handlers(stop, doing="stopping", log_name=log.name):
        log.info("roadgaze speed: %s; key %s", plan.describe(), key)
        try:
            session = open_session(plan, wait_s=math.inf, stopped=stop.is_set)
        except TransportError:
            if not stop.is_set():
                raise
            session = None
        if session is not None:
            what = track.name if args.track is None else track.describe()
            log.info("publishing %s on %s at %g Hz", what, key, SPEED_RATE_HZ)
            totals.started_s = time.monotonic()
            try:
                publisher = session.declare_publisher(key)
                for kmh in publish_track(
                    track,
                    publisher.put,
                    stop.wait,
                    time.monotonic,
                    loop=args.loop,
                    duration_s=args.duration,
                ):
                    totals.add(kmh)
            finally:
                session.close()
    log.info("roadgaze speed: %s", totals.describe())
    return 0
