"""Zenoh's own (Rust) log lines, taken off stdout and told through roadgaze's log on stderr.

Zenoh's native log writes to file descriptor 1 with terminal colour codes and no way to choose
another stream. A process that turns it on (`roadgaze router`, for refused TLS handshakes) calls
`relay_zenoh_log()` first: fd 1 then feeds a pipe read by a thread, which strips the colour
codes, names what happened in a user's words where Zenoh's hint misleads, and logs each kind of
line at most once per `WARNING_PERIOD_S` (with how many were held back), under `roadgaze.zenoh`.
Python's own `sys.stdout` keeps writing to the original stdout.
"""

from __future__ import annotations

import logging
import os
import re
import sys
import threading
from typing import IO

from roadgaze.transport.throttle import WARNING_PERIOD_S, ThrottledWarning

__all__ = ["ZenohLogLine", "parse_zenoh_line", "relay_zenoh_log"]

log = logging.getLogger("roadgaze.zenoh")

_COLOUR = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")
_LINE = re.compile(
    r"^\S+Z\s+(?P<level>TRACE|DEBUG|INFO|WARN|ERROR)\s+(?:\S+\s+ThreadId\(\d+\)\s+)?"
    r"(?P<target>[\w:]+):\s*(?P<message>.*)$"
)
_LEVELS = {
    "ERROR": logging.ERROR,
    "WARN": logging.WARNING,
    "INFO": logging.INFO,
    "DEBUG": logging.DEBUG,
    "TRACE": logging.DEBUG,
}
_PLAIN_CLIENT = "received corrupt message of type InvalidContentType"
"""What rustls says when the first bytes on a TLS endpoint are not a TLS record."""


class ZenohLogLine:
    """One line of Zenoh's log: its level, the Rust module it came from and what it says."""

    __slots__ = ("kind", "level", "message", "target")

    def __init__(self, level: int, target: str, message: str, kind: str) -> None:
        self.level, self.target, self.message, self.kind = level, target, message, kind


def parse_zenoh_line(raw: str) -> ZenohLogLine | None:
    """The line without its colour codes, with a user's reading of what it means; None for an
    empty line. `kind` groups lines that say the same thing (for throttling)."""
    text = _COLOUR.sub("", raw).strip()
    if not text:
        return None
    match = _LINE.match(text)
    if match is None:
        return ZenohLogLine(logging.WARNING, "zenoh", text, text[:60])
    level = _LEVELS[match["level"]]
    target, message = match["target"], match["message"]
    if target.startswith("zenoh_link_tls") and _PLAIN_CLIENT in message:
        message = (
            "refused a connection on a TLS endpoint: the client did not speak TLS (a plain "
            "tcp/ client, or something else knocking on the port)"
        )
        return ZenohLogLine(level, target, message, "plain client on TLS")
    return ZenohLogLine(level, target, message, f"{target} {message[:40]}")


def _relay(stream: IO[bytes]) -> None:
    throttles: dict[str, ThrottledWarning] = {}
    for raw in stream:
        line = parse_zenoh_line(raw.decode("utf-8", "replace"))
        if line is None:
            continue
        if line.level < logging.WARNING:
            log.log(line.level, "zenoh %s: %s", line.target, line.message)
            continue
        throttle = throttles.get(line.kind)
        if throttle is None:
            if len(throttles) >= 64:  # bounded: a peer cannot grow this table
                throttles.clear()
            throttle = throttles[line.kind] = ThrottledWarning(
                log, f"zenoh {line.target}", WARNING_PERIOD_S
            )
        throttle(line.message)


def relay_zenoh_log() -> bool:
    """Send what native code writes to fd 1 through `roadgaze.zenoh` (stderr); Python's
    `sys.stdout` keeps the original stdout. Returns False where fd 1 cannot be replaced."""
    try:
        sys.stdout.flush()
        original = os.dup(1)
        read_end, write_end = os.pipe()
    except (OSError, ValueError):
        return False
    os.dup2(write_end, 1)
    os.close(write_end)
    sys.stdout = os.fdopen(original, "w", encoding="utf-8")
    reader = os.fdopen(read_end, "rb")
    threading.Thread(target=_relay, args=(reader,), name="zenoh-log", daemon=True).start()
    return True
