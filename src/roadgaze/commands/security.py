"""`roadgaze security init DIR --vehicle-id ID`: certificates and Zenoh files for a secure bus."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from roadgaze.commands.options import common_options
from roadgaze.config import Config


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "security",
        help="write a CA, certificates and Zenoh configs with access control (mutual TLS)",
        description="Security tooling for the vehicle bus (docs/security.md).",
    )
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    init = actions.add_parser(
        "init",
        parents=[common_options()],
        help="write the CA, certificates and Zenoh configuration files of one vehicle",
        description="Write into DIR a certificate authority, one certificate per role and the "
        "Zenoh configuration files of the router (mutual TLS only, access control by "
        "certificate name, size and rate limits), the daemon, the speed provider and each "
        "consumer. Only the daemon may publish under the vehicle's dms keys and the COVESA VSS "
        "keys (Vehicle/**, under zenoh.vss_prefix), only the speed provider may publish its "
        "speed, consumers may only subscribe and query. Use them with "
        "`roadgaze router --zenoh-config DIR/router/zenoh.json5` (or `zenohd -c` the same "
        "file), `roadgaze run --zenoh-config "
        "DIR/daemon/zenoh.json5` and `roadgaze listen --zenoh-config "
        "DIR/consumer-NAME/zenoh.json5 --vehicle-id ID`.",
    )
    init.add_argument("dir", type=Path, metavar="DIR", help="an empty or new folder")
    init.add_argument("--vehicle-id", required=True, metavar="ID", help="the vehicle's id")
    init.add_argument(
        "--consumer",
        action="append",
        metavar="NAME",
        help="a consumer allowed to subscribe and query (repeatable; default: one named fcw)",
    )
    init.add_argument(
        "--endpoint",
        default="tls/127.0.0.1:7447",
        metavar="tls/HOST:PORT",
        help="where the roles reach the router; HOST goes into the router's certificate "
        "(default tls/127.0.0.1:7447)",
    )
    init.add_argument(
        "--listen",
        metavar="tls/HOST:PORT",
        help="where the router listens (default: --endpoint; tls/0.0.0.0:7447 in a container)",
    )
    init.add_argument(
        "--path-root",
        type=Path,
        metavar="DIR",
        help="write file paths as seen where the role folders are mounted (e.g. "
        "/etc/roadgaze/zenoh in a container); default: DIR itself",
    )
    init.add_argument("--force", action="store_true", help="replace the files of a non-empty DIR")
    init.set_defaults(handler=run_init)


def run_init(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.security import init_bundle
    from roadgaze.transport import Keys, vss_key

    keys = Keys.from_config(config.zenoh, args.vehicle_id)
    written = init_bundle(
        args.dir,
        keys,
        args.consumer or ["fcw"],
        endpoint=args.endpoint,
        listen=args.listen,
        path_root=args.path_root,
        force=args.force,
        vss_keys=vss_key("Vehicle.**", config.zenoh.vss_prefix),
    )
    for role, path in written.items():
        print(f"{role:<20} {path}")
    print(f"keep {args.dir / 'ca' / 'ca.key'} off the vehicle: it signs new certificates")
    return 0
