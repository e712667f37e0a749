"""The stop signals act off the signal handler: a signal landing while the main thread holds a
lock that is not re-entrant (the recorder's log tap puts into a `queue.Queue`) is logged and
stops the run, where logging from the handler itself waited forever on its own thread (the
daemon hung at SIGTERM with a recorder, once in a few hundred stops)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

from repo_paths import child_env

PROBE = textwrap.dedent(
    """
    import logging, os, signal, threading, time
    from roadgaze.service.signals import StopFlag, signal_handlers

    held = threading.Lock()  # not re-entrant, as a queue.Queue's mutex

    class Tap(logging.Handler):
        def emit(self, record):
            with held:
                print("logged:", record.getMessage(), flush=True)

    logger = logging.getLogger("roadgaze.probe")
    logger.addHandler(Tap())
    logger.setLevel(logging.INFO)
    stop = StopFlag()
    with signal_handlers(stop, log_name="roadgaze.probe"):
        with held:  # the main thread is inside the tap when the signal lands
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.2)
        print("stopped:", stop.wait(10.0), stop.signal_name, flush=True)
    """
)


def test_a_signal_inside_a_held_lock_is_logged_and_stops_the_run() -> None:
    done = subprocess.run(
        [sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=60,
        env=child_env(),
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.splitlines() == [
        "logged: SIGTERM received: finishing the current frame",
        "stopped: True SIGTERM",
    ]
