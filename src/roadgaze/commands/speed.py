"""`roadgaze speed --kmh N | --track CSV`: put a vehicle speed on the bus, for bench tests in a
car without a CAN bus, or on a desk."""

from __future__ import annotations

import argparse
import logging
import math
import time
from pathlib import Path
from typing import Any

from roadgaze.commands.options import check_seconds, common_options, zenoh_config_from_args
from roadgaze.config import Config

log = logging.getLogger("roadgaze.speed")


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "speed",
        parents=[common_options()],
        help="publish a constant speed or a CSV speed track on the speed key at 10 Hz",
        description='Publish {"kmh": N} on the vehicle\'s speed key (zenoh.speed_key, '
        "vehicle/ID/speed) 10 times a second, as a CAN gateway would: a constant (--kmh) until "
        "SIGINT or SIGTERM, or a track (--track CSV with columns t_s,kmh, linear between rows) "
        "to its end (--loop: again and again). It connects as a client to the rendezvous "
        "(tcp/127.0.0.1:7447) or --zenoh-connect, and waits for a router or daemon there; on a "
        "secured bus pass the speed provider's file of `roadgaze security init` with "
        "--zenoh-config. The daemon takes a speed older than 2 s as unknown (moving).",
    )
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--kmh", type=float, metavar="N", help="a constant speed in km/h (0-400)")
    what.add_argument("--track", type=Path, metavar="CSV", help="a speed track: t_s,kmh rows")
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


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.errors import ConfigError, TransportError
    from roadgaze.service.signals import StopFlag, signal_handlers
    from roadgaze.transport import Keys, open_session, plan_session
    from roadgaze.transport.speed_track import (
        SPEED_RATE_HZ,
        SpeedTrack,
        publish_track,
        read_speed_track,
    )

    check_seconds("--duration", args.duration)
    track = SpeedTrack.constant(args.kmh) if args.track is None else read_speed_track(args.track)
    zconf = zenoh_config_from_args(config.zenoh, args)
    key = Keys.from_config(zconf).speed
    if key is None:
        raise ConfigError("zenoh.speed_key is empty: there is no speed key to publish on")
    plan = plan_session(zconf, "consumer")
    stop = StopFlag()
    with signal_handlers(stop, doing="stopping"):
        log.info("roadgaze speed: %s; key %s", plan.describe(), key)
        try:
            session = open_session(plan, wait_s=math.inf, stopped=stop.is_set)
        except TransportError:
            if stop.is_set():
                return 0
            raise
        what = f"{track.kmh[0]:g} km/h" if args.track is None else f"the track {args.track}"
        log.info("publishing %s on %s at %g Hz", what, key, SPEED_RATE_HZ)
        count, last_kmh = 0, math.nan
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
                count, last_kmh = count + 1, kmh
        finally:
            session.close()
    log.info("roadgaze speed: %d speeds published, the last %g km/h", count, last_kmh)
    return 0
