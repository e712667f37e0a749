"""Capture-to-delivery latency of the yaw messages, through a Zenoh subscriber on loopback.

`measure_latency` opens the service's own publishing (`roadgaze.daemon.bus_outputs`, a peer
listening on a free 127.0.0.1 port) and a second Zenoh session connected to it whose subscriber
takes each yaw message as it arrives. The latency of a frame is the time from the moment the loop
received the frame from its source (`Pipeline.frame_received_s`, kept per frame by a
`CaptureStamps` sink placed before the publisher) to the moment the subscriber's callback has the
decoded message, both on this process's `time.perf_counter`. On a live camera add up to one
camera frame period that a frame may wait in the newest-frame slot.
"""

from __future__ import annotations

import json
import logging
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from roadgaze.benchmark.probes import CaptureStamps
from roadgaze.config import Config

log = logging.getLogger(__name__)

SUBSCRIBER_WAIT_S = 10.0
"""How long to wait for the subscriber to see the publisher, and for the last messages."""
MAX_SAMPLES = 100_000
"""Latencies kept (a long `--loop-seconds` run keeps the newest)."""


@dataclass(frozen=True, slots=True)
class LatencyResult:
    """Capture to delivery, and its two parts: in the loop up to the publish, then Zenoh."""

    published: int
    received: int
    p50_ms: float
    p99_ms: float
    max_ms: float
    to_publish_p50_ms: float = float("nan")
    """From the frame's receipt to its messages handed to Zenoh (landmarks, pose, monitor)."""
    to_publish_p99_ms: float = float("nan")
    delivery_p50_ms: float = float("nan")
    """From the hand-over to Zenoh to the subscriber's callback (transport, callback thread)."""
    delivery_p99_ms: float = float("nan")


class YawLatencyProbe:
    """A Zenoh subscriber to the yaw key; records receipt time minus capture stamp per message."""

    def __init__(self, config: Config, stamps: CaptureStamps) -> None:
        from roadgaze.transport import Subscription

        self._stamps = stamps
        self._lock = threading.Lock()
        self._latencies_s: list[float] = []
        self._parts_s: list[tuple[float, float]] = []
        self.received = 0
        self.undecodable = 0
        self._subscription = Subscription(config, lambda keys: keys.yaw, self._on_sample)

    def _on_sample(self, sample: Any) -> None:
        arrived = time.perf_counter()
        try:
            frame = int(json.loads(sample.payload.to_bytes())["frame"])
        except (ValueError, KeyError, TypeError):
            with self._lock:
                self.undecodable += 1
            return
        stamps = self._stamps.pop(frame)
        with self._lock:
            self.received += 1
            if stamps is not None:
                received_s, published_s = stamps
                if len(self._latencies_s) >= MAX_SAMPLES:
                    del self._latencies_s[: MAX_SAMPLES // 10]
                    del self._parts_s[: MAX_SAMPLES // 10]
                self._latencies_s.append(arrived - received_s)
                if published_s is not None:
                    self._parts_s.append((published_s - received_s, arrived - published_s))

    def wait_for_publisher(self, timeout_s: float) -> bool:
        """True once the publisher's liveliness token is visible (routes are then in place)."""
        return self._subscription.wait_for_publisher(timeout_s)

    def wait_for_count(self, count: int, timeout_s: float) -> bool:
        def arrived() -> bool:
            with self._lock:
                return self.received >= count

        return self._subscription.wait_until(arrived, timeout_s)

    def result(self, published: int) -> LatencyResult:
        with self._lock:
            milliseconds = 1e3 * np.asarray(self._latencies_s)
            parts_ms = 1e3 * np.asarray(self._parts_s).reshape(-1, 2)
            received = self.received
        if milliseconds.size == 0:
            return LatencyResult(published, received, float("nan"), float("nan"), float("nan"))
        to_publish = np.percentile(parts_ms[:, 0], [50, 99]) if len(parts_ms) else [np.nan] * 2
        delivery = np.percentile(parts_ms[:, 1], [50, 99]) if len(parts_ms) else [np.nan] * 2
        return LatencyResult(
            published=published,
            received=received,
            p50_ms=float(np.median(milliseconds)),
            p99_ms=float(np.percentile(milliseconds, 99)),
            max_ms=float(np.max(milliseconds)),
            to_publish_p50_ms=float(to_publish[0]),
            to_publish_p99_ms=float(to_publish[1]),
            delivery_p50_ms=float(delivery[0]),
            delivery_p99_ms=float(delivery[1]),
        )

    def close(self) -> None:
        self._subscription.close()


@dataclass(frozen=True, slots=True)
class LatencyRig:
    """What `measure_latency` yields: the sinks to run (stamps first) and the probe."""

    sinks: tuple[Any, ...]
    probe: YawLatencyProbe
    stamps: CaptureStamps


@contextmanager
def measure_latency(
    config: Config, source_label: str, received_s: Callable[[], float]
) -> Iterator[LatencyRig]:
    """Publishing on loopback plus a subscriber measuring latency; `received_s` is the loop's
    `frame_received_s` getter. The sinks yielded go to `Pipeline.run`; after the run call
    `rig.probe.wait_for_count` and `rig.probe.result`."""
    from roadgaze.daemon import bus_outputs
    from roadgaze.demo import demo_config, free_local_port, subscriber_config

    port = free_local_port()
    publishing = demo_config(config, port)
    stamps = CaptureStamps(received_s)
    with bus_outputs(publishing, source_label, publish=True) as bus:
        probe = YawLatencyProbe(subscriber_config(publishing, port), stamps)
        try:
            if not probe.wait_for_publisher(SUBSCRIBER_WAIT_S):
                log.warning("the latency subscriber did not see the publisher in time")
            sinks = (stamps, *bus.sinks, stamps.published_mark)
            yield LatencyRig(sinks=sinks, probe=probe, stamps=stamps)
        finally:
            probe.close()
