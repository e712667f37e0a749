"""The process set for a frame loop: short thread switches, garbage collected between frames,
OpenCV on the calling thread.

Two of CPython's defaults put milliseconds onto a frame's latency. A thread waiting for the
interpreter lock behind another's Python work waits up to 5 ms (`sys.getswitchinterval`). And the
garbage collector runs wherever an allocation crosses its threshold, in the middle of a frame: on
the demo drive its middle generation took about 1 ms on one frame in ten, and its oldest 50-70 ms
now and then, because it scans every object of the process (about a million once MediaPipe, Zenoh
and the models are loaded). So while a loop runs, `loop_runtime` shortens the switch interval,
moves the objects alive at the start out of the collector's sight (`gc.freeze`: they are not
garbage) and raises the collector's threshold; `Collector.after_frame` collects on the loop's
thread after each frame's last sink, while MediaPipe works on the next frame. The automatic
collector stays on behind the higher threshold, so garbage made while no frame comes (a lost
camera, the bus's callbacks) is still collected.

OpenCV splits each call over a pool of threads as large as the machine (`cv2.getNumThreads`). A
frame's calls are small (a 256 px crop, a colour conversion of 640x480, an eye's Sobel), and
waking the pool costs more CPU than it saves: the landmark crop took 1.30 ms of process CPU with
two threads against 0.78 ms with one (`cv2.setNumThreads(1)`), and the loop's threads already
keep the cores busy. So a loop runs OpenCV on the calling thread, and restores the pool after.
"""

from __future__ import annotations

import contextlib
import gc
import sys
import threading
from collections.abc import Iterator

SWITCH_INTERVAL_S = 0.0005
"""Python's thread switch interval while a loop runs (its default: 5 ms)."""
YOUNG_THRESHOLD = 20_000
"""Allocations before an automatic young collection while a loop runs (CPython's default: 700,
fewer than one frame makes); `Collector.after_frame` collects before it is reached."""
MIDDLE_EVERY_FRAMES = 10
"""Frames between collections of the middle generation (CPython's own ratio)."""
FULL_EVERY_FRAMES = 1000
"""Frames between full collections (about a minute at 15 fps; frozen objects are not scanned)."""

_lock = threading.Lock()
_users = 0
_saved: tuple[float, tuple[int, int, int], int] = (0.005, (700, 10, 10), -1)


@contextlib.contextmanager
def loop_runtime() -> Iterator[None]:
    """The settings above while at least one loop runs (loops may run in several threads); the
    interpreter's own settings again once the last one ends."""
    import cv2

    global _users, _saved
    with _lock:
        if _users == 0:
            _saved = (sys.getswitchinterval(), gc.get_threshold(), cv2.getNumThreads())
            sys.setswitchinterval(min(_saved[0], SWITCH_INTERVAL_S))
            cv2.setNumThreads(1)
            gc.collect()
            gc.freeze()
            _, middle, full = _saved[1]
            gc.set_threshold(max(_saved[1][0], YOUNG_THRESHOLD), middle, full)
        _users += 1
    try:
        yield
    finally:
        with _lock:
            _users -= 1
            if _users == 0:
                sys.setswitchinterval(_saved[0])
                gc.set_threshold(*_saved[1])
                cv2.setNumThreads(_saved[2])
                gc.unfreeze()


class Collector:
    """Collects garbage between one loop's frames (`after_frame`), the generations in turn."""

    def __init__(self) -> None:
        self._frames = 0

    def after_frame(self) -> None:
        self._frames += 1
        if self._frames % FULL_EVERY_FRAMES == 0:
            gc.collect(2)
        elif self._frames % MIDDLE_EVERY_FRAMES == 0:
            gc.collect(1)
        else:
            gc.collect(0)
