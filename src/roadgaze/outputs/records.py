"""The per-frame record (one definition) and the writers of it: JSON lines and CSV.

`record_fields(record)` flattens a `FrameRecord` into the JSON-ready dict every writer uses:
the pose sample's fields, then the monitor's verdict and the alerts raised on that frame, then
the hands (`roadgaze.outputs.hand_record`; the one nested field, `hands`, is no CSV column).
`RECORD_SCHEMA` types each of its fields (`alert_fields` and `ALERT_SCHEMA` do the same for one
alert); columnar writers (the fleet's Parquet files) derive their schema from it.
Every writer is a context manager and a pipeline sink (`on_record`, `on_alert`, `close`); an
alert raised outside the frame loop is written as a row of its own (`alert_row`).
"""

from __future__ import annotations

import csv
import json
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

from roadgaze.errors import RoadgazeError
from roadgaze.monitor.behaviours.support import output_name, support_output
from roadgaze.monitor.protocols.support import CHANNELS
from roadgaze.outputs.field_types import FieldType as FieldType
from roadgaze.outputs.field_types import rounded as rounded
from roadgaze.outputs.hand_record import HAND_SCHEMA as HAND_SCHEMA
from roadgaze.outputs.hand_record import hand_fields as hand_fields
from roadgaze.types import Alert, ClosesOnExit, EyesVerdict, Frame, FrameRecord, Sink, Verdict

RECORD_SCHEMA: tuple[tuple[str, FieldType], ...] = (
    ("t_s", FieldType.FLOAT),
    ("frame", FieldType.INT),
    ("face", FieldType.BOOL),
    ("n_faces", FieldType.INT),
    ("driver_ambiguous", FieldType.STR),
    ("yaw_raw_deg", FieldType.FLOAT),
    ("yaw_deg", FieldType.FLOAT),
    ("yaw_rate_dps", FieldType.FLOAT),
    ("yaw_std_deg", FieldType.FLOAT),
    ("pitch_raw_deg", FieldType.FLOAT),
    ("pitch_deg", FieldType.FLOAT),
    ("x_left", FieldType.FLOAT),
    ("x_right", FieldType.FLOAT),
    ("x_center", FieldType.FLOAT),
    ("roll_deg", FieldType.FLOAT),
    ("quality", FieldType.FLOAT),
    ("on_road", FieldType.BOOL),
    ("gaze", FieldType.STR),
    ("zone", FieldType.STR),
    ("eyes_on_road", FieldType.BOOL),
    ("neutral_yaw_deg", FieldType.FLOAT),
    ("neutral_pitch_deg", FieldType.FLOAT),
    ("off_road_s", FieldType.FLOAT),
    ("window_off_road_s", FieldType.FLOAT),
    ("distraction_s", FieldType.FLOAT),
    ("eyes", FieldType.STR),
    ("eyes_reason", FieldType.STR),
    ("eye_openness", FieldType.FLOAT),
    ("eye_yaw_deg", FieldType.FLOAT),
    ("eye_pitch_deg", FieldType.FLOAT),
    ("gaze_yaw_deg", FieldType.FLOAT),
    ("gaze_pitch_deg", FieldType.FLOAT),
    ("gaze_source", FieldType.STR),
    ("closure_s", FieldType.FLOAT),
    ("perclos", FieldType.FLOAT),
    ("blinks", FieldType.INT),
    ("long_blinks", FieldType.INT),
    ("eyes_unavailable_s", FieldType.FLOAT),
    ("degraded", FieldType.BOOL),
    ("eye_calibration", FieldType.STR),
    ("alerts", FieldType.STR_LIST),
    ("support_forward", FieldType.STR),
    ("support_lane", FieldType.STR),
    *HAND_SCHEMA,
    ("yaw_offline_deg", FieldType.FLOAT),
    ("pitch_offline_deg", FieldType.FLOAT),
)
"""Every field of `record_fields`, in order, with its type: the one description the writers and
the fleet's Parquet schema are derived from (x_* in pixels of the roll-removed frame;
`driver_ambiguous` why the driver cannot be told from another face in view, '' when it can; the eye
fields as `roadgaze.types.EyesVerdict` defines them, `eyes` is open, closed or unavailable;
`support_forward` / `support_lane` `normal` or `heightened`, docs/monitor.md). A
field added to `record_fields` is added here too (a test checks it)."""

RECORD_FIELDS = tuple(name for name, _ in RECORD_SCHEMA)
CSV_FIELDS = tuple(name for name, kind in RECORD_SCHEMA if kind is not FieldType.HANDS)
"""The fields of the CSV file: all but the nested `hands` (a cell holds one value)."""
"""The fields of `record_fields`, in order. `yaw_offline_deg` / `pitch_offline_deg` are null
while a replay streams; `fill_offline_columns` fills them at its end."""

OFFLINE_FIELDS = ("yaw_offline_deg", "pitch_offline_deg")

ALERT_SCHEMA: tuple[tuple[str, FieldType], ...] = (
    ("kind", FieldType.STR),
    ("level", FieldType.STR),
    ("t_s", FieldType.FLOAT),
    ("yaw_deg", FieldType.FLOAT),
    ("off_road_s", FieldType.FLOAT),
    ("window_off_road_s", FieldType.FLOAT),
    ("unavailable_s", FieldType.FLOAT),
    ("speed_kmh", FieldType.FLOAT),
    ("clears", FieldType.STR_LIST),
    ("closure_s", FieldType.FLOAT),
    ("perclos", FieldType.FLOAT),
    ("reason", FieldType.STR),
    ("rule", FieldType.STR),
    ("source", FieldType.STR),
)
"""Every field of `alert_fields`: the content of an `AlertMessage` without its wire fields."""


def record_fields(record: FrameRecord) -> dict[str, Any]:
    """The per-frame record as a JSON-ready dict; None (null) where there is no value."""
    sample, verdict = record.sample, record.verdict
    features = sample.features
    neutral = verdict.camera_neutral_deg or (verdict.neutral_yaw_deg, verdict.neutral_pitch_deg)
    return {
        "t_s": round(sample.t_s, 6),
        "frame": sample.frame,
        "face": sample.face,
        "n_faces": sample.n_faces,
        "driver_ambiguous": sample.driver_ambiguous,
        "yaw_raw_deg": rounded(sample.yaw_raw_deg, 3),
        "yaw_deg": rounded(sample.yaw_deg, 3),
        "yaw_rate_dps": rounded(sample.yaw_rate_dps, 3),
        "yaw_std_deg": rounded(sample.yaw_std_deg, 3),
        "pitch_raw_deg": rounded(sample.pitch_raw_deg, 3),
        "pitch_deg": rounded(sample.pitch_deg, 3),
        "x_left": None if features is None else rounded(features.x_left_px, 2),
        "x_right": None if features is None else rounded(features.x_right_px, 2),
        "x_center": None if features is None else rounded(features.x_center_px, 2),
        "roll_deg": rounded(sample.roll_deg, 2),
        "quality": None if features is None else rounded(features.quality, 3),
        "on_road": verdict.on_road,
        "gaze": verdict.gaze.value,
        "zone": verdict.zone,
        "eyes_on_road": verdict.eyes_on_road,
        # The neutral in the frame of `yaw_deg` (the camera's; docs/monitor.md, Camera mounting).
        "neutral_yaw_deg": round(neutral[0], 3),
        "neutral_pitch_deg": round(neutral[1], 3),
        "off_road_s": round(float(verdict.off_road_s), 3),
        "window_off_road_s": round(float(verdict.window_off_road_s), 3),
        "distraction_s": round(float(verdict.distraction_s), 3),
        **eye_fields(verdict.eyes),
        "alerts": [alert.label for alert in record.alerts],
        **support_fields(verdict),
        **hand_fields(sample.hands, sample.phone),
        "yaw_offline_deg": None,
        "pitch_offline_deg": None,
    }


def alert_row(alert: Alert) -> dict[str, Any]:
    """An alert raised outside the frame loop as a row of the record files: the fields of
    `record_fields`, null but its time and its alert (`frame` null tells it from a frame)."""
    row: dict[str, Any] = dict.fromkeys(RECORD_FIELDS)
    row["t_s"] = round(alert.t_s, 6)
    row["alerts"] = [alert.label]
    return row


def alert_fields(alert: Alert) -> dict[str, Any]:
    """One alert as a flat JSON-ready dict with the fields of `ALERT_SCHEMA`."""
    return {
        "kind": alert.kind.value,
        "level": alert.level.value,
        "t_s": round(alert.t_s, 6),
        "yaw_deg": rounded(alert.yaw_deg, 3),
        "off_road_s": round(max(0.0, float(alert.off_road_s)), 3),
        "window_off_road_s": round(max(0.0, float(alert.window_off_road_s)), 3),
        "unavailable_s": round(max(0.0, float(alert.unavailable_s)), 3),
        "speed_kmh": rounded(alert.speed_kmh, 3),
        "clears": [kind.value for kind in alert.clears],
        "closure_s": round(max(0.0, float(alert.closure_s)), 3),
        "perclos": rounded(alert.perclos, 4),
        "reason": alert.reason,
        "rule": alert.rule,
        "source": alert.source,
    }


def support_fields(verdict: Verdict) -> dict[str, Any]:
    """Forward and lane support (`normal` or `heightened`; null when the support behaviour did
    not run): roadgaze.monitor.behaviours.support."""
    fields: dict[str, Any] = {}
    for channel in CHANNELS:
        output = support_output(verdict, channel)
        fields[output_name(channel)] = None if output is None else output.value
    return fields


def eye_fields(eyes: EyesVerdict) -> dict[str, Any]:
    """The eye part of the record (`eyes` ... `degraded` in RECORD_SCHEMA)."""
    return {
        "eyes": eyes.status.value,
        "eyes_reason": eyes.reason,
        "eye_openness": rounded(eyes.openness, 3),
        "eye_yaw_deg": rounded(eyes.eye_yaw_deg, 2),
        "eye_pitch_deg": rounded(eyes.eye_pitch_deg, 2),
        "gaze_yaw_deg": rounded(eyes.gaze_yaw_deg, 2),
        "gaze_pitch_deg": rounded(eyes.gaze_pitch_deg, 2),
        "gaze_source": eyes.gaze_source,
        "closure_s": round(eyes.closure_s, 3),
        "perclos": rounded(eyes.perclos, 4),
        "blinks": eyes.blinks,
        "long_blinks": eyes.long_blinks,
        "eyes_unavailable_s": round(eyes.unavailable_s, 3),
        "degraded": eyes.degraded,
        "eye_calibration": eyes.calibration.value,
    }


def open_for_writing(path: Path, what: str, newline: str | None = None) -> IO[str]:
    """`path` opened for line-buffered text writing (folders created); RoadgazeError if not."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        return path.open("w", encoding="utf-8", buffering=1, newline=newline)
    except OSError as exc:
        raise RoadgazeError(f"cannot write {what} {path}: {exc.strerror or exc}") from None


@contextmanager
def naming(path: Path | None) -> Iterator[None]:
    """An OSError raised while writing `path` names it (a full disk says which output)."""
    try:
        yield
    except OSError as exc:
        if exc.filename is None and path is not None:
            exc.filename = str(path)
        raise


class JsonlWriter(ClosesOnExit, Sink):
    """One JSON object per record and line, flushed line by line (nothing lost on a crash).

    `target` is a path, or an open text stream (e.g. stdout) that is flushed but not closed.
    """

    def __init__(self, target: str | Path | IO[str]) -> None:
        self._owned = isinstance(target, (str, Path))
        if isinstance(target, (str, Path)):
            self.path: Path | None = Path(target)
            self._file: IO[str] | None = open_for_writing(self.path, "frame records")
        else:
            self.path = None
            self._file = target
        self.records = 0

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self._write(record_fields(record))
        self.records += 1

    def on_alert(self, alert: Alert) -> None:
        self._write(alert_row(alert))

    def _write(self, fields: dict[str, Any]) -> None:
        assert self._file is not None, "writer is closed"
        with naming(self.path):
            self._file.write(json.dumps(fields, allow_nan=False) + "\n")
            if not self._owned:
                self._file.flush()

    def close(self) -> None:
        if self._file is not None:
            file, self._file = self._file, None
            with naming(self.path):
                if self._owned:
                    file.close()
                else:
                    file.flush()


class CsvWriter(ClosesOnExit, Sink):
    """The same records as CSV (`CSV_FIELDS`: all but the nested `hands`); empty cells for
    null."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._file: IO[str] | None = open_for_writing(self.path, "CSV", newline="")
        self._writer: csv.DictWriter[str] | None = None
        self.records = 0

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self._write(record_fields(record))
        self.records += 1

    def on_alert(self, alert: Alert) -> None:
        self._write(alert_row(alert))

    def _write(self, fields: dict[str, Any]) -> None:
        assert self._file is not None, "writer is closed"
        with naming(self.path):
            if self._writer is None:
                names = [name for name in fields if name in CSV_FIELDS]
                self._writer = csv.DictWriter(self._file, fieldnames=names, extrasaction="ignore")
                self._writer.writeheader()
            self._writer.writerow({k: "" if v is None else v for k, v in fields.items()})

    def close(self) -> None:
        if self._file is not None:
            file, self._file = self._file, None
            with naming(self.path):
                file.close()
