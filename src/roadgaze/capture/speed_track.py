"""The vehicle speed of a recorded drive: a `t_s,kmh` track beside the video, or a constant.

A replay gates alerts as the car did only if it knows the car's speed. The bus gives it live
(`roadgaze.transport.speed`); for a recorded drive it comes from a speed track:

- **Naming.** `drive.mp4` -> `drive.speed.csv` or `drive.speed.parquet` in the same folder (found
  by `track_beside`; both present is an error), or a file named explicitly (`--speed-track`).
- **Format.** Columns `t_s` (seconds on the video's own timeline, i.e. the records' `t_s`, strictly
  increasing) and `kmh` (km/h, finite, 0-400 like the bus); other columns are ignored. An empty
  `kmh` cell (CSV), `nan` or a null (Parquet) marks the speed as unknown from that sample on: a
  CAN dropout. Parquet needs pyarrow (`roadgaze[fleet]`).
- **Between samples: hold the last**, as the bus does live (its newest value), for at most
  `hold_s` (the bus's `zenoh.speed_timeout_s`, 2 s). Before the first sample, after an unknown
  sample, or more than `hold_s` after the last one (a gap in the track), the speed is unknown and
  taken as moving: fail-safe, no alert is suppressed.

A bad file (missing, unreadable, no rows, a bad value, time not increasing) raises `SourceError`
with the file and line: one clear line on the command line.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from pathlib import Path

from roadgaze.csv_rows import read_csv_rows
from roadgaze.errors import ConfigError, SourceError
from roadgaze.pipeline.speed import ConstantSpeed, VehicleSpeed

SPEED_TRACK_SUFFIXES = (".csv", ".parquet")
MAX_KMH = 400.0
"""Fastest speed accepted, as on the bus (`roadgaze.transport.speed.SPEED_MAX_KMH`)."""
DEFAULT_HOLD_S = 2.0
"""How long a sample holds without a newer one (the bus's default `speed_timeout_s`)."""


@dataclass(frozen=True, slots=True)
class SpeedTrack:
    """Speed samples of one drive; `kmh_at(t_s)` holds the last for at most `hold_s` seconds."""

    t_s: tuple[float, ...]
    kmh: tuple[float | None, ...]
    """None: unknown from that sample on (until the next)."""
    hold_s: float = DEFAULT_HOLD_S
    name: str = "speed track"

    def kmh_at(self, t_s: float) -> float | None:
        """The speed at `t_s` (km/h), or None when unknown (taken as moving)."""
        index = bisect.bisect_right(self.t_s, t_s) - 1
        if index < 0 or t_s - self.t_s[index] > self.hold_s:
            return None
        return self.kmh[index]

    def describe(self) -> str:
        known = [value for value in self.kmh if value is not None]
        span = f"{self.t_s[0]:.2f}-{self.t_s[-1]:.2f} s"
        speeds = f"{min(known):.0f}-{max(known):.0f} km/h" if known else "no known speed"
        return f"{self.name} ({len(self.t_s)} samples, {span}, {speeds})"


def _speed_value(text: str | float | None, where: str) -> float | None:
    """A `kmh` cell: None for empty, `nan` or null; a finite number within 0-400 otherwise."""
    if text is None or (isinstance(text, str) and text.strip().lower() in ("", "nan")):
        return None
    try:
        value = float(text)
    except ValueError:
        raise SourceError(f"{where}: kmh {text!r} is not a number") from None
    if math.isnan(value):
        return None
    if not (math.isfinite(value) and 0.0 <= value <= MAX_KMH):
        raise SourceError(f"{where}: kmh {text!r} is outside 0-{MAX_KMH:g} km/h")
    return value


def _time_value(text: str | float | None, where: str) -> float:
    try:
        value = float(text) if text is not None else math.nan
    except ValueError:
        raise SourceError(f"{where}: t_s {text!r} is not a number") from None
    if not math.isfinite(value):
        raise SourceError(f"{where}: t_s {text!r} is not a finite number of seconds")
    return value


def _columns(path: Path) -> tuple[list[object], list[object], str]:
    """The raw `t_s` and `kmh` columns of a CSV or Parquet file, and what the first row is."""
    suffix = path.suffix.lower()
    if suffix == ".parquet":
        try:
            import pyarrow.parquet as pq
        except ImportError:
            raise SourceError(
                f"speed track {path}: reading Parquet needs pyarrow: pip install 'roadgaze[fleet]'"
            ) from None
        try:
            table = pq.read_table(path)
        except Exception as exc:  # pyarrow raises many kinds for a damaged file
            raise SourceError(f"cannot read speed track {path}: {exc}") from None
        missing = [name for name in ("t_s", "kmh") if name not in table.column_names]
        if missing:
            raise SourceError(f"speed track {path} has no column {', '.join(missing)}")
        return table.column("t_s").to_pylist(), table.column("kmh").to_pylist(), "row"
    if suffix != ".csv":
        raise SourceError(f"speed track {path}: expected a .csv or .parquet file")
    header, rows = read_csv_rows(path, SourceError, "speed track")
    if "t_s" not in header or "kmh" not in header:
        raise SourceError(
            f"speed track {path} must have a header with the columns t_s,kmh "
            f"(found: {','.join(header) or 'nothing'})"
        )
    cells = [{(k or "").strip(): v for k, v in row.items()} for row in rows]
    return [row["t_s"] for row in cells], [row["kmh"] for row in cells], "line"


def read_speed_track(path: Path, hold_s: float = DEFAULT_HOLD_S) -> SpeedTrack:
    """Read a `t_s,kmh` track (CSV or Parquet; the module doc); raises `SourceError`."""
    path = Path(path)
    if not path.is_file():
        raise SourceError(f"speed track {path} not found; pass an existing .csv or .parquet file")
    times, speeds, unit = _columns(path)
    if not times:
        raise SourceError(f"speed track {path} has no sample (expected rows t_s,kmh)")
    first = 2 if unit == "line" else 1  # a CSV's first data row is line 2
    t_s: list[float] = []
    kmh: list[float | None] = []
    for number, (time_cell, speed_cell) in enumerate(zip(times, speeds, strict=True), first):
        where = f"speed track {path} {unit} {number}"
        t = _time_value(time_cell, where)  # type: ignore[arg-type]
        if t_s and t <= t_s[-1]:
            raise SourceError(f"{where}: t_s {t:g} is not after the previous {t_s[-1]:g}")
        t_s.append(t)
        kmh.append(_speed_value(speed_cell, where))  # type: ignore[arg-type]
    return SpeedTrack(tuple(t_s), tuple(kmh), hold_s, name=str(path))


def track_beside(video: Path) -> Path | None:
    """`drive.speed.csv` or `drive.speed.parquet` beside `drive.mp4`, if there is one.

    Raises `SourceError` when both exist (which one the car's is cannot be guessed).
    """
    video = Path(video)
    found = [
        path
        for suffix in SPEED_TRACK_SUFFIXES
        if (path := video.with_name(f"{video.stem}.speed{suffix}")).is_file()
    ]
    if len(found) > 1:
        raise SourceError(
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


def recorded_speed(
    video: Path | str | None,
    track: Path | None = None,
    constant_kmh: float | None = None,
    hold_s: float = DEFAULT_HOLD_S,
) -> SpeedChoice:
    """The speed of a recorded drive: `constant_kmh`, else the `track` named, else the track
    beside `video` (`track_beside`), else none. Raises `ConfigError` for both options or a bad
    constant and `SourceError` for a bad track."""
    if track is not None and constant_kmh is not None:
        raise ConfigError("give --speed-track or --speed-kmh, not both")
    if constant_kmh is not None:
        if not (math.isfinite(constant_kmh) and 0.0 <= constant_kmh <= MAX_KMH):
            raise ConfigError(
                f"--speed-kmh must be within 0-{MAX_KMH:g} km/h, found {constant_kmh}"
            )
        return SpeedChoice(ConstantSpeed(constant_kmh), f"constant {constant_kmh:g} km/h")
    path = track
    if path is None and video is not None and Path(video).is_file():
        path = track_beside(Path(video))
    if path is None:
        return SpeedChoice(None, "none")
    speed_track = read_speed_track(path, hold_s)
    return SpeedChoice(speed_track, speed_track.describe(), Path(path))
