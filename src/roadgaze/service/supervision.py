"""systemd supervision of the daemon (`Type=notify`, `WatchdogSec`), as a pipeline sink.

What `Supervisor` tells systemd:

- `READY=1` once the first frame has been through the whole loop; or, when the camera cannot
  be opened at start, as soon as the daemon waits for it, with `STATUS=degraded: ...`. The
  daemon is then up in the sense that matters to the vehicle: it answers state queries saying
  it is degraded, so the forward-collision warning knows monitoring is off. Withholding READY
  instead would make systemd kill and restart the daemon in a loop while the camera is missing.
- `WATCHDOG=1` from the frame loop (the sink), at most every quarter of `WatchdogSec`. While the
  loop legitimately waits for a lost or missing camera, a background thread pings instead, but
  only while (a) every frame the camera delivered has been through the loop (the loop is not
  stuck on one) and (b) the camera re-open attempts still progress (one within
  `reconnect_max_s` + `WAIT_STALL_MARGIN_S`). A loop stuck anywhere else gets no ping: systemd
  aborts (SIGABRT, Python stacks of every thread in the journal) and restarts it.
- `STOPPING=1` the moment a stop is asked for (SIGTERM from `systemctl stop`), and at the end of
  the source; `STATUS=` lines along the way.

Without `$NOTIFY_SOCKET` it does nothing and starts no thread.
"""

from __future__ import annotations

import faulthandler
import logging
import sys
import threading
import time
from collections.abc import Callable
from types import TracebackType
from typing import Protocol, Self

from roadgaze.capture import FrameSource, SourceStatus
from roadgaze.service.sdnotify import Notifier
from roadgaze.types import Alert, Frame, FrameRecord

log = logging.getLogger("roadgaze.daemon")

WAIT_STALL_MARGIN_S = 5.0
"""Beyond the longest reconnect back-off, how long a camera wait may show no attempt before it
counts as stalled (and the watchdog is no longer fed)."""
STATUS_PERIOD_S = 10.0
"""How often the running status line (frames, alerts) is refreshed."""
NO_WATCHDOG_TICK_S = 1.0
"""Thread period when systemd expects no watchdog (READY while waiting, STOPPING still apply)."""


class StopEvent(Protocol):
    """The daemon's `StopFlag`: set by SIGTERM, waited on by the supervision thread."""

    signal_name: str | None

    def is_set(self) -> bool: ...

    def wait(self, timeout_s: float) -> bool: ...


def waiting_for_camera(source_live: bool, status: SourceStatus, frames_processed: int) -> bool:
    """True when the loop is blocked on a camera that is not delivering (lost or never opened)
    and not on a frame of its own: every delivered frame has reached the sinks."""
    return (
        source_live
        and not status.connected
        and not status.ended
        and status.frames_delivered <= frames_processed
    )


class Supervisor:
    """Pipeline sink and background thread speaking systemd's notify protocol (see module)."""

    def __init__(
        self,
        notifier: Notifier,
        stop: StopEvent,
        reconnect_max_s: float,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.notifier = notifier
        self.stop = stop
        self.stall_after_s = reconnect_max_s + WAIT_STALL_MARGIN_S
        self._clock = clock
        watchdog_s = notifier.watchdog_s
        self.ping_every_s = watchdog_s / 4 if watchdog_s else None
        self.frames = 0
        self.alerts = 0
        self.ready = False
        self.stopping_sent = False
        self._source: FrameSource | None = None
        self._source_label = ""
        self._last_ping = -float("inf")
        self._last_status = -float("inf")
        self._done = threading.Event()
        self._thread: threading.Thread | None = None

    @classmethod
    def from_environment(cls, stop: StopEvent, reconnect_max_s: float) -> Supervisor:
        return cls(Notifier.from_environment(), stop, reconnect_max_s)

    def __enter__(self) -> Self:
        if self.notifier.enabled:
            if self.notifier.watchdog_s is not None and not faulthandler.is_enabled():
                # A watchdog abort (SIGABRT) then leaves every thread's Python stack in the journal.
                faulthandler.enable(file=sys.stderr, all_threads=True)
            log.info(
                "systemd notify socket found: READY after the first frame, watchdog %s",
                f"every {self.ping_every_s:.1f} s" if self.ping_every_s else "off",
            )
            self._thread = threading.Thread(target=self._watch, name="systemd-notify", daemon=True)
            self._thread.start()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.stopping("failed" if exc_type not in (None, SystemExit) else "stopped")
        self._done.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self.notifier.close()

    def status(self, text: str) -> None:
        """A STATUS= line (start-up steps: loading the model, opening the source)."""
        self.notifier.status(text)

    def watch(self, source: FrameSource, label: str) -> None:
        """The open source, read for camera waits; `label` names it in the status lines."""
        self._source_label = label
        self._source = source

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        """The frame loop's heartbeat: READY after the first frame, then WATCHDOG pings."""
        self.frames += 1
        self.alerts += len(record.alerts)
        if not self.notifier.enabled:
            return
        now = self._clock()
        if not self.ready:
            self.ready = True
            self._last_status = now
            self.notifier.ready(f"monitoring {self._source_label}: first frame processed")
        elif now - self._last_status >= STATUS_PERIOD_S:
            self._last_status = now
            self.notifier.status(
                f"monitoring {self._source_label}: {self.frames} frames, {self.alerts} alerts"
            )
        self._ping(now)

    def _ping(self, now: float) -> None:
        if self.ping_every_s is not None and now - self._last_ping >= self.ping_every_s:
            self._last_ping = now
            self.notifier.watchdog()

    def on_alert(self, alert: Alert) -> None:
        """An alert raised outside the frame loop: counted in the status line."""
        self.alerts += 1

    def stopping(self, reason: str) -> None:
        """STOPPING=1 once (SIGTERM, end of the source, or an error)."""
        if self.stopping_sent or not self.notifier.enabled:
            return
        self.stopping_sent = True
        self.notifier.stopping(f"stopping ({reason}) after {self.frames} frames")

    def close(self) -> None:
        """Sink interface: nothing to release (the thread ends with the context)."""

    def _watch(self) -> None:
        """Thread: STOPPING on a stop request; READY and pings while waiting for a camera."""
        tick_s = self.ping_every_s or NO_WATCHDOG_TICK_S
        progress_key: tuple[bool, int, int] | None = None
        last_progress = self._clock()
        while not self._done.is_set():
            if self.stop.wait(tick_s):
                self.stopping(self.stop.signal_name or "stop requested")
                self._done.wait()
                return
            source = self._source
            if source is None:
                continue  # loading the model or opening the source: TimeoutStartSec applies
            status = source.status
            now = self._clock()
            key = (status.connected, status.reopen_attempts, status.reconnects)
            if key != progress_key:
                progress_key, last_progress = key, now
            if not waiting_for_camera(source.info.live, status, self.frames):
                continue
            problem = status.message or f"camera {self._source_label} unavailable"
            if not self.ready:
                self.ready = True
                log.info("told systemd the daemon is up, degraded: %s", problem)
                self.notifier.ready(f"degraded: {problem}")
            if now - last_progress > self.stall_after_s:
                self.notifier.status(
                    f"degraded: camera wait stalled {now - last_progress:.0f} s: {problem}"
                )
                continue  # no ping: systemd's watchdog will restart us
            self.notifier.status(f"degraded: {problem} (attempt {status.reopen_attempts})")
            self._ping(now)
