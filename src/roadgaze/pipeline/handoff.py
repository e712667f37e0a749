"""One step of the loop in its own thread, handing its results over through a bounded queue.

The loop decodes a file (and prepares each image for MediaPipe) this way, and runs MediaPipe this
way while its own thread finishes the frame before (`roadgaze.pipeline.steps`). The queue holds at
most `depth` items, so a step runs at most `depth` + 1 items ahead and memory stays flat.
"""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Generic, TypeVar

log = logging.getLogger(__name__)

T = TypeVar("T")
POLL_S = 0.1
"""How often a producer blocked on a full queue checks whether it should stop."""
JOIN_TIMEOUT_S = 5.0
"""How long `close` waits for the producer's current item (e.g. a camera read) to finish."""


@dataclass(frozen=True, slots=True)
class _End:
    error: BaseException | None = None


class Handoff(Generic[T]):
    """Iterates `items` in a thread named `name`; iterating the `Handoff` yields them in order.

    An exception raised by `items` is raised to the consumer where the item would have come.
    `close()` (also on leaving a `with`) stops the producer after its current item and waits
    up to `JOIN_TIMEOUT_S` for it. Iterate once.
    """

    def __init__(self, items: Iterator[T], name: str, depth: int = 1) -> None:
        if depth < 1:
            raise ValueError(f"hand-off depth must be at least 1, found {depth}")
        self._items = items
        self._queue: queue.Queue[T | _End] = queue.Queue(maxsize=depth)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._produce, name=name, daemon=True)
        self._started = False
        self.finished = False
        """True once the consumer received the end of `items` without an error."""

    def __iter__(self) -> Iterator[T]:
        if self._started:
            raise RuntimeError("a hand-off can be iterated only once")
        self._started = True
        self._thread.start()
        while True:
            item = self._queue.get()
            if isinstance(item, _End):
                if item.error is not None:
                    raise item.error
                self.finished = True
                return
            yield item

    def _produce(self) -> None:
        end = _End()
        try:
            for item in self._items:
                if not self._put(item):
                    return
        except BaseException as exc:  # handed to the consumer, raised in its thread
            end = _End(exc)
        self._put(end)

    def _put(self, item: T | _End) -> bool:
        """Wait for room in the queue; False once `close` asked the producer to stop."""
        while not self._stop.is_set():
            try:
                self._queue.put(item, timeout=POLL_S)
                return True
            except queue.Full:
                continue
        return False

    def close(self) -> None:
        self._stop.set()
        thread = self._thread
        if thread.is_alive() and thread is not threading.current_thread():
            thread.join(JOIN_TIMEOUT_S)
            if thread.is_alive():
                log.warning("%s still busy %.0f s after a stop; left behind", thread.name,
                            JOIN_TIMEOUT_S)  # fmt: skip

    def __enter__(self) -> Handoff[T]:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
