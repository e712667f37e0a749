"""Whose segments are whose in a recording folder: a live run's are never taken over.

A run recording `PREFIX-…` segments into a folder holds an exclusive lock (`flock`) on
`.PREFIX.lock` there, with its pid in it, for as long as it records. Only the holder recovers
the `PREFIX-….mcap.part` left by a killed run, removes old `PREFIX-….mcap` to keep the folder
under its bound and writes new ones. A second run with the same prefix (two daemons with one
vehicle id: every daemon defaults to `car-0`) finds the lock taken and records under the next
free `PREFIX.2`, `PREFIX.3`, … instead (logged), so neither loses a frame. The operating system
drops the lock when its process ends, however it ends: a killed run's parts are recovered by
the next run. A segment belongs to a prefix when its whole name matches `PREFIX-<UTC start>-
<number>.mcap` (a glob `PREFIX-*` would also take a longer vehicle id's segments).
"""

from __future__ import annotations

import fcntl
import logging
import os
import re
from pathlib import Path

from roadgaze.errors import RoadgazeError

log = logging.getLogger(__name__)

MAX_RUNS = 100
"""Runs that may record the same prefix into one folder at once."""
LOCK_SUFFIX = ".lock"


def segment_pattern(prefix: str, suffix: str = "") -> re.Pattern[str]:
    """The names of `prefix`'s segments: `PREFIX-YYYYMMDDTHHMMSSZ-NNNN.mcap` + `suffix`."""
    return re.compile(re.escape(prefix) + r"-\d{8}T\d{6}Z-\d{4,}\.mcap" + re.escape(suffix))


def segments_of(folder: Path, prefix: str, suffix: str = "") -> list[Path]:
    """The files of `prefix`'s segments in `folder` (closed ones, or with `suffix` `.part` the
    open ones), by name."""
    pattern = segment_pattern(prefix, suffix)
    try:
        names = sorted(entry.name for entry in os.scandir(folder) if entry.is_file())
    except OSError:
        return []
    return [folder / name for name in names if pattern.fullmatch(name)]


class PrefixLock:
    """The lock of one prefix in one folder, held until `release`."""

    def __init__(self, path: Path, handle: int) -> None:
        self.path = path
        self._handle: int | None = handle

    @classmethod
    def try_take(cls, path: Path) -> PrefixLock | int | None:
        """The lock, or the pid of the process holding it (None when it says none)."""
        handle = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            owner = os.pread(handle, 32, 0).decode("ascii", "replace").strip()
            os.close(handle)
            return int(owner) if owner.isdigit() else None
        except BaseException:
            os.close(handle)
            raise
        os.ftruncate(handle, 0)
        os.pwrite(handle, f"{os.getpid()}\n".encode(), 0)
        return cls(path, handle)

    def release(self) -> None:
        """Let the next run have the prefix (the file stays: removing it would race a run
        opening it at that moment)."""
        handle, self._handle = self._handle, None
        if handle is not None:
            os.close(handle)  # closing the last descriptor drops the flock


def claim_prefix(folder: Path, prefix: str) -> tuple[PrefixLock, str]:
    """The lock of `prefix` in `folder`, or of the first free `prefix.N` when another run holds
    it (logged once); `RoadgazeError` when none is free or the lock file cannot be made."""
    owner: int | None = None
    for number in range(1, MAX_RUNS + 1):
        name = prefix if number == 1 else f"{prefix}.{number}"
        path = folder / f".{name}{LOCK_SUFFIX}"
        try:
            taken = PrefixLock.try_take(path)
        except OSError as exc:
            raise RoadgazeError(f"cannot record into {folder}: {exc.strerror or exc}") from None
        if isinstance(taken, PrefixLock):
            if number > 1:
                log.warning(
                    "record: another run (pid %s) is recording %s's segments in %s: this one "
                    "records them as %s-… (two daemons with one vehicle id? give each its own "
                    "--vehicle-id)",
                    owner or "unknown",
                    prefix,
                    folder,
                    name,
                )
            return taken, name
        if number == 1:
            owner = taken  # the run that holds the vehicle's own prefix
    raise RoadgazeError(
        f"cannot record into {folder}: {MAX_RUNS} runs already record {prefix}'s segments there"
    )


def recording_pid(part: Path) -> int | None:
    """The pid of the live run writing the open segment `part` (`….mcap.part`; 0 when it wrote
    none), or None when no run holds its prefix (a part left by a killed run: safe to
    recover)."""
    match = re.fullmatch(r"(.+)-\d{8}T\d{6}Z-\d{4,}\.mcap\.part", part.name)
    if match is None:
        return None
    path = part.parent / f".{match.group(1)}{LOCK_SUFFIX}"
    if not path.exists():
        return None
    taken = PrefixLock.try_take(path)
    if isinstance(taken, PrefixLock):
        taken.release()
        return None
    return taken if taken is not None else 0
