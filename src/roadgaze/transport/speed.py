"""The vehicle speed input: the newest bus payload, parsed on the frame loop, fail-safe (pure).

The bus is untrusted: a payload over `SPEED_MAX_BYTES` is dropped unread, anything but a finite
speed within 0-`SPEED_MAX_KMH` km/h is rejected and makes the speed unknown, and no valid speed
for `timeout_s` makes it unknown too. Unknown counts as moving (alerts are not suppressed).
Receiving costs the Zenoh side nothing in Python: the link hands over a `receive()` that returns
the newest sample's payload or None (a ring of one), and `kmh()` takes it once per frame.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from typing import Literal, Protocol

from roadgaze.transport.payloads import SPEED_MAX_BYTES, PayloadError, parse_json_value
from roadgaze.transport.throttle import ThrottledWarning

log = logging.getLogger(__name__)

SPEED_MAX_KMH = 400.0
"""Fastest speed accepted; anything above is a broken or hostile sender."""

SpeedStatus = Literal["waiting", "fresh", "stale", "invalid"]


class Payload(Protocol):
    """What a Zenoh sample's payload offers (`zenoh.ZBytes`): its length and its bytes."""

    def __len__(self) -> int: ...

    def to_bytes(self) -> bytes: ...


def parse_speed_kmh(payload: bytes) -> float:
    """Speed from `{"kmh": <number>}` or a bare number, finite and within 0-400 km/h.

    Raises `PayloadError` (a ValueError) for anything else, including oversize payloads.
    """
    value = parse_json_value(payload, SPEED_MAX_BYTES)
    if isinstance(value, dict):
        if set(value) != {"kmh"}:
            raise PayloadError(f"expected {{'kmh': number}}, found keys {sorted(value)[:5]}")
        value = value["kmh"]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise PayloadError(f"speed must be a number, found {type(value).__name__}")
    try:
        speed = float(value)
    except OverflowError:
        raise PayloadError("speed is not a finite number") from None
    if not math.isfinite(speed) or not 0.0 <= speed <= SPEED_MAX_KMH:
        raise PayloadError(f"speed must be finite and within 0-{SPEED_MAX_KMH:g} km/h")
    return speed


class SpeedInput:
    """The speed the monitor uses: `kmh()` on the frame loop, `current()` from any thread.

    Payloads come from `attach(receive)` (the link's ring of one, read once per frame) or are
    pushed with `on_payload` (tests, other transports); only the newest is parsed. Counters:
    `messages` (payloads taken), `oversize` (dropped unread), `rejected` (not a valid speed).
    """

    def __init__(self, timeout_s: float = 2.0, clock: Callable[[], float] = time.monotonic) -> None:
        self._timeout_s = timeout_s
        self._clock = clock
        self._lock = threading.Lock()
        self._receive: Callable[[], Payload | None] | None = None
        self._pushed: bytes | None = None
        self._speed_kmh: float | None = None
        self._valid_at: float | None = None
        self._invalid = False
        self.messages = 0
        self.oversize = 0
        self.rejected = 0
        self._warn = ThrottledWarning(log, "ignored speed message")

    def attach(self, receive: Callable[[], Payload | None]) -> None:
        """Read payloads from `receive()` (newest or None; it must never block)."""
        self._receive = receive

    def on_payload(self, payload: bytes) -> None:
        """Keep `payload` as the newest (O(1): parsed later by `kmh()`)."""
        with self._lock:
            self._pushed = payload

    def _take(self) -> bytes | None:
        with self._lock:
            raw, self._pushed = self._pushed, None
        payload = self._receive() if self._receive is not None else None
        if payload is None:
            if raw is not None:
                self.messages += 1
            return raw
        self.messages += 1
        if len(payload) > SPEED_MAX_BYTES:
            self.oversize += 1
            self._warn(f"{len(payload)} bytes, limit {SPEED_MAX_BYTES}: dropped unread")
            return None
        return payload.to_bytes()

    def kmh(self) -> float | None:
        """The speed for this frame, in km/h; None when unknown (taken as moving)."""
        raw = self._take()
        if raw is not None:
            try:
                speed = parse_speed_kmh(raw)
            except PayloadError as exc:
                self.rejected += 1
                self._warn(f"{exc}; speed unknown (taken as moving) until a valid one")
                with self._lock:
                    self._invalid = True
            else:
                with self._lock:
                    self._speed_kmh, self._valid_at, self._invalid = speed, self._clock(), False
        return self.current()[0]

    def current(self) -> tuple[float | None, SpeedStatus]:
        """The speed in use (None: unknown, taken as moving) and where it stands."""
        with self._lock:
            if self._invalid:
                return None, "invalid"
            if self._valid_at is None:
                return None, "waiting"
            if self._clock() - self._valid_at > self._timeout_s:
                return None, "stale"
            return self._speed_kmh, "fresh"
