"""How the service's helper threads run: below the loop's priority where they must not steal it
(the decoder, the MCAP recorder's image encoder). Shared by the pipeline and the outputs."""

from __future__ import annotations

import logging
import os
import threading

log = logging.getLogger(__name__)


def lower_this_thread_priority(niceness: int) -> None:
    """Raise the calling thread's niceness by `niceness` (Linux: per thread; elsewhere nothing)."""
    if not hasattr(os, "setpriority") or not hasattr(threading, "get_native_id"):
        return
    try:
        thread_id = threading.get_native_id()
        current = os.getpriority(os.PRIO_PROCESS, thread_id)
        os.setpriority(os.PRIO_PROCESS, thread_id, min(19, current + niceness))
    except OSError as exc:
        log.debug(
            "cannot lower the priority of thread %s: %s", threading.current_thread().name, exc
        )
