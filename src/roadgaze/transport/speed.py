"""The vehicle speed input: parsed, validated and kept thread-safe for the monitor (pure)."""

from __future__ import annotations

import json
import logging
import math
import threading
import time
from collections.abc import Callable
from typing import Literal

log = logging.getLogger(__name__)


def parse_speed_kmh(payload: bytes) -> float:
    """Speed from a speed message: `{"kmh": <number>}` or a bare number; ValueError otherwise."""
    try:
        value = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"not JSON: {payload[:60]!r}") from exc
    if isinstance(value, dict):
        if set(value) != {"kmh"}:
            raise ValueError(f"expected {{'kmh': number}}, found keys {sorted(value)}")
        value = value["kmh"]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"speed must be a number, found {value!r}")
    speed = float(value)
    if not math.isfinite(speed) or speed < 0:
        raise ValueError(f"speed must be finite and >= 0, found {speed}")
    return speed


class SpeedInput:
    """The latest speed received, thread-safe; stale after `stale_s` of wall time."""

    def __init__(self, stale_s: float, clock: Callable[[], float] = time.monotonic) -> None:
        self._stale_s = stale_s
        self._clock = clock
        self._lock = threading.Lock()
        self._speed_kmh: float | None = None
        self._received_at: float | None = None
        self.messages = 0
        self.rejected = 0

    def on_payload(self, payload: bytes) -> None:
        try:
            speed = parse_speed_kmh(payload)
        except ValueError as exc:
            with self._lock:
                self.rejected += 1
                count = self.rejected
            if count <= 10 or count % 100 == 0:
                log.warning("ignored speed message (%d so far): %s", count, exc)
            return
        with self._lock:
            self._speed_kmh, self._received_at = speed, self._clock()
            self.messages += 1

    def kmh(self) -> float | None:
        """The speed the monitor should use: None when unknown (none yet, or stale)."""
        return self.current()[0]

    def current(self) -> tuple[float | None, Literal["waiting", "fresh", "stale"]]:
        """The speed to use (None: unknown, taken as moving) and where it stands."""
        with self._lock:
            if self._received_at is None:
                return None, "waiting"
            if self._clock() - self._received_at > self._stale_s:
                return None, "stale"
            return self._speed_kmh, "fresh"
