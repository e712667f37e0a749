"""The sink that records one drive: frames and alerts to Parquet, the counts of its summary."""

from __future__ import annotations

import math
from array import array
from dataclasses import dataclass, field

import numpy as np

from roadgaze.config import SmoothingConfig
from roadgaze.fleet.drives import Drive
from roadgaze.fleet.results import ALERT_KINDS, DriveResult
from roadgaze.fleet.tables import AtomicParquetWriter
from roadgaze.outputs.records import OFFLINE_FIELDS, alert_fields, record_fields, rounded
from roadgaze.types import Alert, AlertKind, AlertLevel, Frame, FrameRecord, Gaze


@dataclass(slots=True)
class DriveRecorder:
    """A pipeline sink: every record to the frames table, every alert to the alerts table, and
    the counts of the drive's summary."""

    frames: AtomicParquetWriter
    alerts: AtomicParquetWriter
    faces: int = 0
    known_gaze: int = 0
    off_road: int = 0
    first_t_s: float | None = None
    last_t_s: float = 0.0
    longest_off_road_s: float = 0.0
    neutral_yaw_deg: float | None = None
    critical: int = 0
    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(ALERT_KINDS, 0))
    _active: tuple[AlertKind, ...] = ()
    _raw: tuple[array[float], array[float], array[float]] = field(
        default_factory=lambda: (array("d"), array("d"), array("d"))
    )
    """t_s, raw yaw and raw pitch as written (NaN for null): the offline pass's input."""

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        fields = record_fields(record)
        self.frames.append(fields)
        for series, name in zip(self._raw, ("t_s", "yaw_raw_deg", "pitch_raw_deg"), strict=True):
            value = fields[name]
            series.append(math.nan if value is None else value)
        sample, verdict = record.sample, record.verdict
        self.first_t_s = sample.t_s if self.first_t_s is None else self.first_t_s
        self.last_t_s = sample.t_s
        self.faces += sample.face
        self.known_gaze += verdict.gaze is not Gaze.UNKNOWN
        self.off_road += verdict.gaze is Gaze.OFF_ROAD
        self.longest_off_road_s = max(self.longest_off_road_s, verdict.off_road_s)
        self.neutral_yaw_deg = verdict.neutral_yaw_deg
        for alert in record.alerts:
            self._note(alert, sample.frame)
        self._active = verdict.active

    def on_alert(self, alert: Alert) -> None:
        """An alert raised outside the frame loop: a row of the alerts table with no frame."""
        self._note(alert, None)

    def _note(self, alert: Alert, frame: int | None) -> None:
        self.alerts.append({"frame": frame, **alert_fields(alert)})
        self.critical += alert.level is AlertLevel.CRITICAL
        if alert.kind.value in self.counts and alert.kind not in self._active:
            self.counts[alert.kind.value] += 1

    def close(self) -> None:
        return None

    def offline_columns(
        self, smoothing: SmoothingConfig
    ) -> tuple[dict[str, list[float | None]], str | None]:
        """The offline (RTS) yaw and pitch of every frame, as `replay` fills them at its end
        (from the values written); empty with the reason when the pass cannot run."""
        from roadgaze.pose import offline_pose

        t_s, yaw_raw, pitch_raw = (np.asarray(series) for series in self._raw)
        try:
            pose = offline_pose(t_s, yaw_raw, pitch_raw, smoothing)
        except ValueError as exc:
            return {}, f"offline columns left null: {exc}"
        columns = (pose.yaw_deg, pose.pitch_deg)
        return {
            name: [rounded(float(value), 3) for value in values]
            for name, values in zip(OFFLINE_FIELDS, columns, strict=True)
        }, None

    def result(
        self,
        drive: Drive,
        period_s: float,
        warning: str | None,
        processing_fps: float,
        startup_s: float,
    ) -> DriveResult:
        duration_s = self.last_t_s - (self.first_t_s or 0.0) + period_s
        return DriveResult.of(
            drive,
            "ok",
            warning=warning,
            frames=self.frames.rows,
            frames_with_face=self.faces,
            frames_gaze_known=self.known_gaze,
            frames_off_road=self.off_road,
            duration_s=round(duration_s, 3),
            alert_counts=tuple(self.counts.items()),
            critical_alerts=self.critical,
            longest_off_road_s=round(self.longest_off_road_s, 3),
            neutral_yaw_deg=_finite_or_none(self.neutral_yaw_deg),
            processing_fps=round(processing_fps, 2),
            startup_s=round(startup_s, 3),
        )


def _finite_or_none(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else round(value, 3)
