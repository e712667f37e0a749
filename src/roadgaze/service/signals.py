"""Signals: a stop flag the loop checks between frames, and SIGTERM handling for batch commands.

SIGINT, SIGTERM and SIGHUP all mean "stop": a terminal closing (SIGHUP) must not kill the
daemon without its final state.
"""

from __future__ import annotations

import logging
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

log = logging.getLogger("roadgaze.daemon")


STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class StopFlag:
    """Set by SIGINT/SIGTERM/SIGHUP (or a caller); the loop checks it between frames."""

    def __init__(self) -> None:
        self._event = threading.Event()
        self.signal_name: str | None = None

    def set(self, name: str = "request") -> None:
        self.signal_name = name
        self._event.set()

    def is_set(self) -> bool:
        return self._event.is_set()

    def wait(self, timeout_s: float) -> bool:
        return self._event.wait(timeout_s)


@contextmanager
def signal_handlers(stop: StopFlag, doing: str = "finishing the current frame") -> Iterator[None]:
    """SIGINT/SIGTERM/SIGHUP set `stop` (the current frame is finished); a second one exits at
    once (exit code 1). `doing` says in the log what happens next."""

    def on_signal(number: int, frame: FrameType | None) -> None:
        name = signal.Signals(number).name
        if stop.is_set():
            log.warning("second %s: exiting without waiting", name)
            raise SystemExit(1)
        log.info("%s received: %s", name, doing)
        stop.set(name)

    previous = {number: signal.signal(number, on_signal) for number in STOP_SIGNALS}
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM and SIGHUP raise KeyboardInterrupt so `with` blocks close every
    output."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum: int, frame: object) -> None:
        raise KeyboardInterrupt(f"signal {signum}")

    previous = {number: signal.signal(number, interrupt) for number in STOP_SIGNALS[1:]}
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
