"""The vehicle speed on the bus: the speed message, its input and its publisher (pure).

Input: the bus is untrusted. A payload over `SPEED_MAX_BYTES` is dropped unread, anything but a
finite speed within 0-`SPEED_MAX_KMH` km/h (the one check, `roadgaze.speed.checked_kmh`) is
rejected and makes the speed unknown (`{"kmh": null}` is how a sender says it does not know), and
no valid speed for `timeout_s` makes it unknown too. Unknown counts as moving (alerts are not
suppressed). Receiving costs the Zenoh side nothing in Python: the link hands over a `receive()`
that returns the newest sample's payload or None (a ring of one), and `kmh()` takes it once per
frame.

Output: `publish_track` puts what `roadgaze speed` sends: a track's speed by its one rule
(`roadgaze.speed.SpeedTrack`), at `SPEED_RATE_HZ` and at each instant it changes, so a daemon fed
the track sees at every frame the speed a replay of the same track uses.
"""

from __future__ import annotations

import json
import logging
import math
import threading
import time
from collections.abc import Callable, Iterator
from typing import Literal, Protocol

from roadgaze.errors import SpeedError
from roadgaze.speed import MAX_KMH, SpeedTrack, checked_kmh
from roadgaze.transport.payloads import SPEED_MAX_BYTES, PayloadError, parse_json_value
from roadgaze.transport.throttle import ThrottledWarning

log = logging.getLogger(__name__)

SPEED_MAX_KMH = MAX_KMH
"""Fastest speed accepted; anything above is a broken or hostile sender."""
SPEED_RATE_HZ = 10.0
"""How often `roadgaze speed` publishes: well inside the daemon's 2 s `zenoh.speed_timeout_s`."""

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
    if value is None:
        raise PayloadError("kmh null: the sender does not know the speed")
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise PayloadError(f"speed must be a number, found {type(value).__name__}")
    try:
        return checked_kmh(float(value), "speed")
    except OverflowError:
        raise PayloadError("speed is not a finite number") from None
    except SpeedError as exc:
        raise PayloadError(str(exc)) from None


def speed_payload(kmh: float | None) -> bytes:
    """The speed message the daemon reads: `{"kmh": 57.5}`, or `{"kmh": null}` for unknown
    (the daemon takes it as unknown at once). Not rounded: the daemon gets the track's value."""
    return json.dumps({"kmh": kmh}).encode()


class SpeedInput:
    """The speed the monitor uses: `kmh()` on the frame loop, `current()` from any thread.

    Payloads come from `attach(receive)` (the link's ring of one, read once per frame) or are
    pushed with `on_payload` (tests, other transports); only the newest is parsed. Counters:
    `messages` (payloads taken), `oversize` (dropped unread), `rejected` (not a valid speed);
    either of the last two makes the speed unknown at once ("invalid").
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
            self._not_a_speed(f"{len(payload)} bytes, limit {SPEED_MAX_BYTES}: dropped unread")
            return None
        return payload.to_bytes()

    def _not_a_speed(self, why: str) -> None:
        """A payload that is not a speed (oversize or rejected): the speed is unknown at once."""
        self._warn(f"{why}; speed unknown (taken as moving) until a valid one")
        with self._lock:
            self._invalid = True

    def kmh(self) -> float | None:
        """The speed for this frame, in km/h; None when unknown (taken as moving)."""
        raw = self._take()
        if raw is not None:
            try:
                speed = parse_speed_kmh(raw)
            except PayloadError as exc:
                self.rejected += 1
                self._not_a_speed(str(exc))
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


def publish_track(
    track: SpeedTrack,
    put: Callable[[bytes], None],
    wait: Callable[[float], bool],
    clock: Callable[[], float],
    rate_hz: float = SPEED_RATE_HZ,
    loop: bool = False,
    duration_s: float | None = None,
) -> Iterator[float | None]:
    """Put the track's speed at the time elapsed since the start (`SpeedTrack.kmh_at`: the held
    sample, None as `{"kmh": null}`) every 1/rate_hz s on an absolute schedule (no drift) and at
    each instant it changes (a sample's time, a hold's end), yielding each speed put.

    Ends when `wait(seconds)` returns True (a stop), after `duration_s`, or once the last sample
    has stopped holding (that unknown put last; a constant never ends); with `loop` the track
    starts again every `track.duration_s` seconds instead.
    """
    period_s = 1.0 / rate_hz
    started = clock()
    cycle_s = track.duration_s if loop and track.duration_s > 0 else None
    end_s = math.inf if cycle_s is not None else track.end_s
    if duration_s is not None:
        end_s = min(end_s, duration_s)
    elapsed_s = 0.0
    while True:
        cycles = math.floor(elapsed_s / cycle_s) if cycle_s is not None else 0
        cycle_start_s = cycles * cycle_s if cycle_s is not None else 0.0
        t_s = elapsed_s - cycle_start_s
        kmh = track.kmh_at(t_s)
        put(speed_payload(kmh))
        yield kmh
        if elapsed_s >= end_s:
            return
        change_s = track.next_change_s(t_s)
        if cycle_s is not None:
            change_s = min(change_s, cycle_s)  # the track starts again
        tick_s = (math.floor(elapsed_s / period_s + 1e-9) + 1) * period_s
        following_s = min(tick_s, cycle_start_s + change_s, end_s)
        following_s = max(following_s, elapsed_s + 1e-6)  # float rounding never stalls it
        if wait(max(0.0, started + following_s - clock())):
            return
        elapsed_s = max(following_s, clock() - started)
