"""Rate-limited warnings: a flood of bad input must not become a flood of log lines (pure)."""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable

WARNING_PERIOD_S = 10.0


class ThrottledWarning:
    """Logs the first warning at once, then at most one per `period_s` with how many were
    held back; `count` is the total number of calls. Thread-safe."""

    def __init__(
        self,
        logger: logging.Logger,
        what: str,
        period_s: float = WARNING_PERIOD_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._logger = logger
        self._what = what
        self._period_s = period_s
        self._clock = clock
        self._lock = threading.Lock()
        self._last_s = -math.inf
        self._held_back = 0
        self.count = 0

    def __call__(self, detail: str) -> None:
        now = self._clock()
        with self._lock:
            self.count += 1
            if now - self._last_s < self._period_s:
                self._held_back += 1
                return
            held_back, self._held_back, self._last_s = self._held_back, 0, now
            total = self.count
        more = f" ({held_back} more since the last warning, {total} in all)" if held_back else ""
        self._logger.warning("%s: %s%s", self._what, detail, more)
