"""`roadgaze doctor`: one screen of what a user needs to know before filing a bug."""

from __future__ import annotations

import argparse
import json
from typing import Any

from roadgaze.commands.options import add_zenoh_options, common_options, with_zenoh_args
from roadgaze.config import Config


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "doctor",
        parents=[common_options()],
        help="check the installation: versions, OpenCV build, EGL, model, Zenoh, cameras",
        description="Check what roadgaze depends on and print one line per check (OK, WARN or "
        "FAIL) with the fix for each problem: roadgaze, Python and package versions; which "
        "OpenCV build cv2 really is and whether a second distribution shares its folder; the "
        "EGL/GLES libraries MediaPipe loads; the model file (path, size, SHA-256) and whether "
        "MediaPipe loads it; whether a Zenoh session opens with the configured settings and the "
        "configured connect endpoints answer; the cameras found. Exit code 1 when a check "
        "fails, 0 otherwise (warnings included).",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    add_zenoh_options(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.doctor import Status, format_checks, run_checks, worst

    checks = run_checks(with_zenoh_args(config, args))
    status = worst(checks)
    if args.json:
        document = {"status": status.value, "checks": [check.to_json_dict() for check in checks]}
        print(json.dumps(document, indent=2))
    else:
        print(format_checks(checks))
    return 1 if status is Status.FAIL else 0
