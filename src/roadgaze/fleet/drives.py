"""The drives of a batch: every video under a folder, or the rows of a CSV manifest.

A drive is one video with a unique, filesystem-safe `drive_id` (it names the drive's output
files) and optional metadata: who drove (`driver_id`), which vehicle (`vehicle_id`) and when the
recording started (`start_time`, ISO 8601; a time without a zone is taken as UTC). Anything wrong
with the input as a whole (no such folder, no video in it, a malformed manifest) raises
`ConfigError`; a drive whose video is missing or unreadable is not an input error: it fails on
its own when it is processed.
"""

from __future__ import annotations

import hashlib
import os
import re
from collections import Counter
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path

from roadgaze.csv_rows import read_csv_rows
from roadgaze.errors import ConfigError

VIDEO_SUFFIXES = frozenset(
    {".mp4", ".m4v", ".mov", ".avi", ".mkv", ".webm", ".mpg", ".mpeg", ".ts", ".mts", ".wmv"}
    | {".flv", ".gif", ".mcap"}
)
"""File suffixes (any case) taken as drives when a folder is searched (`.mcap`: a recording with a
camera channel, `roadgaze.capture.McapSource`)."""

MANIFEST_COLUMNS = ("path", "drive_id", "driver_id", "vehicle_id", "start_time", "speed_track")
"""The columns a manifest may have; `path` is required, relative paths (`path`, `speed_track`)
are relative to the manifest's folder."""

DRIVE_ID_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,159}$")
"""A drive id: letters, digits, `.`, `_` and `-`, starting with a letter or digit, at most 160
characters (it names files on every common filesystem)."""

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


@dataclass(frozen=True, slots=True)
class Drive:
    """One recorded drive: its video and what is known about it."""

    drive_id: str
    path: Path
    driver_id: str | None = None
    vehicle_id: str | None = None
    start_time: datetime | None = None
    """When the recording started, timezone-aware (UTC when the input gave no zone)."""
    speed_track: Path | None = None
    """The drive's `t_s,kmh` speed track when the manifest names one; else the one beside the
    video, if any (`roadgaze.capture.speed_track`)."""


def discover_drives(input_path: Path) -> tuple[Drive, ...]:
    """The drives of a folder (searched recursively) or of a `.csv` manifest, in input order.

    Raises `ConfigError` when the input is missing, is neither a folder nor a `.csv` file, holds
    no video, or the manifest is malformed (the message names the row).
    """
    input_path = input_path.absolute()
    if input_path.is_dir():
        return drives_in_folder(input_path)
    if input_path.is_file() and input_path.suffix.lower() == ".csv":
        return read_manifest(input_path)
    if not input_path.exists():
        raise ConfigError(f"batch input {input_path} not found; pass a folder or a .csv manifest")
    raise ConfigError(
        f"batch input {input_path} is neither a folder nor a .csv manifest; pass a folder of "
        "videos or a CSV with a 'path' column"
    )


def drives_in_folder(folder: Path) -> tuple[Drive, ...]:
    """Every video under `folder` (hidden files and folders skipped), sorted by relative path,
    with ids derived from the relative paths; raises `ConfigError` when there is none."""
    relative_paths: list[Path] = []
    for root, folders, files in os.walk(folder):
        folders[:] = sorted(name for name in folders if not name.startswith("."))
        relative_root = Path(root).relative_to(folder)
        relative_paths.extend(
            relative_root / name
            for name in files
            if not name.startswith(".") and Path(name).suffix.lower() in VIDEO_SUFFIXES
        )
    if not relative_paths:
        suffixes = " ".join(sorted(VIDEO_SUFFIXES))
        raise ConfigError(f"no video found under {folder} (looked for {suffixes})")
    relative_paths.sort(key=lambda path: path.as_posix())
    ids = derived_drive_ids(relative_paths)
    return tuple(
        Drive(drive_id=drive_id, path=folder / relative)
        for drive_id, relative in zip(ids, relative_paths, strict=True)
    )


def derived_drive_ids(relative_paths: list[Path]) -> list[str]:
    """Stable, unique, filesystem-safe ids for videos named by their paths relative to the input.

    `fleet A/2024-05-01/cab.mp4` -> `fleet_A__2024-05-01__cab`: the suffix is dropped, folders
    are joined with `__` and unsafe characters become `_`. Paths that would share an id (`a.mp4`
    and `a.mkv`) each get a short hash of their relative path appended.
    """
    ids = [_safe_id("__".join((*path.parent.parts, path.stem))) for path in relative_paths]
    counts = Counter(ids)
    return [
        f"{drive_id[:150]}-{hashlib.sha1(path.as_posix().encode()).hexdigest()[:8]}"
        if counts[drive_id] > 1
        else drive_id
        for drive_id, path in zip(ids, relative_paths, strict=True)
    ]


def _safe_id(text: str) -> str:
    safe = _UNSAFE.sub("_", text).strip("._-")[:160]
    return safe if safe and DRIVE_ID_PATTERN.match(safe) else "drive"


def read_manifest(manifest: Path) -> tuple[Drive, ...]:
    """The drives listed in a CSV manifest (header row required, UTF-8, comma-separated).

    Raises `ConfigError` for a missing `path` column, unknown columns, an empty path, a bad or
    duplicate `drive_id`, a `start_time` that is not ISO 8601, or no rows.
    """
    header, rows = read_csv_rows(manifest, ConfigError, "manifest")
    if "path" not in header:
        raise ConfigError(
            f"manifest {manifest} has no 'path' column (found: {', '.join(header) or 'nothing'}); "
            f"columns: {', '.join(MANIFEST_COLUMNS)}"
        )
    unknown = [name for name in header if name not in MANIFEST_COLUMNS]
    if unknown:
        raise ConfigError(
            f"manifest {manifest} has unknown columns {', '.join(unknown)}; "
            f"allowed: {', '.join(MANIFEST_COLUMNS)}"
        )
    if not rows:
        raise ConfigError(f"manifest {manifest} lists no drive")
    base = manifest.parent
    drives: list[Drive] = []
    for line, raw in enumerate(rows, start=2):
        row = {name.strip(): (value or "").strip() for name, value in raw.items() if name}
        if None in raw:
            raise ConfigError(f"manifest {manifest} line {line}: more cells than columns")
        drives.append(_drive_of_row(row, base, f"manifest {manifest} line {line}"))
    ids = derived_drive_ids([_relative_or_absolute(d.path, base) for d in drives])
    drives = [
        d if d.drive_id else replace(d, drive_id=derived)
        for d, derived in zip(drives, ids, strict=True)
    ]
    duplicates = sorted(name for name, n in Counter(d.drive_id for d in drives).items() if n > 1)
    if duplicates:
        raise ConfigError(
            f"manifest {manifest}: drive ids must be unique; repeated: {', '.join(duplicates[:5])}"
        )
    return tuple(drives)


def _relative_or_absolute(path: Path, base: Path) -> Path:
    try:
        return path.relative_to(base)
    except ValueError:
        return Path(*path.parts[1:]) if path.is_absolute() else path


def _drive_of_row(row: dict[str, str], base: Path, where: str) -> Drive:
    if not row.get("path"):
        raise ConfigError(f"{where}: empty 'path'")
    path = Path(row["path"]).expanduser()
    drive_id = row.get("drive_id", "")
    if drive_id and not DRIVE_ID_PATTERN.match(drive_id):
        raise ConfigError(
            f"{where}: drive_id {drive_id!r} is not filesystem-safe; use letters, digits, "
            "'.', '_' and '-' (starting with a letter or digit, at most 160 characters)"
        )
    track = Path(row["speed_track"]).expanduser() if row.get("speed_track") else None
    return Drive(
        drive_id=drive_id,
        path=path if path.is_absolute() else base / path,
        speed_track=None if track is None else track if track.is_absolute() else base / track,
        driver_id=row.get("driver_id") or None,
        vehicle_id=row.get("vehicle_id") or None,
        start_time=parse_start_time(row.get("start_time", ""), where),
    )


def parse_start_time(text: str, where: str) -> datetime | None:
    """An ISO 8601 date and time as an aware datetime (UTC when it has no zone); None for ''."""
    if not text:
        return None
    try:
        value = datetime.fromisoformat(text)
    except ValueError:
        raise ConfigError(
            f"{where}: start_time {text!r} is not ISO 8601 (e.g. 2024-05-01T08:30:00+02:00)"
        ) from None
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value
