"""A subscriber to one key in a consumer session of its own, for in-process watchers.

The demo's alert subscriber and the benchmark's latency probe both watch what the service
publishes on loopback: each opens a consumer session, subscribes to one key, waits for the
publisher's liveliness token and then for enough samples, and closes both at the end.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from roadgaze.config import Config
from roadgaze.transport.keys import Keys
from roadgaze.transport.session import open_session, plan_session
from roadgaze.types import ClosesOnExit


class Subscription(ClosesOnExit):
    """`on_sample` is called on Zenoh's receiving thread with each sample on `key(keys)`.

    The session is a peer on `config.zenoh` (a consumer's plan); a failure to open or subscribe
    closes what was opened and raises.
    """

    def __init__(
        self, config: Config, key: Callable[[Keys], str], on_sample: Callable[[Any], None]
    ) -> None:
        self.keys = Keys.from_config(config.zenoh)
        self._session: Any = None
        self._subscriber: Any = None
        try:
            self._session = open_session(plan_session(config.zenoh, "consumer", mode="peer"))
            self._subscriber = self._session.declare_subscriber(key(self.keys), on_sample)
        except BaseException:
            self.close()
            raise

    def wait_for_publisher(self, timeout_s: float) -> bool:
        """True once the publisher's liveliness token is visible (routes are then in place);
        False after `timeout_s`."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            replies = self._session.liveliness().get(self.keys.alive, timeout=0.5)
            if any(reply.ok is not None for reply in replies):
                return True
            time.sleep(0.05)
        return False

    @staticmethod
    def wait_until(done: Callable[[], bool], timeout_s: float) -> bool:
        """True once `done()` holds, polled every 20 ms; False after `timeout_s`."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if done():
                return True
            time.sleep(0.02)
        return done()

    def close(self) -> None:
        if self._subscriber is not None:
            self._subscriber.undeclare()
            self._subscriber = None
        if self._session is not None:
            self._session.close()
            self._session = None
