"""`roadgaze estimate IMAGE...`: one JSON object per image with every model's yaw."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from roadgaze.commands.options import common_options
from roadgaze.config import Config


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "estimate",
        parents=[common_options()],
        help="estimate the driver's head yaw in still images (one JSON line per image)",
        description="Run MediaPipe and the five yaw models on each image and print one JSON "
        "object per image: file, face, yaw_deg (the service's, full range by default), models, "
        "pitch_deg, pitch_geometric_deg, zone (neutral 0), mediapipe_yaw_deg, "
        "mediapipe_pitch_deg, x_left, x_right, x_center, roll_deg. Yaw > 0: head turned to the "
        "person's own left; pitch > 0: looking up. An image "
        "that cannot be read gives an object with 'error' and the others are still processed "
        "(exit code 1 if any image could not be read).",
    )
    parser.add_argument("images", nargs="+", type=Path, metavar="IMAGE")
    parser.add_argument(
        "--workers", type=int, default=1, metavar="N", help="worker processes (default 1)"
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.evaluation import estimate_images
    from roadgaze.landmarks.model_store import resolve_model
    from roadgaze.pose.geometry import FaceModelConstants

    constants = FaceModelConstants.from_config(config.geometry)
    model_path = resolve_model(config.model)
    jobs = [(path, str(path)) for path in args.images]
    failures = 0
    for estimate in estimate_images(
        jobs, config.landmarks, model_path, constants, workers=max(1, args.workers), config=config
    ):
        print(json.dumps(estimate.to_json_dict()), flush=True)
        if estimate.error is not None:
            failures += 1
            print(f"roadgaze estimate: {estimate.error}", file=sys.stderr)
    return 1 if failures else 0
