"""COVESA VSS 6.0 driver signals from the frame record, in Eclipse Kuksa's Zenoh convention. Pure.

Each signal is published on its VSS path with `.` replaced by `/` (e.g.
`Vehicle/Driver/IsEyesOnRoad`), under `zenoh.vss_prefix` when one is configured (Kuksa assumes one
vehicle per Zenoh network and bare paths), the value as text (`true`/`false`, decimal numbers)
with the attachment `currentValue`, which Kuksa's zenoh-kuksa-provider requires before it
forwards a sample to the databroker. A value is sent when it changes, at most `VSS_MAX_RATE_HZ`
times a second per signal on the source timeline; a change held back is sent once the interval
has passed, so the last value always arrives. Every value is also sent again `VSS_REFRESH_S`
after it was last sent, so a subscriber that joins late (or a Kuksa provider that restarted)
has the whole state within a second, and a silent key means a silent service.

Values (definitions and how the levels are computed: docs/zenoh.md):

- `IsEyesOnRoad`: on the road with the eyes not closed; false when unknown (fail-safe).
- `DistractionLevel` = 100 min(1, max(distraction_s / warn_s, window_off_road_s /
  vats_threshold_s)), warn_s the distraction time that warns at this speed under the configured
  protocol(s) (`long_distraction_s` when none is active): 100 % exactly when `long_distraction`
  or `vats` is due.
- `FatigueLevel` = 100 min(1, max(PERCLOS / perclos_drowsy, long blinks / long_blinks_drowsy,
  closure_s / microsleep_s)): 100 % exactly when `drowsy` or `microsleep` is due.
- `AttentiveProbability` = q (100 - max(distraction, fatigue)) + (1 - q) 50, q the confidence
  of the measurement (1 with the eyes judged, 0.6 on head pose only, 0 without a face). A
  heuristic, not a calibrated probability.
- `HeadPosition.Yaw/Pitch` and `MidEyeGaze.Azimuth/Elevation`: relative to the learned
  road-ahead pose (VSS's "normal position"), degrees, yaw > 0 = turned left, pitch > 0 = up;
  `HeadPosition.Roll` > 0 = leaning to the right (the project's roll). Not sent when unknown.
- `ADAS.DMS.IsWarning`: an alert is active; `ADAS.DMS.IsError`: monitoring degraded (the eyes
  unavailable too long) or a temporary failure in force (blocked, black, saturated or frozen
  frames, no judgeable face; docs/monitor.md, "Failures"); a permanent failure (camera gone)
  sends `IsError` and `IsWarning` true when raised, false when cleared (`publish_failure`).
- `ADAS.DMS.Support.Forward.IsHeightened`, `ADAS.DMS.Support.Lane.IsHeightened`: forward and
  lane support (the support message). VSS 6.0 has no standard path for them: they are
  roadgaze's overlay branch (docs/vss/roadgaze-support.vspec); true when unknown (fail-safe).
"""

from __future__ import annotations

import math
import re
from typing import Protocol

from roadgaze.config import MonitorConfig
from roadgaze.monitor.behaviours.support import HEIGHTENED, support_output
from roadgaze.monitor.protocols.support import FORWARD, LANE
from roadgaze.transport.payloads import PayloadError, printable
from roadgaze.types import Alert, AlertKind, EyeStatus, Frame, FrameRecord, Gaze

__all__ = [
    "SUPPORT_PATHS",
    "VSS_ATTACHMENT",
    "VSS_MAX_RATE_HZ",
    "VSS_PATHS",
    "VSS_REFRESH_S",
    "VssLink",
    "VssPublisher",
    "parse_vss_text",
    "vss_key",
    "vss_text",
    "vss_values",
]

VSS_MAX_RATE_HZ = 10.0
VSS_REFRESH_S = 1.0
VSS_ATTACHMENT = b"currentValue"
"""Kuksa's zenoh-kuksa-provider forwards only samples with this attachment."""
DRIVER = "Vehicle.Driver"
HEAD = "Vehicle.Occupant.Row1.DriverSide.HeadPosition"
GAZE = "Vehicle.Occupant.Row1.DriverSide.MidEyeGaze"
DMS = "Vehicle.ADAS.DMS"
SUPPORT = f"{DMS}.Support"
"""roadgaze's overlay branch (not in VSS 6.0): forward and lane support."""
SUPPORT_PATHS = {FORWARD: f"{SUPPORT}.Forward.IsHeightened", LANE: f"{SUPPORT}.Lane.IsHeightened"}
VSS_PATHS: tuple[str, ...] = (
    f"{DRIVER}.IsEyesOnRoad",
    f"{DRIVER}.DistractionLevel",
    f"{DRIVER}.AttentiveProbability",
    f"{DRIVER}.FatigueLevel",
    f"{HEAD}.Yaw",
    f"{HEAD}.Pitch",
    f"{HEAD}.Roll",
    f"{GAZE}.Azimuth",
    f"{GAZE}.Elevation",
    f"{DMS}.IsWarning",
    f"{DMS}.IsError",
    *SUPPORT_PATHS.values(),
)

VssValue = bool | float

_PERCENT = (0.0, 100.0)
_ANGLE = (-180.0, 180.0)
VSS_RANGES: dict[str, tuple[float, float] | None] = {
    f"{DRIVER}.IsEyesOnRoad": None,
    f"{DRIVER}.DistractionLevel": _PERCENT,
    f"{DRIVER}.AttentiveProbability": _PERCENT,
    f"{DRIVER}.FatigueLevel": _PERCENT,
    f"{HEAD}.Yaw": _ANGLE,
    f"{HEAD}.Pitch": (-90.0, 90.0),
    f"{HEAD}.Roll": _ANGLE,
    f"{GAZE}.Azimuth": _ANGLE,
    f"{GAZE}.Elevation": (-90.0, 90.0),
    f"{DMS}.IsWarning": None,
    f"{DMS}.IsError": None,
    **dict.fromkeys(SUPPORT_PATHS.values()),
}
"""The type of each signal roadgaze publishes: None for a boolean, else the allowed range."""
VSS_MAX_CHARS = 64
_DECIMAL = re.compile(r"-?[0-9]{1,6}(\.[0-9]{1,6})?")


def vss_key(path: str, prefix: str = "") -> str:
    """The Zenoh key of a VSS path: dots become slashes, under `prefix` when one is given."""
    key = path.replace(".", "/")
    prefix = prefix.strip("/")
    return f"{prefix}/{key}" if prefix else key


def parse_vss_text(key: str, raw: bytes, prefix: str = "") -> str:
    """Check one VSS value received from the bus (untrusted) and return its text.

    A signal roadgaze publishes must be `true`/`false` or a finite decimal number inside its
    range (`VSS_RANGES`); any other key under `Vehicle/` (another provider's) must be printable
    UTF-8 text of at most `VSS_MAX_CHARS` characters. Raises `PayloadError` saying why not.
    """
    if len(raw) > 4 * VSS_MAX_CHARS:
        raise PayloadError(f"value of {len(raw)} bytes, limit {4 * VSS_MAX_CHARS}")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise PayloadError("value is not UTF-8") from None
    prefix = prefix.strip("/")
    path = (key[len(prefix) + 1 :] if prefix and key.startswith(prefix + "/") else key).replace(
        "/", "."
    )
    if path not in VSS_RANGES:
        if len(text) > VSS_MAX_CHARS or printable(text, VSS_MAX_CHARS) != text:
            raise PayloadError(f"value {printable(text, 20)!r} is not short printable text")
        return text
    limits = VSS_RANGES[path]
    if limits is None:
        if text not in ("true", "false"):
            raise PayloadError(f"{path} must be true or false, found {printable(text, 20)!r}")
        return text
    if not _DECIMAL.fullmatch(text):
        raise PayloadError(f"{path} must be a decimal number, found {printable(text, 20)!r}")
    number = float(text)
    if not (math.isfinite(number) and limits[0] <= number <= limits[1]):
        raise PayloadError(f"{path} = {text} is outside {limits[0]:g}..{limits[1]:g}")
    return text


def vss_text(value: VssValue) -> bytes:
    """The value as Kuksa reads it: `true`/`false`, or a decimal number."""
    if isinstance(value, bool):
        return b"true" if value else b"false"
    return repr(float(value)).encode("ascii")


def _relative(value: float | None, neutral: float, pitch: bool = False) -> float | None:
    """`value - neutral` in degrees, rounded to 0.1, within VSS's range: a yaw wrapped into
    -180..180 (a full-range yaw of -179 with a neutral of +5 is +176, not -184), a pitch held
    within -90..90; None when unknown."""
    if value is None or not math.isfinite(value):
        return None
    if pitch:
        return round(min(90.0, max(-90.0, value - neutral)), 1)
    return round((value - neutral + 180.0) % 360.0 - 180.0, 1)


def vss_values(record: FrameRecord, config: MonitorConfig) -> dict[str, VssValue]:
    """The signals of one frame record (VSS path -> value); unknown angles are left out."""
    sample, verdict = record.sample, record.verdict
    eyes = verdict.eyes
    distraction = 100.0 * min(
        1.0,
        max(
            verdict.distraction_s / (verdict.distraction_warn_s or config.long_distraction_s),
            verdict.window_off_road_s / config.vats_threshold_s,
        ),
    )
    fatigue = 100.0 * min(
        1.0,
        max(
            0.0 if eyes.perclos is None else eyes.perclos / config.perclos_drowsy,
            eyes.long_blinks / config.long_blinks_drowsy,
            eyes.closure_s / config.microsleep_s,
        ),
    )
    if eyes.status is not EyeStatus.UNAVAILABLE:
        confidence = 1.0
    elif verdict.gaze is not Gaze.UNKNOWN:
        confidence = 0.6
    else:
        confidence = 0.0
    attentive = confidence * (100.0 - max(distraction, fatigue)) + (1.0 - confidence) * 50.0
    values: dict[str, VssValue] = {
        f"{DRIVER}.IsEyesOnRoad": verdict.eyes_on_road is True,
        f"{DRIVER}.DistractionLevel": round(distraction, 1),
        f"{DRIVER}.AttentiveProbability": round(attentive, 1),
        f"{DRIVER}.FatigueLevel": round(fatigue, 1),
        f"{DMS}.IsWarning": bool(verdict.active),
        f"{DMS}.IsError": eyes.degraded or bool(verdict.failure),
    }
    for channel, path in SUPPORT_PATHS.items():
        output = support_output(verdict, channel)
        values[path] = output is None or output.value == HEIGHTENED
    angles = {
        f"{HEAD}.Yaw": _relative(verdict.yaw_deg, verdict.neutral_yaw_deg),
        f"{HEAD}.Pitch": _relative(verdict.pitch_deg, verdict.neutral_pitch_deg, pitch=True),
        f"{HEAD}.Roll": _relative(sample.roll_deg, 0.0),
        f"{GAZE}.Azimuth": _relative(eyes.gaze_yaw_deg, verdict.neutral_yaw_deg),
        f"{GAZE}.Elevation": _relative(eyes.gaze_pitch_deg, verdict.neutral_pitch_deg, pitch=True),
    }
    values.update({path: value for path, value in angles.items() if value is not None})
    return values


class VssLink(Protocol):
    """Where VSS values go: `ZenohLink.publish_vss` in production, a list in tests."""

    def publish_vss(self, key: str, payload: bytes) -> None: ...


class VssPublisher:
    """Pipeline sink: each VSS signal on change, at most `max_rate_hz` per signal, and again
    every `refresh_s` without a change.

    Time is the records' `t_s` (the source timeline), so a replay publishes what the vehicle
    would have; a change held back by the rate limit is sent with the first record after the
    interval, unless the value came back to what was last sent.
    """

    def __init__(
        self,
        link: VssLink,
        config: MonitorConfig,
        prefix: str = "",
        max_rate_hz: float = VSS_MAX_RATE_HZ,
        refresh_s: float = VSS_REFRESH_S,
    ) -> None:
        self.link = link
        self.config = config
        self.keys = {path: vss_key(path, prefix) for path in VSS_PATHS}
        self.min_interval_s = 1.0 / max_rate_hz
        self.refresh_s = refresh_s
        self._sent: dict[str, tuple[VssValue, float]] = {}
        self.published = 0

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        t_s = record.t_s
        for path, value in vss_values(record, self.config).items():
            last = self._sent.get(path)
            if last is not None:
                since_s = t_s - last[1]
                due = since_s >= self.refresh_s - 1e-9 or (
                    last[0] != value and since_s >= self.min_interval_s - 1e-9
                )
                if not due:
                    continue
            self.link.publish_vss(self.keys[path], vss_text(value))
            self._sent[path] = (value, t_s)
            self.published += 1

    def on_alert(self, alert: Alert) -> None:
        """An alert raised outside the frame loop: a permanent failure sets `IsError` and
        `IsWarning` now, its `cleared` unsets them (a record would come too late or never)."""
        if alert.kind is AlertKind.PERMANENT_FAILURE:
            self.publish_failure(True)
        elif AlertKind.PERMANENT_FAILURE in alert.clears:
            self.publish_failure(False)

    def publish_failure(self, failed: bool) -> None:
        """Send `ADAS.DMS.IsError` (and `IsWarning`) now: a permanent failure raised or cleared
        outside the frame loop, when no record comes to carry it."""
        for path in (f"{DMS}.IsError", f"{DMS}.IsWarning"):
            self.link.publish_vss(self.keys[path], vss_text(failed))
            self.published += 1

    def close(self) -> None:
        """Nothing to release: the link is owned by whoever opened it."""
