"""Helpers of the MCAP and Foxglove tests: real frame records from the one loop with a scripted
detector (no MediaPipe), and an MCAP file read back with the `mcap` reader."""

from __future__ import annotations

import json
from collections import defaultdict
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from fakes import ScriptedDetector, numbered_image
from roadgaze.capture import SourceInfo, SourceStatus
from roadgaze.config import Config
from roadgaze.pipeline import Pipeline
from roadgaze.types import ClosesOnExit, Detection, Frame, FrameRecord

FPS = 30.0
GLANCE_YAWS = [0.0] * 30 + [-60.0] * 150 + [0.0] * 30
"""1 s on the road, 5 s turned 60 deg away (a long distraction, then critical), 1 s back."""


class NumberedSource(ClosesOnExit):
    """A file-like source of `count` numbered images at `fps`."""

    def __init__(self, count: int, fps: float = FPS, size: tuple[int, int] = (160, 120)) -> None:
        self.count, self.fps, self.size = count, fps, size
        self._status = SourceStatus()

    @property
    def info(self) -> SourceInfo:
        return SourceInfo("numbered", False, self.fps, self.count, *self.size)

    @property
    def status(self) -> SourceStatus:
        return self._status

    def __iter__(self) -> Any:
        for index in range(self.count):
            self._status = SourceStatus(frames_delivered=index + 1)
            yield Frame(index, index / self.fps, numbered_image(index, self.size))

    def close(self) -> None:
        return None


class FaceDetector(ScriptedDetector):
    """`ScriptedDetector` whose face carries landmarks (a small grid inside the box)."""

    def detect(self, image: np.ndarray, t_s: float | None = None) -> Detection:
        detection = super().detect(image, t_s)
        if detection.driver is None:
            return detection
        face = detection.driver
        x0, y0, x1, y1 = face.box_px
        steps = [(i / 4, j / 4) for i in range(5) for j in range(5)]
        grid = np.array(
            [[x0 + (x1 - x0) * u, y0 + (y1 - y0) * v, 0.0] for u, v in steps], np.float32
        )
        return Detection(faces=(replace(face, landmarks_px=grid),), driver_index=0)


def pipeline_records(
    yaws: list[float | None] | None = None, fps: float = FPS, size: tuple[int, int] = (160, 120)
) -> list[tuple[FrameRecord, Frame]]:
    """The records (and frames) the one loop makes of numbered frames with these true yaws."""
    yaws = GLANCE_YAWS if yaws is None else yaws
    pipeline = Pipeline.from_config(Config(), FaceDetector(list(yaws)))
    source = NumberedSource(len(yaws), fps, size)
    return [(p.record, p.frame) for p in pipeline.frames(source)]


@dataclass
class McapContents:
    """What the `mcap` reader found in a file."""

    schemas: dict[str, str] = field(default_factory=dict)
    """topic -> schema name."""
    encodings: dict[str, tuple[str, str]] = field(default_factory=dict)
    """topic -> (schema encoding, message encoding)."""
    counts: dict[str, int] = field(default_factory=dict)
    """topic -> message count from the summary's statistics."""
    messages: dict[str, list[Any]] = field(default_factory=lambda: defaultdict(list))
    """topic -> the messages (`mcap.records.Message`) in log-time order."""
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    schema_data: dict[str, bytes] = field(default_factory=dict)

    def json(self, topic: str) -> list[dict[str, Any]]:
        return [json.loads(message.data) for message in self.messages[topic]]


def read_mcap(path: Path) -> McapContents:
    """Every channel, schema, count, message and metadata record of a complete MCAP file."""
    from mcap.reader import make_reader

    contents = McapContents()
    with path.open("rb") as handle:
        reader = make_reader(handle)
        summary = reader.get_summary()
        assert summary is not None, f"{path} has no summary"
        for channel in summary.channels.values():
            schema = summary.schemas.get(channel.schema_id)
            contents.schemas[channel.topic] = schema.name if schema else ""
            contents.encodings[channel.topic] = (
                schema.encoding if schema else "",
                channel.message_encoding,
            )
            contents.schema_data[channel.topic] = schema.data if schema else b""
            contents.counts[channel.topic] = summary.statistics.channel_message_counts.get(
                channel.id, 0
            )
        for _, channel, message in reader.iter_messages(log_time_order=True):
            contents.messages[channel.topic].append(message)
        contents.metadata = {
            record.name: dict(record.metadata) for record in reader.iter_metadata()
        }
    return contents


def protobuf_message(contents: McapContents, topic: str, data: bytes) -> Any:
    """A protobuf message of `topic` decoded with the schema stored in the file."""
    from roadgaze.capture.mcap_images import protobuf_class

    return protobuf_class(contents.schemas[topic], contents.schema_data[topic])(data)
