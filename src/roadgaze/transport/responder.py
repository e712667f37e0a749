"""The state queryable's answering thread: bounded work whatever the query rate.

Queries wait in a ring of `QUERY_RING` inside Zenoh (older ones are dropped there, at no Python
cost; their askers get no answer). One thread answers at most `REPLIES_PER_S` a second with
cached state bytes, rebuilt at most every `REFRESH_S`. A flood of queries therefore costs the
frame loop nothing but those replies; the router's per-client ingress downsampling (in the
files `roadgaze security init` writes) keeps a flooding client from crowding out the others.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from typing import Any

log = logging.getLogger(__name__)

QUERY_RING = 8
REPLIES_PER_S = 50.0
REFRESH_S = 0.2


class StateResponder:
    """Answers the queries of a ring-channel queryable from a thread; `close()` stops it.

    `build()` returns the current state as bytes (thread-safe); `reply(query, data)` answers one
    query.
    """

    def __init__(
        self,
        handler: Any,
        build: Callable[[], bytes],
        reply: Callable[[Any, bytes], None],
    ) -> None:
        self._handler = handler
        self._build = build
        self._reply = reply
        self._cached = b""
        self._built_at = -math.inf
        self.answered = 0
        self._thread = threading.Thread(target=self._serve, name="zenoh-state", daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        period_s = 1.0 / REPLIES_PER_S
        while True:
            try:
                query = self._handler.recv()  # blocks without the GIL; raises once undeclared
            except Exception:
                return
            started = time.monotonic()
            try:
                if started - self._built_at >= REFRESH_S:
                    self._cached, self._built_at = self._build(), started
                self._reply(query, self._cached)
                self.answered += 1
            except Exception as exc:  # the asker may be gone; the state must never kill us
                log.debug("state reply failed: %s", exc)
            finally:
                del query  # a dropped query ends the asker's wait at once
            rest_s = period_s - (time.monotonic() - started)
            if rest_s > 0:
                time.sleep(rest_s)

    def close(self, timeout_s: float = 2.0) -> None:
        """Wait for the thread to end (call after undeclaring the queryable)."""
        self._thread.join(timeout=timeout_s)
