"""Capture-to-delivery latency of the yaw messages, through a Zenoh subscriber on loopback.

`measure_latency` builds the service's own run (`roadgaze.pipeline.build_run`, publishing as a
peer listening on a free 127.0.0.1 port) and, in a process of its own as a forward-collision system
would be, a Zenoh session connected to it whose subscriber takes each yaw message as it arrives.
The latency of a frame is the time from the moment the loop received the frame from its source
(`Pipeline.frame_received_s`, kept per frame by a `CaptureStamps` sink placed before the
publisher) to the moment the subscriber's callback has the decoded message; both are read on
`time.perf_counter`, the system's monotonic clock on Linux, which both processes share. On a live
camera add up to one camera frame period that a frame may wait in the newest-frame slot.
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
import multiprocessing
import threading
import time
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from multiprocessing.connection import Connection
from typing import TYPE_CHECKING, Any

import numpy as np

from roadgaze.benchmark.probes import CaptureStamps
from roadgaze.config import Config

if TYPE_CHECKING:
    from roadgaze.capture import FrameSource
    from roadgaze.pipeline import Run

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
    """A Zenoh subscriber to the yaw key in a child process; latency = its arrival time of each
    message minus the frame's capture stamp here."""

    def __init__(self, config: Config, stamps: CaptureStamps) -> None:
        self._stamps = stamps
        context = multiprocessing.get_context("spawn")  # no fork of MediaPipe's threads
        self._connection, child_end = context.Pipe()
        self._process = context.Process(
            target=_subscriber_process,
            args=(config, child_end),
            name="roadgaze-latency-subscriber",
            daemon=True,
        )
        self._process.start()
        child_end.close()
        ready = self._ask(("ready",), SUBSCRIBER_WAIT_S + 20.0)
        if ready is not True:
            self.close()
            raise RuntimeError(f"the latency subscriber did not start: {ready}")

    def _ask(self, command: tuple[Any, ...], timeout_s: float) -> Any:
        """Send `command` to the child and wait for its answer (None after `timeout_s`)."""
        try:
            if command[0] != "ready":
                self._connection.send(command)
            if not self._connection.poll(timeout_s):
                return None
            return self._connection.recv()
        except (EOFError, OSError):
            return None

    def wait_for_publisher(self, timeout_s: float) -> bool:
        """True once the publisher's liveliness token is visible (routes are then in place)."""
        return self._ask(("publisher", timeout_s), timeout_s + 5.0) is True

    def wait_for_count(self, count: int, timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while True:
            received = self._ask(("count",), 5.0)
            if received is None or received >= count or time.monotonic() >= deadline:
                return received is not None and received >= count
            time.sleep(0.02)

    def result(self, published: int, skip_first: int = 0) -> LatencyResult:
        """Percentiles over the messages received, the first `skip_first` (model start-up) left
        out."""
        arrivals: list[tuple[int, float]] = self._ask(("arrivals",), 10.0) or []
        latencies_s: list[float] = []
        parts_s: list[tuple[float, float]] = []
        for frame, arrived in arrivals[skip_first:]:
            stamps = self._stamps.pop(frame)
            if stamps is None:
                continue
            received_s, published_s = stamps
            latencies_s.append(arrived - received_s)
            if published_s is not None:
                parts_s.append((published_s - received_s, arrived - published_s))
        milliseconds = 1e3 * np.asarray(latencies_s)
        parts_ms = 1e3 * np.asarray(parts_s).reshape(-1, 2)
        if milliseconds.size == 0:
            return LatencyResult(published, len(arrivals), math.nan, math.nan, math.nan)
        to_publish = np.percentile(parts_ms[:, 0], [50, 99]) if len(parts_ms) else [math.nan] * 2
        delivery = np.percentile(parts_ms[:, 1], [50, 99]) if len(parts_ms) else [math.nan] * 2
        return LatencyResult(
            published=published,
            received=len(arrivals),
            p50_ms=float(np.median(milliseconds)),
            p99_ms=float(np.percentile(milliseconds, 99)),
            max_ms=float(np.max(milliseconds)),
            to_publish_p50_ms=float(to_publish[0]),
            to_publish_p99_ms=float(to_publish[1]),
            delivery_p50_ms=float(delivery[0]),
            delivery_p99_ms=float(delivery[1]),
        )

    def close(self) -> None:
        with contextlib.suppress(OSError, EOFError):
            self._connection.send(("close",))
        self._process.join(5.0)
        if self._process.is_alive():
            self._process.terminate()
            self._process.join(1.0)
        self._connection.close()


def _subscriber_process(config: Config, connection: Connection) -> None:
    """The child: subscribe, answer the parent's questions until it says close or goes away."""
    from roadgaze.transport import Subscription

    lock = threading.Lock()
    arrivals: deque[tuple[int, float]] = deque(maxlen=MAX_SAMPLES)

    def on_sample(sample: Any) -> None:
        arrived = time.perf_counter()
        try:
            frame = int(json.loads(sample.payload.to_bytes())["frame"])
        except (ValueError, KeyError, TypeError):
            return
        with lock:
            arrivals.append((frame, arrived))

    try:
        subscription = Subscription(config, lambda keys: keys.yaw, on_sample)
    except Exception as exc:  # reported to the parent, which raises
        connection.send(f"{type(exc).__name__}: {exc}")
        return
    with subscription:
        connection.send(True)
        while True:
            try:
                command = connection.recv()
            except (EOFError, OSError):
                return
            if command[0] == "publisher":
                connection.send(subscription.wait_for_publisher(command[1]))
            elif command[0] == "count":
                with lock:
                    connection.send(len(arrivals))
            elif command[0] == "arrivals":
                with lock:
                    connection.send(list(arrivals))
            else:
                return


@dataclass(frozen=True, slots=True)
class LatencyRig:
    """What `measure_latency` yields: the run to drive (`Run.run`) and the probe."""

    run: Run
    probe: YawLatencyProbe
    stamps: CaptureStamps


@contextmanager
def measure_latency(
    config: Config, source_label: str, source: FrameSource | None = None
) -> Iterator[LatencyRig]:
    """The run as `roadgaze run` builds it (`build_run`, publishing on loopback; over `source`
    when given, else the one `source_label` names) plus a subscriber measuring latency. Drive
    `rig.run.run(realtime=True, ...)`, then call `rig.probe.wait_for_count` and
    `rig.probe.result`."""
    from roadgaze.demo import demo_config, free_local_port, subscriber_config
    from roadgaze.pipeline import RunOptions, build_run

    port = free_local_port()
    publishing = demo_config(config, port)
    built: list[Run] = []
    stamps = CaptureStamps(
        lambda: built[0].pipeline.frame_received_s if built else math.nan, capacity=MAX_SAMPLES
    )
    options = RunOptions(source_label, command="bench", publish=True, quiet=True)
    with contextlib.ExitStack() as stack:
        # The subscriber closes after the service's session: a subscriber leaving first is a
        # link going down to the service, which warns that alerts are held.
        probes = stack.enter_context(contextlib.ExitStack())
        run = stack.enter_context(
            build_run(
                publishing,
                options,
                source=source,
                first_sinks=(stamps,),
                sinks=(stamps.published_mark,),
            )
        )
        built.append(run)
        probe = YawLatencyProbe(subscriber_config(publishing, port), stamps)
        probes.callback(probe.close)
        if not probe.wait_for_publisher(SUBSCRIBER_WAIT_S):
            log.warning("the latency subscriber did not see the publisher in time")
        yield LatencyRig(run=run, probe=probe, stamps=stamps)
