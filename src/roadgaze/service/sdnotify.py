"""systemd's notify protocol (sd_notify(3)) in plain Python: no libsystemd, no new dependency.

A message is `KEY=VALUE` lines sent as one datagram to the AF_UNIX socket named by
`$NOTIFY_SOCKET` (a path, or `@name` for an abstract socket). `WATCHDOG_USEC` (with
`WATCHDOG_PID` unset or this process) says how often systemd expects `WATCHDOG=1`. Without
`$NOTIFY_SOCKET` (not started by systemd, or `Type=simple`) every call does nothing; a send that
fails is logged once and never raises: supervision must not stop monitoring.
"""

from __future__ import annotations

import logging
import os
import socket
import threading
from collections.abc import Mapping

log = logging.getLogger("roadgaze.daemon")

SEND_TIMEOUT_S = 0.5
"""How long a send may block when systemd's queue is full (a watchdog ping comes again soon)."""


def socket_address(value: str) -> str | None:
    """The address to send to: a path as is, `@name` as the abstract name `\\0name`; None for
    anything else (e.g. `vsock:` addresses, which this module does not speak)."""
    if value.startswith("/"):
        return value
    if value.startswith("@") and len(value) > 1:
        return "\0" + value[1:]
    return None


class Notifier:
    """Sends notify messages to systemd; `enabled` is False when nothing listens for them."""

    def __init__(self, notify_socket: str | None, watchdog_usec: int | None = None) -> None:
        self.address = socket_address(notify_socket) if notify_socket else None
        if notify_socket and self.address is None:
            log.warning("NOTIFY_SOCKET=%s is not a unix socket path: not notifying", notify_socket)
        self.watchdog_s = watchdog_usec / 1e6 if watchdog_usec and self.address else None
        """systemd's WatchdogSec in seconds; None when no watchdog is expected from us."""
        self._socket: socket.socket | None = None
        self._lock = threading.Lock()
        self._failed = False
        self.sent: int = 0

    @classmethod
    def from_environment(
        cls, environ: Mapping[str, str] | None = None, pid: int | None = None
    ) -> Notifier:
        """From `NOTIFY_SOCKET`, `WATCHDOG_USEC` and `WATCHDOG_PID` (ignored when they are not
        for this process or not numbers)."""
        environ = os.environ if environ is None else environ
        pid = os.getpid() if pid is None else pid
        watchdog_usec: int | None = None
        watchdog_pid = environ.get("WATCHDOG_PID", "").strip()
        if not watchdog_pid or watchdog_pid == str(pid):
            text = environ.get("WATCHDOG_USEC", "").strip()
            watchdog_usec = int(text) if text.isdigit() and int(text) > 0 else None
        return cls(environ.get("NOTIFY_SOCKET") or None, watchdog_usec)

    @property
    def enabled(self) -> bool:
        return self.address is not None

    def send(self, **fields: str | int) -> bool:
        """One datagram of `KEY=value` lines (keys as given, e.g. READY=1, STATUS=...); True when
        it was sent. Newlines in values are replaced: they would start a new field."""
        if self.address is None:
            return False
        message = "\n".join(
            f"{key}={str(value).replace(chr(10), ' ')}" for key, value in fields.items()
        )
        with self._lock:
            try:
                if self._socket is None:
                    self._socket = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
                    self._socket.settimeout(SEND_TIMEOUT_S)
                self._socket.sendto(message.encode("utf-8"), self.address)
            except OSError as exc:
                if not self._failed:
                    log.warning("cannot notify systemd (%s): %s", fields, exc)
                    self._failed = True
                return False
        self._failed = False
        self.sent += 1
        return True

    def ready(self, status: str) -> bool:
        """Start-up is complete (Type=notify services are 'started' from now on)."""
        return self.send(READY=1, STATUS=status)

    def status(self, text: str) -> bool:
        """A one-line status for `systemctl status`."""
        return self.send(STATUS=text)

    def watchdog(self) -> bool:
        """Still alive: resets systemd's watchdog timer."""
        return self.send(WATCHDOG=1)

    def stopping(self, status: str) -> bool:
        """Shutting down (so systemd does not take the exit for a crash of a running service)."""
        return self.send(STOPPING=1, STATUS=status)

    def close(self) -> None:
        with self._lock:
            if self._socket is not None:
                self._socket.close()
                self._socket = None
