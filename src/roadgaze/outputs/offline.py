"""Fill the offline columns of a finished recording's frame-record file (JSON lines or CSV).

A replay streams its records line by line (nothing is lost on a crash) with `yaw_offline_deg` and
`pitch_offline_deg` null; at the normal end `fill_offline_columns` reads the raw yaw and pitch
back, runs the offline pass (`roadgaze.pose.offline_pose`, RTS) and rewrites the file atomically
(a temporary file beside it, then `os.replace`), so the file on disk is always either the
streamed one or the complete one.
"""

from __future__ import annotations

import contextlib
import csv
import json
import math
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np

from roadgaze.config import SmoothingConfig
from roadgaze.errors import RoadgazeError
from roadgaze.outputs.records import OFFLINE_FIELDS, rounded
from roadgaze.pose import OfflinePose, offline_pose

__all__ = ["fill_offline_columns"]


def _number(value: Any) -> float:
    """A record cell as a float; NaN for null, an empty CSV cell or anything not a number."""
    if value is None or value == "":
        return math.nan
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def _rows(path: Path, csv_format: bool, stream: IO[str]) -> Iterator[dict[str, Any]]:
    if csv_format:
        yield from csv.DictReader(stream)
        return
    for number, line in enumerate(stream, start=1):
        if line.strip():
            try:
                yield json.loads(line)
            except ValueError:
                raise RoadgazeError(f"{path}:{number}: not a JSON frame record") from None


def _offline(path: Path, csv_format: bool, smoothing: SmoothingConfig) -> OfflinePose:
    times: list[float] = []
    yaws: list[float] = []
    pitches: list[float] = []
    with path.open(encoding="utf-8", newline="" if csv_format else None) as stream:
        for row in _rows(path, csv_format, stream):
            times.append(_number(row.get("t_s")))
            yaws.append(_number(row.get("yaw_raw_deg")))
            pitches.append(_number(row.get("pitch_raw_deg")))
    try:
        return offline_pose(np.asarray(times), np.asarray(yaws), np.asarray(pitches), smoothing)
    except ValueError as exc:
        raise RoadgazeError(f"{path}: cannot run the offline pass: {exc}") from None


def fill_offline_columns(
    path: str | Path, smoothing: SmoothingConfig | None = None, csv_format: bool | None = None
) -> int:
    """Rewrite a frame-record file (CSV when `csv_format`, else JSON lines; None: CSV for a
    `.csv` name) with the offline columns filled.

    Returns the number of records. Raises RoadgazeError for an unreadable file or one whose
    times do not increase; the original file is then left as it was.
    """
    path = Path(path)
    if csv_format is None:
        csv_format = path.suffix.lower() == ".csv"
    smoothing = smoothing if smoothing is not None else SmoothingConfig()
    try:
        pose = _offline(path, csv_format, smoothing)
        handle, name = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
        temporary = Path(name)
        temporary.chmod(stat.S_IMODE(path.stat().st_mode))
    except OSError as exc:
        raise RoadgazeError(f"cannot fill the offline columns of {path}: {exc}") from None
    count = 0
    try:
        with (
            os.fdopen(handle, "w", encoding="utf-8", newline="" if csv_format else None) as out,
            path.open(encoding="utf-8", newline="" if csv_format else None) as stream,
        ):
            writer: csv.DictWriter[str] | None = None
            for row in _rows(path, csv_format, stream):
                values = (pose.yaw_deg[count], pose.pitch_deg[count])
                for name, value in zip(OFFLINE_FIELDS, values, strict=True):
                    filled = rounded(float(value), 3)
                    row[name] = ("" if filled is None else filled) if csv_format else filled
                if csv_format:
                    if writer is None:
                        writer = csv.DictWriter(out, fieldnames=list(row))
                        writer.writeheader()
                    writer.writerow(row)
                else:
                    out.write(json.dumps(row, allow_nan=False) + "\n")
                count += 1
        temporary.replace(path)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            temporary.unlink()
        if isinstance(exc, OSError):
            raise RoadgazeError(f"cannot fill the offline columns of {path}: {exc}") from None
        raise
    return count
