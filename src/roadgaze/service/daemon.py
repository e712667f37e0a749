"""The `run` service: what is the daemon's own around the one loop: signals, systemd, shutdown.

`run_daemon` builds the run (`roadgaze.pipeline.build_run`: the Zenoh link with the `Health`
and publisher sinks, the recorder, the model, a camera waited for, the permanent-failure watch)
under the signal handlers (SIGINT, SIGTERM, SIGHUP) and systemd's notifications, runs
`Run.run` until the source ends or a stop, publishes a final state, undeclares everything and
returns 0, or `EXIT_UNDELIVERED` (4) when alerts never reached the bus (no link before the end,
after waiting `zenoh.delivery_wait_s` for one; pushed out of the publisher's cache; a failed
put): a warning names them.
"""

from __future__ import annotations

import gc
import logging
from contextlib import ExitStack
from pathlib import Path

from roadgaze.config import Config
from roadgaze.pipeline.bus import EXIT_UNDELIVERED
from roadgaze.service.signals import StopFlag, signal_handlers

log = logging.getLogger("roadgaze.daemon")


def run_daemon(
    config: Config,
    source_spec: str,
    stop: StopFlag | None = None,
    realtime: bool = True,
    handle_signals: bool = True,
    record_dir: Path | None = None,
    foxglove: str | None = None,
) -> int:
    """Monitor `source_spec` and publish until the source ends or a stop; returns 0, or
    `EXIT_UNDELIVERED` when some alerts never reached the bus (a warning names them).

    A camera that cannot be opened is waited for with backoff (capture.reconnect_*) and reported
    in the state as degraded; a missing file is a `SourceError`. An unreachable Zenoh peer never
    stops monitoring (see `ZenohLink`). Under systemd (`$NOTIFY_SOCKET`) it sends READY, WATCHDOG
    and STOPPING notifications (see `roadgaze.service.supervision`). `record_dir` records MCAP
    segments there and `foxglove` (`[HOST:]PORT`) serves the live view (docs/foxglove.md); a
    recording that fails is reported in the state, never fatal.
    """
    from roadgaze.pipeline import RunOptions, build_run
    from roadgaze.service.supervision import Supervisor

    stop = stop if stop is not None else StopFlag()
    options = RunOptions(
        source_spec,
        command="run",
        publish=True,
        record_dir=record_dir,
        foxglove=foxglove,
        wait_for_camera=True,
        watch_failures=True,
    )
    with ExitStack() as stack:
        if handle_signals:
            stack.enter_context(signal_handlers(stop))
        supervisor = stack.enter_context(
            Supervisor.from_environment(stop, config.capture.reconnect_max_s)
        )
        run = stack.enter_context(
            build_run(config, options, sinks=(supervisor,), on_step=supervisor.status)
        )
        health = run.health
        supervisor.watch(run.source, source_spec)
        log.info(
            "roadgaze run: source %s, vehicle %s, prefix %s",
            source_spec,
            health.keys.vehicle_id,
            health.keys.prefix,
        )
        run.run(realtime=realtime and not run.source.info.live, stop=stop)
        health.status = "stopping"
        supervisor.stopping(stop.signal_name or "end of source")
        log.info(
            "roadgaze run: stopping (%s) after %d frames, %d alerts",
            stop.signal_name or "end of source",
            health.frames,
            health.alerts_raised,
        )
    # MediaPipe's objects are finalised here, while the stop handlers still stand (a second
    # signal during a finaliser then exits 1 at once, never "Exception ignored" and exit 130).
    gc.collect()
    return EXIT_UNDELIVERED if run.undelivered() else 0
