"""What became of one drive: its status and the figures of its row in `summary.parquet`."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Literal

from roadgaze.fleet.drives import Drive
from roadgaze.types import AlertKind

Status = Literal["ok", "failed", "interrupted", "pending"]
"""ok: outputs written (now or by an earlier run); failed: see `error`; interrupted: stopped
before its end, nothing written; pending: not started before the batch was stopped."""

ALERT_KINDS = tuple(kind.value for kind in AlertKind if kind is not AlertKind.CLEARED)
"""The kinds counted per drive (`cleared` ends alerts; it is not one)."""


@dataclass(frozen=True, slots=True)
class DriveResult:
    """One drive's outcome and summary: one row of `summary.parquet`."""

    drive_id: str
    path: str
    driver_id: str | None
    vehicle_id: str | None
    start_time: str | None
    """ISO 8601 with its zone."""
    status: Status
    resumed: bool = False
    """The outputs come from an earlier run (the input and configuration had not changed)."""
    error: str | None = None
    warning: str | None = None
    """A problem that did not stop the drive, e.g. a video that ended before its announced end."""
    frames: int = 0
    frames_with_face: int = 0
    frames_gaze_known: int = 0
    """Frames on which the monitor knew the gaze (on or off road)."""
    frames_off_road: int = 0
    duration_s: float = 0.0
    """Video time from the first frame to the end of the last one."""
    alert_counts: tuple[tuple[str, int], ...] = ()
    """Alerts raised by kind; a long distraction escalated to critical counts once."""
    critical_alerts: int = 0
    longest_off_road_s: float = 0.0
    """The longest continuous counted off-road episode (the monitor's `off_road_s`)."""
    neutral_yaw_deg: float | None = None
    """The monitor's road-ahead yaw at the end of the drive (learned unless configured)."""
    processing_fps: float = 0.0
    """Frames per second of the loop on this drive (start-up excluded)."""
    startup_s: float = 0.0
    """Opening the video and creating the landmarker."""
    wall_s: float = 0.0
    """The whole task, start-up and writing included."""

    @classmethod
    def of(cls, drive: Drive, status: Status, **values: Any) -> DriveResult:
        start = drive.start_time.isoformat() if drive.start_time is not None else None
        return cls(
            drive_id=drive.drive_id,
            path=str(drive.path),
            driver_id=drive.driver_id,
            vehicle_id=drive.vehicle_id,
            start_time=start,
            status=status,
            **values,
        )

    @property
    def face_found_rate(self) -> float | None:
        return self.frames_with_face / self.frames if self.frames else None

    @property
    def off_road_ratio(self) -> float | None:
        """Off-road frames over frames whose gaze is known."""
        return self.frames_off_road / self.frames_gaze_known if self.frames_gaze_known else None

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_json(cls, values: dict[str, Any]) -> DriveResult:
        counts = tuple((str(k), int(n)) for k, n in values.get("alert_counts", ()))
        return cls(**{**values, "alert_counts": counts})
