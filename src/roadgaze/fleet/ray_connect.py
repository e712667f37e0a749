"""Reaching a Ray cluster within a bounded time: Ray's own connect retries for minutes.

`wait_for_ray_head` waits until something accepts TCP connections at the head's address (or
fails naming it); `bounded_call` runs `ray.init` on a thread and gives up at a deadline.
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable

from roadgaze.errors import ConfigError


def ray_head_endpoint(address: str) -> tuple[str, int] | None:
    """(host, port) a Ray address connects to (`HOST:PORT`, `ray://HOST:PORT`), or None for
    `auto`, `local` and anything without a port (Ray resolves those itself)."""
    rest = address.split("://", 1)[-1].rstrip("/")
    host, _, port = rest.rpartition(":")
    if not host or not port.isdigit():
        return None
    return host.strip("[]"), int(port)


def wait_for_ray_head(address: str, deadline: float, timeout_s: float) -> None:
    """Return once something accepts TCP connections at `address`'s head; ConfigError naming
    the address after `deadline` (Ray's own connect retries for minutes)."""
    endpoint = ray_head_endpoint(address)
    if endpoint is None:
        return
    while True:
        try:
            with socket.create_connection(endpoint, timeout=min(2.0, timeout_s)):
                return
        except OSError as exc:
            reason = exc.strerror or type(exc).__name__
        if time.monotonic() + 0.5 > deadline:
            raise ConfigError(
                f"no Ray cluster at {address}: nothing accepted a connection in {timeout_s:g} s "
                f"({reason}); start the head (ray start --head) or fix --ray-address / "
                "RAY_ADDRESS"
            )
        time.sleep(0.5)


def bounded_call(call: Callable[[], object], deadline: float) -> None:
    """Run `call` on a thread; TimeoutError when it has not returned by `deadline` (the thread
    is left behind: the process is about to report and exit)."""
    failure: list[BaseException] = []

    def target() -> None:
        try:
            call()
        except BaseException as exc:
            failure.append(exc)

    thread = threading.Thread(target=target, name="ray-init", daemon=True)
    thread.start()
    thread.join(max(0.0, deadline - time.monotonic()))
    if thread.is_alive():
        raise TimeoutError
    if failure:
        raise failure[0]
