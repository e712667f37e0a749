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
        with suppress(OSError, ValueError, RuntimeError):  # a closed pipe, a re-entrant call
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

    The handler itself only writes the signal's number into a pipe: a thread (`_SignalWatch`)
    logs it, sets `stop` and, for a second signal, exits. A Python signal handler runs in the
    main thread between two of its bytecodes, possibly while that thread holds a lock that is
    not re-entrant (a `queue.Queue`'s, which the recorder's log tap takes, or a
    `threading.Event`'s): logging or setting an event from the handler can then wait forever
    on its own thread. It did: one SIGTERM in a few hundred hung the daemon with a recorder.

    With `hard_exit` the second signal ends the process right there (`os._exit` after the log is
    flushed): raising SystemExit can land inside a finaliser (MediaPipe's
    `FaceLandmarker.__del__`), where Python prints "Exception ignored" and goes on. Without it
    (the batch, which must stop its worker processes) the handler raises SystemExit(1) in the
    main thread.
    """
    watch = _SignalWatch(stop, doing, logging.getLogger(log_name), hard_exit)
    owner_pid = os.getpid()
    received = 0

    def on_signal(number: int, frame: FrameType | None) -> None:
        nonlocal received
        if os.getpid() != owner_pid:  # a forked child: the default action, as if never set
            signal.signal(number, signal.SIG_DFL)
            os.kill(os.getpid(), number)
            return
        received += 1
        watch.post(number)
        if received > 1 and not hard_exit:
            raise SystemExit(EXIT_SECOND_SIGNAL)

    previous = {number: signal.signal(number, on_signal) for number in STOP_SIGNALS}
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
        watch.close()


class _SignalWatch:
    """The thread that acts on the signals `post`ed through a pipe (os.write takes no lock)."""

    _CLOSE = 0

    def __init__(self, stop: StopFlag, doing: str, logger: logging.Logger, hard_exit: bool) -> None:
        self.stop, self.doing, self.logger, self.hard_exit = stop, doing, logger, hard_exit
        self._read_fd, self._write_fd = os.pipe()
        os.set_blocking(self._write_fd, False)
        self._thread = threading.Thread(target=self._watch, name="roadgaze-signals", daemon=True)
        self._thread.start()

    def post(self, number: int) -> None:
        """From the signal handler: no lock, never waits (a full pipe drops the byte; the
        signals already in it say the same)."""
        with suppress(OSError):
            os.write(self._write_fd, bytes((number,)))

    def close(self) -> None:
        with suppress(OSError):
            os.set_blocking(self._write_fd, True)
            os.write(self._write_fd, bytes((self._CLOSE,)))
        self._thread.join(timeout=5.0)
        for descriptor in (self._read_fd, self._write_fd):
            with suppress(OSError):
                os.close(descriptor)

    def _watch(self) -> None:
        while data := os.read(self._read_fd, 64):
            for number in data:
                if number == self._CLOSE:
                    return
                self._act(signal.Signals(number).name)

    def _act(self, name: str) -> None:
        if self.stop.is_set():
            self.logger.warning("second %s: exiting without waiting (exit status 1)", name)
            if self.hard_exit:
                exit_now(EXIT_SECOND_SIGNAL)
            return  # the batch: the handler raised SystemExit in the main thread
        self.logger.info("%s received: %s", name, self.doing)
        self.stop.set(name)


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
