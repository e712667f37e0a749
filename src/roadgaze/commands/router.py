"""`roadgaze router`: a Zenoh router in this process, for machines without `zenohd`."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from roadgaze.commands.options import common_options
from roadgaze.config import Config


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "router",
        parents=[common_options()],
        help="run a Zenoh router (for machines without zenohd)",
        description="A Zenoh router in this process: daemons, speed providers and listeners in "
        "client mode connect to it. It logs the endpoints it listens on and every session that "
        "connects or disconnects. Default: tcp/127.0.0.1:7447 (loopback only), multicast "
        "scouting off. With --zenoh-config it runs a full Zenoh router configuration (TLS "
        "endpoints, mutual TLS, access control, e.g. the router file of `roadgaze security "
        "init`); --listen replaces the file's endpoints. SIGINT, SIGTERM and SIGHUP stop it "
        "(exit 0); an endpoint it cannot listen on or a bad file is one line and exit 2.",
    )
    parser.add_argument(
        "--listen",
        action="append",
        metavar="ENDPOINT",
        help="endpoint to listen on, e.g. tcp/0.0.0.0:7447 or tls/0.0.0.0:7447 (repeatable; "
        "default: the file's, else tcp/127.0.0.1:7447)",
    )
    parser.add_argument(
        "--zenoh-config",
        type=Path,
        metavar="FILE",
        help="a Zenoh router configuration file (JSON5, JSON or YAML)",
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.service.signals import StopFlag, signal_handlers

    stop = StopFlag()
    # Before zenoh is imported: a stop asked for during start-up is kept.
    with signal_handlers(stop, doing="stopping the router", log_name="roadgaze.router"):
        from roadgaze.transport.router import Router, RouterSettings, log_refused_handshakes

        log_refused_handshakes()
        settings = RouterSettings(listen=tuple(args.listen or ()), config_file=args.zenoh_config)
        with Router(settings):
            while not stop.wait(1.0):
                pass
    return 0
