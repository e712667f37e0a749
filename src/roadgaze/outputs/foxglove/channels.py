"""The channels of a recording and of the live view, and the messages of one frame.

Well-known Foxglove schemas where one fits: the camera frames (`foxglove.CompressedImage`), the
face's box, boundaries, centre line and landmarks with the verdict's text
(`foxglove.ImageAnnotations`, in the pixels of the recorded image, with each camera frame they
are drawn on) and the logs (`foxglove.Log`). JSON Schema channels for roadgaze's own: the
frame record (`record_fields`, every frame; its schema derived from `RECORD_SCHEMA`, so a new
field flows in without a change here), the monitor's limits (the road zone around the learned
neutral, the timers' thresholds; when the neutral moves, and at least every state interval),
the alerts, the state and forward and lane support (every frame; the messages `roadgaze
schema` prints, named by their version, so a new alert kind or field flows in too), and the
driver chosen on each recorded camera frame (`/roadgaze/driver`, `roadgaze.capture.mcap_driver`:
a replay of the recording follows it). Every message is stamped with its frame's capture time
(`log_time` = `publish_time`, and the header stamps).
"""

from __future__ import annotations

import json
import logging
from collections.abc import Iterable
from typing import Any

import foxglove
import numpy as np
import numpy.typing as npt
from foxglove.channels import CompressedImageChannel, ImageAnnotationsChannel, LogChannel
from foxglove.messages import (
    Color,
    CompressedImage,
    ImageAnnotations,
    Log,
    LogLevel,
    Point2,
    PointsAnnotation,
    PointsAnnotationType,
    TextAnnotation,
    Timestamp,
)

from roadgaze.capture.mcap_driver import (
    DRIVER_SCHEMA_NAME,
    DRIVER_TOPIC,
    driver_json_schema,
    driver_message,
)
from roadgaze.config import MonitorConfig
from roadgaze.errors import RoadgazeError
from roadgaze.outputs.annotate import face_lines_px, verdict_text
from roadgaze.outputs.foxglove.hand_annotations import hand_annotations
from roadgaze.outputs.hand_record import HAND_JSON_SCHEMA
from roadgaze.outputs.plots import road_bands_deg, road_pitch_bands_deg, timer_thresholds
from roadgaze.outputs.records import RECORD_SCHEMA, FieldType, record_fields, rounded
from roadgaze.transport.message_base import Message
from roadgaze.transport.messages import AlertMessage, StateMessage
from roadgaze.transport.support_message import SupportMessage
from roadgaze.types import Alert, FrameRecord

TOPIC_IMAGE = "/camera/image"
TOPIC_ANNOTATIONS = "/roadgaze/annotations"
TOPIC_RECORD = "/roadgaze/record"
TOPIC_LIMITS = "/roadgaze/limits"
TOPIC_ALERTS = "/roadgaze/alerts"
TOPIC_STATE = "/roadgaze/state"
TOPIC_SUPPORT = "/roadgaze/support"
TOPIC_LOG = "/roadgaze/log"
TOPIC_DRIVER = DRIVER_TOPIC
TOPICS = (
    TOPIC_IMAGE,
    TOPIC_DRIVER,
    TOPIC_ANNOTATIONS,
    TOPIC_RECORD,
    TOPIC_LIMITS,
    TOPIC_ALERTS,
    TOPIC_STATE,
    TOPIC_SUPPORT,
    TOPIC_LOG,
)
CAMERA_FRAME_ID = "driver_camera"
RECORD_SCHEMA_NAME = "roadgaze.record"
LIMITS_SCHEMA_NAME = "roadgaze.limits"

_JSON_TYPES: dict[FieldType, dict[str, Any]] = {
    FieldType.BOOL: {"type": ["boolean", "null"]},
    FieldType.INT: {"type": ["integer", "null"]},
    FieldType.FLOAT: {"type": ["number", "null"]},
    FieldType.STR: {"type": ["string", "null"]},
    FieldType.STR_LIST: {"type": ["array", "null"], "items": {"type": "string"}},
    FieldType.HANDS: {"type": ["array", "null"], "items": HAND_JSON_SCHEMA},
}
_LOG_LEVELS = {
    logging.DEBUG: LogLevel.Debug,
    logging.INFO: LogLevel.Info,
    logging.WARNING: LogLevel.Warning,
    logging.ERROR: LogLevel.Error,
    logging.CRITICAL: LogLevel.Fatal,
}
LIMIT_FIELDS = ("yaw_min_deg", "yaw_max_deg", "yaw_back_min_deg", "yaw_back_max_deg")
PITCH_LIMIT_FIELDS = ("pitch_min_deg", "pitch_max_deg", "pitch_back_min_deg", "pitch_back_max_deg")


def record_json_schema() -> dict[str, Any]:
    """The JSON Schema of the record channel: every field of `RECORD_SCHEMA`, each nullable."""
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": RECORD_SCHEMA_NAME,
        "description": "One frame's record, as `roadgaze replay --out` writes it "
        "(docs/pipeline.md); yaw > 0 = head turned to the driver's own left, pitch > 0 = up.",
        "type": "object",
        "properties": {name: dict(_JSON_TYPES[kind]) for name, kind in RECORD_SCHEMA},
        "required": [name for name, _ in RECORD_SCHEMA],
    }


def limits_fields(record: FrameRecord, monitor: MonitorConfig) -> dict[str, Any]:
    """The monitor's limits at this frame: the road zone's yaw and pitch bands around the learned
    neutral (left beyond `*_min/max_deg`, entered again within `*_back_*`) and the timers'
    thresholds, seconds (what the timers of the record are judged against)."""
    verdict = record.verdict
    yaw_bands = road_bands_deg(verdict.neutral_yaw_deg, monitor)
    pitch_bands = road_pitch_bands_deg(verdict.neutral_pitch_deg, monitor)
    fields: dict[str, Any] = {"t_s": round(record.t_s, 6)}
    for names, ((low, high), (back_low, back_high)) in (
        (LIMIT_FIELDS, yaw_bands),
        (PITCH_LIMIT_FIELDS, pitch_bands),
    ):
        for name, value in zip(names, (low, high, back_low, back_high), strict=True):
            fields[name] = rounded(value, 3)
    for key, seconds, _, _ in timer_thresholds(monitor):
        fields[key] = seconds
    return fields


def limits_json_schema(monitor: MonitorConfig) -> dict[str, Any]:
    """The JSON Schema of the limits channel."""
    names = ["t_s", *LIMIT_FIELDS, *PITCH_LIMIT_FIELDS]
    names += [key for key, *_ in timer_thresholds(monitor)]
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": LIMITS_SCHEMA_NAME,
        "description": "The monitor's limits at one frame: the road zone around the learned "
        "neutral (degrees; left beyond min/max, entered again within back_min/back_max) and "
        "the timers' thresholds (seconds).",
        "type": "object",
        "properties": {name: {"type": ["number", "null"]} for name in names},
        "required": names,
    }


def _json_schema(name: str, schema: dict[str, Any]) -> foxglove.Schema:
    return foxglove.Schema(name=name, encoding="jsonschema", data=json.dumps(schema).encode())


def _model_schema(model: type[Message]) -> foxglove.Schema:
    """A message model's JSON Schema (as `roadgaze schema` prints it), named by its version."""
    name = str(model.model_fields["schema_id"].default)
    return _json_schema(name, model.model_json_schema(by_alias=True, mode="serialization"))


def scaled_size(width: int, height: int, width_px: int) -> tuple[int, int]:
    """(width, height) of a `width` x `height` camera frame recorded at most `width_px` wide."""
    if width <= width_px:
        return width, height
    return width_px, max(1, round(height * width_px / width))


def timestamp(stamp_ns: int) -> Timestamp:
    seconds, nanoseconds = divmod(stamp_ns, 1_000_000_000)
    return Timestamp(seconds, nanoseconds)


def _colour(red: float, green: float, blue: float, alpha: float = 1.0) -> Color:
    return Color(r=red, g=green, b=blue, a=alpha)


BOX_COLOUR = _colour(0.6, 0.6, 0.6)
BOUNDARY_COLOUR = _colour(1.0, 0.78, 0.0)
CENTRE_COLOUR = _colour(0.0, 1.0, 0.0)
LANDMARK_COLOUR = _colour(0.3, 0.8, 1.0, 0.8)
TEXT_COLOUR = _colour(1.0, 1.0, 1.0)
TEXT_BACKGROUND = _colour(0.0, 0.0, 0.0, 0.55)
ALERT_BACKGROUND = _colour(0.85, 0.1, 0.1, 0.8)


def _points(pairs: Iterable[tuple[float, float]], scale: float) -> list[Point2]:
    return [Point2(x=float(x) * scale, y=float(y) * scale) for x, y in pairs]


def face_annotations(
    record: FrameRecord, stamp_ns: int, scale: float, with_landmarks: bool
) -> ImageAnnotations:
    """The frame's face box, boundaries (orange) and centre line (green) rotated back from the
    roll-removed frame, its landmarks (`with_landmarks`), the hands (`hand_annotations`), the
    verdict's line and the active alerts, in the pixels of the image scaled by `scale`."""
    stamp = timestamp(stamp_ns)

    def shape(
        kind: PointsAnnotationType, pairs: Iterable[Any], colour: Color, thickness: float
    ) -> PointsAnnotation:
        return PointsAnnotation(
            timestamp=stamp,
            type=kind,
            points=_points(pairs, scale),
            outline_color=colour,
            thickness=thickness,
        )

    def text(y_px: float, line: str, background: Color) -> TextAnnotation:
        return TextAnnotation(
            timestamp=stamp,
            position=Point2(x=8.0, y=y_px),
            text=line,
            font_size=14.0,
            text_color=TEXT_COLOUR,
            background_color=background,
        )

    points: list[PointsAnnotation] = []
    features = record.sample.features
    if features is not None:
        x_min, y_min, x_max, y_max = features.box_px
        corners = ((x_min, y_min), (x_max, y_min), (x_max, y_max), (x_min, y_max))
        points.append(shape(PointsAnnotationType.LineLoop, corners, BOX_COLOUR, 1.0))
        for name, ends in face_lines_px(features):
            colour = CENTRE_COLOUR if name == "centre" else BOUNDARY_COLOUR
            points.append(shape(PointsAnnotationType.LineStrip, ends.tolist(), colour, 2.0))
        if with_landmarks and len(features.landmarks_px):
            xy = features.landmarks_px[:, :2].tolist()
            points.append(shape(PointsAnnotationType.Points, xy, LANDMARK_COLOUR, 2.0))
    texts = [text(20.0, verdict_text(record), TEXT_BACKGROUND)]
    hand_points, hand_texts = hand_annotations(record, stamp, scale)
    points += hand_points
    texts += hand_texts
    if record.verdict.active:
        active = ", ".join(kind.value for kind in record.verdict.active)
        texts.append(text(42.0, f"ACTIVE: {active}", ALERT_BACKGROUND))
    return ImageAnnotations(timestamp=stamp, points=points, texts=texts)


class FrameChannels:
    """The channels of `TOPICS` on one Foxglove context, and what each frame logs on them.

    Every `log_*` takes the capture time `stamp_ns` (nanoseconds) it stamps the message with.
    Not thread-safe by itself: the recorder calls it under one lock.
    """

    def __init__(
        self,
        context: foxglove.Context,
        monitor: MonitorConfig,
        vehicle_id: str,
        limits_interval_ns: int = 1_000_000_000,
    ) -> None:
        self.monitor = monitor
        self.vehicle_id = vehicle_id
        self.limits_interval_ns = limits_interval_ns
        self._limits_neutral: tuple[float, float] | None = None
        self._limits_due_ns = 0
        self.image = CompressedImageChannel(TOPIC_IMAGE, context=context)
        self.annotations = ImageAnnotationsChannel(TOPIC_ANNOTATIONS, context=context)
        self.record = foxglove.Channel(
            TOPIC_RECORD,
            schema=_json_schema(RECORD_SCHEMA_NAME, record_json_schema()),
            message_encoding="json",
            context=context,
        )
        self.limits = foxglove.Channel(
            TOPIC_LIMITS,
            schema=_json_schema(LIMITS_SCHEMA_NAME, limits_json_schema(monitor)),
            message_encoding="json",
            context=context,
        )
        self.alerts = foxglove.Channel(
            TOPIC_ALERTS,
            schema=_model_schema(AlertMessage),
            message_encoding="json",
            context=context,
        )
        self.state = foxglove.Channel(
            TOPIC_STATE,
            schema=_model_schema(StateMessage),
            message_encoding="json",
            context=context,
        )
        self.support = foxglove.Channel(
            TOPIC_SUPPORT,
            schema=_model_schema(SupportMessage),
            message_encoding="json",
            context=context,
        )
        self.log = LogChannel(TOPIC_LOG, context=context)
        self.driver = foxglove.Channel(
            TOPIC_DRIVER,
            schema=_json_schema(DRIVER_SCHEMA_NAME, driver_json_schema()),
            message_encoding="json",
            context=context,
        )
        self.alerts_logged = 0
        self.support_logged = 0

    def log_frame(
        self,
        record: FrameRecord,
        stamp_ns: int,
        annotate: bool,
        scale: float,
        with_landmarks: bool,
        wall_time_s: float,
    ) -> None:
        """The record, the limits when they changed (or `limits_interval_ns` after the last),
        the annotations when `annotate` (the frame carries a camera image: they are drawn on
        it), and the alerts raised on this frame."""
        self.record.log(_json_bytes(record_fields(record)), log_time=stamp_ns)
        support = SupportMessage.from_record(
            record, self.vehicle_id, self.support_logged, wall_time_s
        )
        self.support.log(support.to_json_bytes(), log_time=stamp_ns)
        self.support_logged += 1
        verdict = record.verdict
        neutral = (verdict.neutral_yaw_deg, verdict.neutral_pitch_deg)
        if neutral != self._limits_neutral or stamp_ns >= self._limits_due_ns:
            self.limits.log(_json_bytes(limits_fields(record, self.monitor)), log_time=stamp_ns)
            self._limits_neutral = neutral
            self._limits_due_ns = stamp_ns + self.limits_interval_ns
        if annotate:
            annotations = face_annotations(record, stamp_ns, scale, with_landmarks)
            self.annotations.log(annotations, log_time=stamp_ns)
        for alert in record.alerts:
            self.log_alert(alert, stamp_ns, wall_time_s)

    def log_alert(self, alert: Alert, stamp_ns: int, wall_time_s: float) -> None:
        """One alert on the alerts channel (of a frame, or raised outside the loop)."""
        message = AlertMessage.from_alert(alert, self.vehicle_id, self.alerts_logged, wall_time_s)
        self.alerts.log(message.to_json_bytes(), log_time=stamp_ns)
        self.alerts_logged += 1

    def log_image(self, data: bytes, image_format: str, stamp_ns: int) -> None:
        message = CompressedImage(
            timestamp=timestamp(stamp_ns), frame_id=CAMERA_FRAME_ID, data=data, format=image_format
        )
        self.image.log(message, log_time=stamp_ns)

    def log_driver(
        self, record: FrameRecord, shape: tuple[int, ...], width_px: int, stamp_ns: int
    ) -> None:
        """The frame's driver, its box in the pixels of the frame's image (`shape`) as recorded
        at most `width_px` wide; logged just before that image (a replay reads it with it)."""
        height, width = shape[:2]
        size = scaled_size(width, height, width_px)
        sample, x, y = record.sample, size[0] / width, size[1] / height
        features = sample.features
        box = None if features is None else features.box_px
        scaled = None if box is None else (box[0] * x, box[1] * y, box[2] * x, box[3] * y)
        fields = driver_message(scaled, sample.n_faces, sample.driver_ambiguous)
        self.driver.log(_json_bytes(fields), log_time=stamp_ns)

    def log_state(self, payload: bytes, stamp_ns: int) -> None:
        self.state.log(payload, log_time=stamp_ns)

    def log_line(self, entry: logging.LogRecord, message: str, stamp_ns: int) -> None:
        line = Log(
            timestamp=timestamp(stamp_ns),
            level=_LOG_LEVELS.get(entry.levelno, LogLevel.Unknown),
            message=message,
            name=entry.name,
            file=entry.pathname,
            line=entry.lineno,
        )
        self.log.log(line, log_time=stamp_ns)


def encode_image(
    image: npt.NDArray[np.uint8], width_px: int, image_format: str, jpeg_quality: int
) -> bytes:
    """`image` (BGR) scaled down to `width_px` wide if wider, as JPEG or PNG bytes."""
    import cv2

    height, width = image.shape[:2]
    if width > width_px:
        size = scaled_size(width, height, width_px)
        image = np.asarray(cv2.resize(image, size, interpolation=cv2.INTER_AREA), np.uint8)
    if image_format == "png":
        ok, data = cv2.imencode(".png", image, [cv2.IMWRITE_PNG_COMPRESSION, 1])
    else:
        ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality])
    if not ok:
        raise RoadgazeError(f"cannot encode a {width}x{height} camera frame as {image_format}")
    return bytes(data)


_ENCODER = json.JSONEncoder(allow_nan=False, separators=(",", ":"))
"""One encoder for every message (`json.dumps` with options builds a new one each call)."""


def _json_bytes(fields: dict[str, Any]) -> bytes:
    return _ENCODER.encode(fields).encode()
