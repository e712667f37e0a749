"""Rate-limited warnings: a flood of bad input must not become a flood of log lines (pure)."""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import OrderedDict
from collections.abc import Callable

WARNING_PERIOD_S = 10.0
MAX_KEYS = 1024
"""Sources a `KeyedThrottle` tells apart (beyond, the one heard from least recently goes)."""


class KeyedThrottle:
    """Per key (a client, a source): the first event passes at once, then at most one per
    `period_s`; each passing one says how many of its key were held back since the last.
    Thread-safe; at most `max_keys` keys are remembered."""

    def __init__(
        self,
        period_s: float = WARNING_PERIOD_S,
        max_keys: int = MAX_KEYS,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._period_s = period_s
        self._max_keys = max_keys
        self._clock = clock
        self._lock = threading.Lock()
        self._keys: OrderedDict[str, list[float]] = OrderedDict()
        """Key -> [last passed (monotonic s), held back since, events in all]."""

    def __call__(self, key: str) -> tuple[int, int] | None:
        """None when this event of `key` is held back; else (held back since the last passed
        one, events of `key` in all)."""
        now = self._clock()
        with self._lock:
            entry = self._keys.get(key)
            if entry is None:
                if len(self._keys) >= self._max_keys:
                    self._keys.popitem(last=False)
                entry = self._keys[key] = [-math.inf, 0, 0]
            self._keys.move_to_end(key)
            entry[2] += 1
            if now - entry[0] < self._period_s:
                entry[1] += 1
                return None
            held_back, entry[1], entry[0] = int(entry[1]), 0, now
            return held_back, int(entry[2])

    def count(self, key: str) -> int:
        """Events of `key` in all (0 when forgotten or never seen)."""
        with self._lock:
            entry = self._keys.get(key)
            return 0 if entry is None else int(entry[2])

    def held_back(self) -> dict[str, tuple[int, int]]:
        """Per key with events held back since its last passed one: (how many, in all); they
        are counted as told."""
        with self._lock:
            found = {key: (int(e[1]), int(e[2])) for key, e in self._keys.items() if e[1]}
            for key in found:
                self._keys[key][1] = 0
        return found


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
        self._throttle = KeyedThrottle(period_s, 1, clock)

    @property
    def count(self) -> int:
        return self._throttle.count("")

    def __call__(self, detail: str) -> None:
        passed = self._throttle("")
        if passed is None:
            return
        held_back, total = passed
        more = f" ({held_back} more since the last warning, {total} in all)" if held_back else ""
        self._logger.warning("%s: %s%s", self._what, detail, more)
