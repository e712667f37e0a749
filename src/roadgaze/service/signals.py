"""Signals: a stop flag the loop checks between frames, and SIGTERM handling for batch commands.

SIGINT, SIGTERM and SIGHUP all mean "stop": a terminal closing (SIGHUP) must not kill the
daemon without its final state.
"""

from __future__ import annotations

import logging
import os
import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager, suppress
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


EXIT_SECOND_SIGNAL = 1
"""Exit status after a second stop signal."""


def exit_now(code: int) -> None:
    """End the process at once with `code`, after flushing the log and the standard streams
    (no finaliser runs: none can print "Exception ignored" or swallow the exit)."""
    for handler in logging.getLogger().handlers:
        handler.flush()
    for stream in (sys.stdout, sys.stderr):
        with suppress(OSError, ValueError):  # a closed pipe: nothing more to say
            stream.flush()
    os._exit(code)


@contextmanager
def signal_handlers(
    stop: StopFlag,
    doing: str = "finishing the current frame",
    log_name: str = "roadgaze.daemon",
    hard_exit: bool = True,
) -> Iterator[None]:
    """SIGINT/SIGTERM/SIGHUP set `stop` (the current frame is finished); a second one exits at
    once with status 1, at any spacing. `doing` says in the log what happens next, under the
    logger `log_name`.

    With `hard_exit` the second signal ends the process right there (`os._exit` after the log is
    flushed): raising SystemExit from a signal handler can land inside a finaliser (MediaPipe's
    `FaceLandmarker.__del__`), where Python prints "Exception ignored" and goes on. Without it
    (the batch, which must stop its worker processes) it raises SystemExit(1).
    """
    logger = logging.getLogger(log_name)

    def on_signal(number: int, frame: FrameType | None) -> None:
        name = signal.Signals(number).name
        if stop.is_set():
            logger.warning("second %s: exiting without waiting (exit status 1)", name)
            if not hard_exit:
                raise SystemExit(EXIT_SECOND_SIGNAL)
            exit_now(EXIT_SECOND_SIGNAL)
        logger.info("%s received: %s", name, doing)
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
