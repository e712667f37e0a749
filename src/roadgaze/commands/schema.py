"""`roadgaze schema`: print the JSON Schemas of the messages roadgaze publishes on Zenoh."""

from __future__ import annotations

import argparse
import json
from typing import Any

from roadgaze.config import Config

NAMES = ("yaw", "alert", "state", "support")


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "schema",
        help="print the JSON Schemas of the yaw, alert, state and support messages",
        description="Print the JSON Schema (draft 2020-12, from the pydantic models) of the "
        "messages published under vehicle/<id>/dms/: all of them as one object keyed by name, "
        "or the one named.",
    )
    parser.add_argument("name", nargs="?", choices=NAMES, help="only this message's schema")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.transport import json_schemas

    schemas = json_schemas()
    document = schemas[args.name] if args.name else schemas
    print(json.dumps(document, indent=2, sort_keys=True))
    return 0
