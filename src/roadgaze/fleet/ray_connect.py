"""Reaching a Ray cluster within a bounded time: Ray's own connect retries for minutes.

`wait_for_ray_head` waits until something accepts TCP connections at the head's address (or
fails naming it); `KeeperThread` runs `ray.init` on a thread, gives up at a deadline, and keeps
that thread alive until the caller is done with Ray.

Why the thread must outlive the call: a local Ray instance's processes (GCS, raylet) are started
with `prctl(PR_SET_PDEATHSIG, SIGKILL)`, and Linux sends that signal when the *thread* that
started them ends, not the process. A `ray.init` on a short-lived thread therefore started a
local instance that the kernel killed the moment the thread returned ("Failed to connect to GCS
within 60 seconds"); on the main thread it worked. The keeper thread waits, after the call, until
`release()`.
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable, MutableMapping
from pathlib import Path

from roadgaze.errors import ConfigError


def ray_head_endpoint(address: str) -> tuple[str, int] | None:
    """(host, port) a Ray address connects to (`HOST:PORT`, `ray://HOST:PORT`), or None for
    `auto`, `local` and anything without a port (Ray resolves those itself)."""
    rest = address.split("://", 1)[-1].rstrip("/")
    host, _, port = rest.rpartition(":")
    if not host or not port.isdigit():
        return None
    return host.strip("[]"), int(port)


def use_ray_token(environ: MutableMapping[str, str], home: Path) -> bool:
    """Ask Ray to send its authentication token when one is at hand and the user set no mode.

    Ray 2.60's `ray start --head` turns token authentication on and writes the token to
    `~/.ray/auth_token`, but a driver connecting to it sends no token unless `RAY_AUTH_MODE` is
    `token` ("Authentication token is missing or incorrect"). A cluster without authentication
    accepts a driver that sends one, so sending it is never worse. Returns whether it set the
    mode."""
    if "RAY_AUTH_MODE" in environ:
        return False
    if not (
        environ.get("RAY_AUTH_TOKEN")
        or environ.get("RAY_AUTH_TOKEN_PATH")
        or (home / ".ray" / "auth_token").is_file()
    ):
        return False
    environ["RAY_AUTH_MODE"] = "token"
    return True


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


class KeeperThread:
    """Runs `call` on a thread that stays alive, after the call returns, until `release()`.

    `start(deadline)` raises TimeoutError when `call` has not returned by `deadline` (the thread
    is left behind: the process is about to report and exit) and re-raises what `call` raised.
    Processes `call` starts with a parent-death signal live as long as the thread (see the
    module's docstring).
    """

    def __init__(self, call: Callable[[], object], name: str = "ray-init") -> None:
        self._call = call
        self._returned = threading.Event()
        self._released = threading.Event()
        self._failure: list[BaseException] = []
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def _run(self) -> None:
        try:
            self._call()
        except BaseException as exc:
            self._failure.append(exc)
            self._released.set()
        finally:
            self._returned.set()
        self._released.wait()

    def start(self, deadline: float) -> KeeperThread:
        self._thread.start()
        if not self._returned.wait(max(0.0, deadline - time.monotonic())):
            raise TimeoutError
        if self._failure:
            raise self._failure[0]
        return self

    def release(self) -> None:
        """Let the thread end (after the caller has shut down what `call` started)."""
        self._released.set()
        self._thread.join(timeout=5.0)
