"""The fleet summary: one row per drive (`summary.parquet`), and the same figures per driver and
for the whole fleet.

Rates are per hour of video. Alerts are counted by kind (`cleared` is not an alert; a long
distraction escalated from warning to critical counts once, and once in `critical_alerts`).
Ratios over several drives are weighted by frames (face found) or by frames with a known gaze
(off road), so a long drive weighs more than a short one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any

import pyarrow as pa

from roadgaze.fleet.results import ALERT_KINDS, DriveResult

UNKNOWN_DRIVER = "(unknown)"
"""How drives without a `driver_id` are grouped."""

_SUMMARY_COLUMNS: tuple[tuple[str, Any], ...] = (
    ("drive_id", pa.string()),
    ("driver_id", pa.string()),
    ("vehicle_id", pa.string()),
    ("start_time", pa.timestamp("us", tz="UTC")),
    ("path", pa.string()),
    ("status", pa.string()),
    ("resumed", pa.bool_()),
    ("error", pa.string()),
    ("warning", pa.string()),
    ("frames", pa.int64()),
    ("duration_s", pa.float64()),
    ("face_found_rate", pa.float64()),
    ("off_road_ratio", pa.float64()),
    *((f"alerts_{kind}", pa.int64()) for kind in ALERT_KINDS),
    *((f"{kind}_per_h", pa.float64()) for kind in ALERT_KINDS),
    ("critical_alerts", pa.int64()),
    ("longest_off_road_s", pa.float64()),
    ("neutral_yaw_deg", pa.float64()),
    ("processing_fps", pa.float64()),
    ("startup_s", pa.float64()),
    ("wall_s", pa.float64()),
)


def summary_schema() -> Any:
    """The Arrow schema of `summary.parquet`."""
    return pa.schema([pa.field(name, arrow_type) for name, arrow_type in _SUMMARY_COLUMNS])


def per_hour(count: float, duration_s: float) -> float | None:
    """`count` per hour of `duration_s`; None for no duration."""
    return count * 3600.0 / duration_s if duration_s > 0 else None


def summary_row(result: DriveResult) -> dict[str, Any]:
    """One drive as a row of `summary.parquet`; figures are null unless the drive is ok."""
    ok = result.status == "ok"
    counts = dict(result.alert_counts)
    row: dict[str, Any] = {
        "drive_id": result.drive_id,
        "driver_id": result.driver_id,
        "vehicle_id": result.vehicle_id,
        "start_time": datetime.fromisoformat(result.start_time) if result.start_time else None,
        "path": result.path,
        "status": result.status,
        "resumed": result.resumed,
        "error": result.error,
        "warning": result.warning,
        "frames": result.frames if ok else None,
        "duration_s": result.duration_s if ok else None,
        "face_found_rate": _rounded(result.face_found_rate, 4) if ok else None,
        "off_road_ratio": _rounded(result.off_road_ratio, 4) if ok else None,
        "critical_alerts": result.critical_alerts if ok else None,
        "longest_off_road_s": result.longest_off_road_s if ok else None,
        "neutral_yaw_deg": result.neutral_yaw_deg if ok else None,
        "processing_fps": result.processing_fps if ok else None,
        "startup_s": result.startup_s if ok else None,
        "wall_s": result.wall_s if ok else None,
    }
    for kind in ALERT_KINDS:
        row[f"alerts_{kind}"] = counts.get(kind, 0) if ok else None
        rate = per_hour(counts.get(kind, 0), result.duration_s) if ok else None
        row[f"{kind}_per_h"] = _rounded(rate, 3)
    return row


def summary_table(results: Sequence[DriveResult]) -> Any:
    """All drives, in the order given, as an Arrow table with `summary_schema()`."""
    rows = [summary_row(result) for result in results]
    schema = summary_schema()
    return pa.Table.from_pydict(
        {name: [row[name] for row in rows] for name in schema.names}, schema
    )


@dataclass(frozen=True, slots=True)
class GroupStats:
    """The figures of a group of drives (one driver, or the fleet)."""

    name: str
    drives: int
    drives_ok: int
    drives_failed: int
    hours: float
    frames: int
    face_found_rate: float | None
    off_road_ratio: float | None
    alerts: dict[str, int]
    alerts_per_h: dict[str, float | None]
    critical_alerts: int
    longest_off_road_s: float | None
    neutral_yaw_deg: float | None
    """Mean over the group's drives of the road-ahead yaw learned by the end of each."""
    processing_fps: float | None
    """Frames over the summed per-drive loop time: the speed of one worker's loop (a resumed
    drive counts with the speed of the run that processed it)."""


def group_stats(name: str, results: Sequence[DriveResult]) -> GroupStats:
    """The figures of `results` taken together (only drives with status ok count)."""
    ok = [r for r in results if r.status == "ok"]
    duration_s = sum(r.duration_s for r in ok)
    frames = sum(r.frames for r in ok)
    known = sum(r.frames_gaze_known for r in ok)
    alerts = {kind: sum(dict(r.alert_counts).get(kind, 0) for r in ok) for kind in ALERT_KINDS}
    neutrals = [r.neutral_yaw_deg for r in ok if r.neutral_yaw_deg is not None]
    timed = [r for r in ok if r.processing_fps > 0]
    loop_s = sum(r.frames / r.processing_fps for r in timed)
    return GroupStats(
        name=name,
        drives=len(results),
        drives_ok=len(ok),
        drives_failed=sum(r.status == "failed" for r in results),
        hours=duration_s / 3600.0,
        frames=frames,
        face_found_rate=sum(r.frames_with_face for r in ok) / frames if frames else None,
        off_road_ratio=sum(r.frames_off_road for r in ok) / known if known else None,
        alerts=alerts,
        alerts_per_h={kind: per_hour(count, duration_s) for kind, count in alerts.items()},
        critical_alerts=sum(r.critical_alerts for r in ok),
        longest_off_road_s=max((r.longest_off_road_s for r in ok), default=None),
        neutral_yaw_deg=sum(neutrals) / len(neutrals) if neutrals else None,
        processing_fps=sum(r.frames for r in timed) / loop_s if loop_s > 0 else None,
    )


def by_driver(results: Sequence[DriveResult]) -> list[GroupStats]:
    """One `GroupStats` per driver id (drives without one grouped as `UNKNOWN_DRIVER`), sorted
    by name."""
    groups: dict[str, list[DriveResult]] = {}
    for result in results:
        groups.setdefault(result.driver_id or UNKNOWN_DRIVER, []).append(result)
    return [group_stats(name, groups[name]) for name in sorted(groups)]


def _rounded(value: float | None, digits: int) -> float | None:
    return None if value is None else round(value, digits)


@dataclass(frozen=True, slots=True)
class BatchOutcome:
    """What one run of a batch did: every drive's result, in input order, and the run's pace."""

    results: tuple[DriveResult, ...]
    engine: str
    workers: int
    wall_s: float
    """From the first drive submitted to the last result (engine start-up excluded)."""
    startup_s: float
    """Starting the engine (Ray: connecting or starting a local instance)."""
    interrupted: bool = False
    worker_deaths: int = 0
    """Local engine: worker processes that died on a drive (each cost that drive one try)."""
    retries: int = 0
    """Local engine: drives started again after their worker died."""

    @property
    def processed(self) -> tuple[DriveResult, ...]:
        """Drives run to their end in this run (not resumed)."""
        return tuple(r for r in self.results if r.status == "ok" and not r.resumed)

    @property
    def frames_processed(self) -> int:
        return sum(r.frames for r in self.processed)

    @property
    def frames_per_s(self) -> float:
        """Frames of the drives processed in this run over the run's wall time."""
        return self.frames_processed / self.wall_s if self.wall_s > 0 else 0.0

    def count(self, status: str, resumed: bool | None = None) -> int:
        return sum(
            r.status == status and (resumed is None or r.resumed == resumed) for r in self.results
        )

    @property
    def failed(self) -> tuple[DriveResult, ...]:
        return tuple(r for r in self.results if r.status == "failed")

    def to_json(self) -> dict[str, Any]:
        """The run in numbers (`roadgaze batch --json`)."""
        startups = sorted(r.startup_s for r in self.processed)
        return {
            "engine": self.engine,
            "workers": self.workers,
            "drives": len(self.results),
            "ok": self.count("ok"),
            "processed": len(self.processed),
            "resumed": self.count("ok", resumed=True),
            "failed": self.count("failed"),
            "interrupted": self.count("interrupted"),
            "pending": self.count("pending"),
            "frames": self.frames_processed,
            "wall_s": round(self.wall_s, 3),
            "frames_per_s": round(self.frames_per_s, 2),
            "engine_startup_s": round(self.startup_s, 3),
            "drive_startup_median_s": startups[len(startups) // 2] if startups else None,
            "drive_startup_max_s": startups[-1] if startups else None,
            "video_s": round(sum(r.duration_s for r in self.processed), 3),
            "worker_deaths": self.worker_deaths,
            "retries": self.retries,
        }
