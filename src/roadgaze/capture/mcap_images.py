"""Camera frames in MCAP messages: `foxglove.CompressedImage` (JPEG, PNG) and `foxglove.RawImage`,
encoded as protobuf (what foxglove-sdk writes) or JSON, decoded to BGR with their header stamp.

A protobuf schema in MCAP is a `FileDescriptorSet`: the message class is built from it with the
protobuf runtime (no generated code), so any writer's copy of the Foxglove schemas reads.
"""

from __future__ import annotations

import base64
import json
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.capture.base import as_bgr
from roadgaze.errors import SourceError

COMPRESSED_IMAGE = "foxglove.CompressedImage"
RAW_IMAGE = "foxglove.RawImage"
IMAGE_SCHEMAS = (COMPRESSED_IMAGE, RAW_IMAGE)
RAW_CHANNELS = {
    "bgr8": 3,
    "rgb8": 3,
    "8UC3": 3,
    "bgra8": 4,
    "rgba8": 4,
    "mono8": 1,
    "8UC1": 1,
    "mono16": 1,
    "16UC1": 1,
}
"""The `RawImage.encoding`s read, with their channels (16-bit grey is shifted to 8 bits)."""


@dataclass(frozen=True, slots=True)
class CameraImage:
    """One decoded camera frame; `stamp_ns` 0 when the message's header had no time."""

    image: npt.NDArray[np.uint8]
    stamp_ns: int


def protobuf_class(name: str, descriptor_set: bytes) -> Callable[[bytes], Any]:
    """The parser of message `name` from a serialised `FileDescriptorSet` (an MCAP protobuf
    schema). Raises `SourceError` when the set does not describe it."""
    from google.protobuf import (  # type: ignore[import-untyped]
        descriptor_pb2,
        descriptor_pool,
        message_factory,
    )

    try:
        files = descriptor_pb2.FileDescriptorSet.FromString(descriptor_set)
        pending = {file.name: file for file in files.file}
        pool = descriptor_pool.DescriptorPool()
        added: set[str] = set()

        def add(file_name: str) -> None:
            if file_name in added:
                return
            added.add(file_name)
            for dependency in pending[file_name].dependency:
                if dependency in pending:
                    add(dependency)
            pool.Add(pending[file_name])

        for file_name in pending:
            add(file_name)
        message_class = message_factory.GetMessageClass(pool.FindMessageTypeByName(name))
    except Exception as exc:  # protobuf raises several types for a bad descriptor set
        raise SourceError(f"the MCAP schema {name} cannot be read: {exc}") from None
    parse: Callable[[bytes], Any] = message_class.FromString
    return parse


def _stamp_ns(stamp: Any) -> int:
    if stamp is None:
        return 0
    if isinstance(stamp, dict):
        return int(stamp.get("sec", 0)) * 1_000_000_000 + int(stamp.get("nsec", 0))
    return int(stamp.seconds) * 1_000_000_000 + int(stamp.nanos)


def _field(message: Any, name: str) -> Any:
    return message.get(name) if isinstance(message, dict) else getattr(message, name)


def _bytes(value: Any) -> bytes:
    return base64.b64decode(value) if isinstance(value, str) else bytes(value)


def decode_compressed(data: bytes) -> npt.NDArray[np.uint8] | None:
    """A JPEG or PNG (any format OpenCV reads) as BGR; None when it does not decode."""
    import cv2

    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    return None if image is None else as_bgr(image)


def decode_raw(
    width: int, height: int, encoding: str, step: int, data: bytes
) -> npt.NDArray[np.uint8]:
    """A `RawImage`'s pixels as BGR; raises `SourceError` for an encoding not in RAW_CHANNELS or
    a size that does not match."""
    import cv2

    channels = RAW_CHANNELS.get(encoding)
    if channels is None:
        raise SourceError(
            f"RawImage encoding {encoding!r} is not read; supported: {', '.join(RAW_CHANNELS)}"
        )
    depth = 2 if encoding in ("mono16", "16UC1") else 1
    row = width * channels * depth
    step = step or row
    if width <= 0 or height <= 0 or step < row or len(data) < step * (height - 1) + row:
        raise SourceError(f"RawImage of {width}x{height} {encoding} holds {len(data)} bytes")
    buffer = np.frombuffer(data, np.uint8, count=step * (height - 1) + row)
    rows = np.lib.stride_tricks.as_strided(buffer, (height, row), (step, 1))
    grid = np.ascontiguousarray(rows)
    if depth == 2:
        return as_bgr((grid.view("<u2").reshape(height, width) >> 8).astype(np.uint8))
    pixels = grid.reshape((height, width, channels) if channels > 1 else (height, width))
    conversion = {"rgb8": cv2.COLOR_RGB2BGR, "rgba8": cv2.COLOR_RGBA2BGR}.get(encoding)
    if conversion is not None:
        return np.asarray(cv2.cvtColor(pixels, conversion), dtype=np.uint8)
    return as_bgr(pixels)


class ImageDecoder:
    """Decodes the messages of one camera channel (its schema name, schema and encoding)."""

    def __init__(
        self, schema_name: str, schema_encoding: str, schema_data: bytes, message_encoding: str
    ) -> None:
        if schema_name not in IMAGE_SCHEMAS:
            raise SourceError(
                f"schema {schema_name} is not a camera image ({', '.join(IMAGE_SCHEMAS)})"
            )
        self.raw = schema_name == RAW_IMAGE
        if message_encoding == "protobuf" and schema_encoding == "protobuf":
            self._parse: Callable[[bytes], Any] = protobuf_class(schema_name, schema_data)
        elif message_encoding == "json":
            self._parse = json.loads
        else:
            raise SourceError(
                f"camera messages encoded as {message_encoding!r} are not read (protobuf or json)"
            )

    def decode(self, data: bytes) -> CameraImage | None:
        """The frame of one message; None when its picture does not decode (corrupt)."""
        message = self._parse(data)
        stamp_ns = _stamp_ns(
            _field(message, "timestamp")
            if not isinstance(message, dict) or "timestamp" in message
            else None
        )
        pixels = _bytes(_field(message, "data") or b"")
        if self.raw:
            image = decode_raw(
                int(_field(message, "width") or 0),
                int(_field(message, "height") or 0),
                str(_field(message, "encoding") or ""),
                int(_field(message, "step") or 0),
                pixels,
            )
        else:
            decoded = decode_compressed(pixels)
            if decoded is None:
                return None
            image = decoded
        return CameraImage(image=image, stamp_ns=stamp_ns)
