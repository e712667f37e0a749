"""The driver a recording chose, read back with its camera frames (`/roadgaze/driver`).

roadgaze's recorder logs, just before each camera frame and with the same log time, one JSON
message on `DRIVER_TOPIC` (`roadgaze.driver/1`): `box_px`, the driver's face box in the pixels of
that recorded image (x_min, y_min, x_max, y_max; null when it had no driver), `n_faces` and
`driver_ambiguous` (why the driver could not be told from another face, '' when it could). A
replay of the recording follows that box (`roadgaze.landmarks.driver_track`), so a drive and its
recording judge the same person. The file is untrusted: a message that is not such an object is
ignored (counted, the first one logged) and its frame chooses its driver afresh.
"""

from __future__ import annotations

import json
import logging
import math
from collections import OrderedDict
from typing import Any

from roadgaze.types import RecordedDriver

log = logging.getLogger(__name__)

DRIVER_TOPIC = "/roadgaze/driver"
DRIVER_SCHEMA_NAME = "roadgaze.driver/1"
DRIVER_MESSAGE_MAX_BYTES = 4096
"""A driver message longer than this is not read."""
DRIVERS_WAITING = 16
"""Driver messages kept for frames still to come (each is taken by the frame of its log time)."""
MAX_COORDINATE_PX = 1e6


def driver_json_schema() -> dict[str, Any]:
    """The JSON Schema of `DRIVER_TOPIC`'s messages."""
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": DRIVER_SCHEMA_NAME,
        "description": "The driver chosen on the camera frame of the same log time: the face box "
        "in that image's pixels (null: no driver), the faces found and why the driver could not "
        "be told from another face ('' when it could).",
        "type": "object",
        "properties": {
            "box_px": {
                "type": ["array", "null"],
                "items": {"type": "number"},
                "minItems": 4,
                "maxItems": 4,
            },
            "n_faces": {"type": "integer", "minimum": 0},
            "driver_ambiguous": {"type": "string"},
        },
        "required": ["box_px", "n_faces", "driver_ambiguous"],
    }


def driver_message(
    box_px: tuple[float, float, float, float] | None, n_faces: int, driver_ambiguous: str
) -> dict[str, Any]:
    """One driver message (see the module doc); `box_px` in the recorded image's pixels."""
    box = None if box_px is None else [round(float(value), 2) for value in box_px]
    return {"box_px": box, "n_faces": n_faces, "driver_ambiguous": driver_ambiguous}


def parse_driver(data: bytes) -> RecordedDriver | None:
    """The driver of one message; None when it is not a well-formed driver message."""
    if len(data) > DRIVER_MESSAGE_MAX_BYTES:
        return None
    try:
        message = json.loads(data)
    except (ValueError, RecursionError):
        return None
    if not isinstance(message, dict) or "box_px" not in message:
        return None
    box = message["box_px"]
    if box is None:
        return RecordedDriver(None)
    if not isinstance(box, list) or len(box) != 4:
        return None
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in box):
        return None
    x_min, y_min, x_max, y_max = (float(value) for value in box)
    values = (x_min, y_min, x_max, y_max)
    if not all(math.isfinite(v) and abs(v) <= MAX_COORDINATE_PX for v in values):
        return None
    if not (x_min < x_max and y_min < y_max):
        return None
    return RecordedDriver(values)


class RecordedDrivers:
    """The driver messages read ahead of their camera frames, by log time (bounded)."""

    def __init__(self) -> None:
        self._waiting: OrderedDict[int, RecordedDriver] = OrderedDict()
        self.ignored = 0
        """Driver messages that were not well formed."""

    def note(self, log_time_ns: int, data: bytes) -> None:
        """A message of `DRIVER_TOPIC`, for the frame of the same log time."""
        driver = parse_driver(bytes(data))
        if driver is None:
            self.ignored += 1
            if self.ignored == 1:
                log.warning(
                    "ignoring a malformed driver message at log time %d ns (its frame chooses "
                    "its driver afresh)",
                    log_time_ns,
                )
            return
        self._waiting[log_time_ns] = driver
        while len(self._waiting) > DRIVERS_WAITING:
            self._waiting.popitem(last=False)

    def take(self, log_time_ns: int) -> RecordedDriver | None:
        """The driver recorded for the camera frame logged at `log_time_ns` (None: none was)."""
        return self._waiting.pop(log_time_ns, None)
