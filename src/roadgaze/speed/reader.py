"""Speed track files: the one reader (CSV or Parquet), the track beside a video, and which speed a
recorded drive gets.

A track has the columns `t_s` (seconds on the video's timeline, strictly increasing) and `kmh`
(km/h within 0-400; an empty cell, `nan` or a null: unknown from that sample on); other columns
are ignored. Rows are parsed and checked in batches of `BATCH_ROWS` into two float arrays, so
memory is 16 bytes a row whatever else the file holds, and a file of more than `max_rows` rows
(`capture.speed_track_max_rows`) is refused once the batch past the limit is read (Parquet: from
its footer, before reading). A CSV line over `MAX_LINE_CHARS` characters is refused. A
Parquet column must hold numbers (integers, floats or decimals): booleans, times, dates, text,
lists and structs are refused. Every refusal is one `SpeedError` naming the file and the line
(CSV) or row (Parquet).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Generator, Iterator
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import numpy as np
import numpy.typing as npt

from roadgaze.errors import ConfigError, SpeedError
from roadgaze.speed.track import DEFAULT_HOLD_S, SpeedTrack
from roadgaze.speed.values import MAX_KMH, ConstantSpeed, VehicleSpeed, checked_kmh

SPEED_TRACK_SUFFIXES = (".csv", ".parquet")
DEFAULT_MAX_ROWS = 2_000_000
"""The default of `capture.speed_track_max_rows`: 11 h of a 50 Hz CAN speed, 32 MB of samples."""
MAX_LINE_CHARS = 65_536
"""Longest CSV line read (a row of a speed track is a few dozen characters)."""
COLUMNS = ("t_s", "kmh")

BATCH_ROWS = 65_536
"""Rows parsed, then checked together (vectorised), at a time."""

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Batch:
    """Consecutive rows of a track: times, speeds (NaN: unknown) and where each row is."""

    t_s: FloatArray
    kmh: FloatArray
    where: Callable[[int], str]
    """The place of row `i` of the batch in the file, for messages (`... line 12`)."""


def _lines(handle: IO[str], path: Path) -> Iterator[str]:
    """The file's lines, each at most `MAX_LINE_CHARS` long (`SpeedError` for a longer one)."""
    number = 0
    while line := handle.readline(MAX_LINE_CHARS + 1):
        number += 1
        if len(line) > MAX_LINE_CHARS:
            raise SpeedError(
                f"speed track {path} line {number} is longer than {MAX_LINE_CHARS} characters; "
                "expected rows t_s,kmh"
            )
        yield line


def _csv_batches(path: Path, handle: IO[str]) -> Iterator[Batch]:
    reader = csv.reader(_lines(handle, path))
    header = [name.strip() for name in next(reader, [])]
    if any(header.count(name) != 1 for name in COLUMNS):
        raise SpeedError(
            f"speed track {path} must have a header with the columns t_s,kmh, once each "
            f"(found: {','.join(header)[:200] or 'nothing'})"
        )
    time_index, speed_index = header.index("t_s"), header.index("kmh")
    width = max(time_index, speed_index) + 1
    times: list[float] = []
    speeds: list[float] = []
    lines: list[int] = []
    for row in reader:
        if not row:
            continue  # a blank line
        if len(row) < width:
            row += [""] * (width - len(row))
        try:
            times.append(float(row[time_index]))
        except ValueError:
            where = f"speed track {path} line {reader.line_num}"
            raise SpeedError(f"{where}: t_s {row[time_index]!r} is not a number") from None
        try:
            speeds.append(float(row[speed_index]))
        except ValueError:
            if row[speed_index].strip():
                where = f"speed track {path} line {reader.line_num}"
                raise SpeedError(f"{where}: kmh {row[speed_index]!r} is not a number") from None
            speeds.append(math.nan)  # an empty cell: unknown
        lines.append(reader.line_num)
        if len(lines) == BATCH_ROWS:
            yield _csv_batch(path, times, speeds, lines)
            times, speeds, lines = [], [], []
    if lines:
        yield _csv_batch(path, times, speeds, lines)


def _csv_batch(path: Path, times: list[float], speeds: list[float], lines: list[int]) -> Batch:
    return Batch(np.array(times), np.array(speeds), lambda i: f"speed track {path} line {lines[i]}")


def _parquet_batches(path: Path, max_rows: int) -> Iterator[Batch]:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise SpeedError(
            f"speed track {path}: reading Parquet needs pyarrow: pip install 'roadgaze[fleet]'"
        ) from None
    try:
        parquet = pq.ParquetFile(path)
        schema, rows = parquet.schema_arrow, parquet.metadata.num_rows
    except Exception as exc:  # pyarrow raises many kinds for a damaged file
        raise SpeedError(f"cannot read speed track {path}: {exc}") from None
    missing = [name for name in COLUMNS if name not in schema.names]
    if missing:
        raise SpeedError(f"speed track {path} has no column {', '.join(missing)}")
    for name in COLUMNS:
        if schema.names.count(name) > 1:
            raise SpeedError(f"speed track {path} has two columns {name}; keep one")
        kind = schema.field(name).type
        numeric = (pa.types.is_integer, pa.types.is_floating, pa.types.is_decimal)
        if not (pa.types.is_null(kind) or any(test(kind) for test in numeric)):
            unit = "seconds" if name == "t_s" else "km/h"
            raise SpeedError(
                f"speed track {path}: column {name} holds {kind} values; expected numbers ({unit})"
            )
    if rows > max_rows:
        raise _too_long(path, max_rows)
    first = 1
    try:
        for batch in parquet.iter_batches(batch_size=BATCH_ROWS, columns=list(COLUMNS)):
            times, speeds = (
                np.asarray(batch.column(name).cast(pa.float64()).to_numpy(zero_copy_only=False))
                for name in COLUMNS
            )
            yield Batch(times, speeds, _row_names(path, first))
            first += len(times)
    except Exception as exc:
        raise SpeedError(f"cannot read speed track {path}: {exc}") from None


def _row_names(path: Path, first: int) -> Callable[[int], str]:
    return lambda i: f"speed track {path} row {first + i}"


def _check(batch: Batch, previous_s: float) -> None:
    """`SpeedError` for the first bad row of `batch`: a time not finite or not after the one
    before (`previous_s` is the last of the batch before), or a speed the one range check
    (`checked_kmh`) refuses."""
    times, speeds = batch.t_s, batch.kmh
    before = np.concatenate(([previous_s], times[:-1]))
    bad_time = ~np.isfinite(times) | ~(times > before)
    # NaN is unknown; any other speed outside the range goes to `checked_kmh`, which decides.
    maybe_bad_speed = ~np.isnan(speeds) & ~((speeds >= 0.0) & (speeds <= MAX_KMH))
    for index in np.flatnonzero(bad_time | maybe_bad_speed).tolist():
        where, t_s = batch.where(index), float(times[index])
        if not math.isfinite(t_s):
            raise SpeedError(f"{where}: t_s '{t_s:g}' is not a finite number of seconds")
        if bad_time[index]:
            raise SpeedError(f"{where}: t_s {t_s:g} is not after the previous {before[index]:g}")
        checked_kmh(float(speeds[index]), f"{where}: kmh")


def _too_long(path: Path, max_rows: int) -> SpeedError:
    return SpeedError(
        f"speed track {path} has more than {max_rows} rows (capture.speed_track_max_rows); "
        "split the drive, thin the track or raise the setting"
    )


def _batches(path: Path, suffix: str, max_rows: int) -> Generator[Batch, None, None]:
    if suffix == ".parquet":
        yield from _parquet_batches(path, max_rows)
        return
    with path.open(newline="", encoding="utf-8-sig") as handle:
        yield from _csv_batches(path, handle)


def read_speed_track(
    path: Path, hold_s: float = DEFAULT_HOLD_S, *, max_rows: int = DEFAULT_MAX_ROWS
) -> SpeedTrack:
    """Read a `t_s,kmh` track (CSV or Parquet; the module doc); raises `SpeedError`."""
    path = Path(path)
    if not path.is_file():
        raise SpeedError(f"speed track {path} not found; pass an existing .csv or .parquet file")
    suffix = path.suffix.lower()
    if suffix not in SPEED_TRACK_SUFFIXES:
        raise SpeedError(f"speed track {path}: expected a .csv or .parquet file")
    times: list[FloatArray] = []
    speeds: list[FloatArray] = []
    rows, previous_s = 0, -math.inf
    try:
        with closing(_batches(path, suffix, max_rows)) as batches:
            for batch in batches:
                rows += batch.t_s.size
                if rows > max_rows:
                    raise _too_long(path, max_rows)
                _check(batch, previous_s)
                times.append(batch.t_s)
                speeds.append(batch.kmh)
                previous_s = float(batch.t_s[-1])
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise SpeedError(f"cannot read speed track {path}: {exc}") from None
    if not rows:
        raise SpeedError(f"speed track {path} has no sample (expected rows t_s,kmh)")
    return SpeedTrack(np.concatenate(times), np.concatenate(speeds), hold_s, name=str(path))


def track_beside(video: Path) -> Path | None:
    """`drive.speed.csv` or `drive.speed.parquet` beside `drive.mp4`, if there is one.

    Raises `SpeedError` when both exist (which one the car's is cannot be guessed).
    """
    video = Path(video)
    found = [
        path
        for suffix in SPEED_TRACK_SUFFIXES
        if (path := video.with_name(f"{video.stem}.speed{suffix}")).is_file()
    ]
    if len(found) > 1:
        raise SpeedError(
            f"two speed tracks beside {video}: {found[0].name} and {found[1].name}; keep one"
        )
    return found[0] if found else None


@dataclass(frozen=True, slots=True)
class SpeedChoice:
    """The speed of a recorded drive and where it came from (for the log)."""

    speed: VehicleSpeed | None
    """None: no track and no constant (the bus, or unknown = moving)."""
    origin: str
    track_path: Path | None = None
    """The track file read (named, or found beside the video): an input of the run."""


def recorded_speed(
    video: Path | str | None,
    track: Path | None = None,
    constant_kmh: float | None = None,
    hold_s: float = DEFAULT_HOLD_S,
    max_rows: int = DEFAULT_MAX_ROWS,
) -> SpeedChoice:
    """The speed of a recorded drive: `constant_kmh`, else the `track` named, else the track
    beside `video` (`track_beside`), else none. `ConfigError` for both options; `SpeedError`
    for a bad constant or a bad track."""
    if track is not None and constant_kmh is not None:
        raise ConfigError("give --speed-track or --speed-kmh, not both")
    if constant_kmh is not None:
        speed = ConstantSpeed(checked_kmh(constant_kmh, "--speed-kmh"))
        return SpeedChoice(speed, f"constant {constant_kmh:g} km/h")
    path = track
    if path is None and video is not None and Path(video).is_file():
        path = track_beside(Path(video))
    if path is None:
        return SpeedChoice(None, "none")
    speed_track = read_speed_track(path, hold_s, max_rows=max_rows)
    return SpeedChoice(speed_track, speed_track.describe(), Path(path))
