"""The `run` service: what is the daemon's own around the one loop: signals, the link, health.

`bus_outputs` opens the Zenoh link (when publishing) with the `Health` sink answering its state
queries and the `BusPublisher` sink; `roadgaze run`, `roadgaze replay --publish` and the demo use
it. `run_daemon` adds the signal handlers (SIGINT, SIGTERM, SIGHUP) and a source that waits for
a camera, runs `Pipeline.run` until the source ends or a stop, publishes a final state,
undeclares everything and returns 0, or `EXIT_UNDELIVERED` (4) when alerts never reached the
bus (no link before the end, after waiting `zenoh.delivery_wait_s` for one; pushed out of the
publisher's cache; a failed put): a warning names them.
"""

from __future__ import annotations

import gc
import logging
from collections.abc import Iterator
from contextlib import ExitStack, closing, contextmanager
from dataclasses import dataclass
from pathlib import Path

from roadgaze.config import Config
from roadgaze.errors import RoadgazeError
from roadgaze.pipeline import Sink, SpeedSource, no_speed
from roadgaze.service.signals import StopFlag, signal_handlers
from roadgaze.transport import BusPublisher, Health, Keys, SpeedInput, ZenohLink
from roadgaze.transport.failure_watch import PermanentFailureWatch, failure_alert
from roadgaze.transport.health import ALERT_LOG
from roadgaze.transport.vss import VSS_PATHS, VssPublisher, vss_key
from roadgaze.types import Alert, AlertKind

log = logging.getLogger("roadgaze.daemon")

EXIT_UNDELIVERED = 4
"""Exit status of `run` and `replay --publish` when some alerts never reached the bus."""


@dataclass(frozen=True, slots=True)
class BusOutputs:
    """The health sink, the sinks to add to the loop and the speed the monitor should use."""

    health: Health
    sinks: tuple[Sink, ...]
    speed: SpeedSource
    link: ZenohLink | None

    def undelivered(self) -> int:
        """Alerts that never reached the bus (after the `bus_outputs` block: the final count)."""
        if self.link is None:
            return 0
        waiting, gone, _ = self.link.undelivered()
        return waiting + gone


@contextmanager
def bus_outputs(
    config: Config, source_label: str, publish: bool, *, log_name: str = ALERT_LOG
) -> Iterator[BusOutputs]:
    """`Health` (always) and, when `publish`, the Zenoh link and its publisher; on exit the final
    state is published and everything undeclared. Alerts are logged once under `log_name`."""
    keys = Keys.from_config(config.zenoh)
    if not publish:
        health = Health(config, keys, None, source_label, log_name=log_name)
        yield BusOutputs(health=health, sinks=(health,), speed=no_speed, link=None)
        return
    speed = SpeedInput(config.zenoh.speed_timeout_s) if keys.speed is not None else None
    holder: list[Health] = []
    prefix = config.zenoh.vss_prefix
    link = ZenohLink(
        config.zenoh,
        keys,
        state_reply=lambda: holder[0].state_json(),
        speed=speed,
        vss_keys=tuple(vss_key(path, prefix) for path in VSS_PATHS) if config.zenoh.vss else (),
    )
    health = Health(config, keys, link, source_label, log_name=log_name)
    holder.append(health)
    sinks: tuple[Sink, ...] = (health, BusPublisher(keys.vehicle_id, link))
    if config.zenoh.vss:
        sinks = (*sinks, VssPublisher(link, config.monitor, prefix))
    with link:
        try:
            yield BusOutputs(
                health=health,
                sinks=sinks,
                speed=speed.kmh if speed is not None else no_speed,
                link=link,
            )
        finally:
            health.status = "stopped"
            link.settle(config.zenoh.delivery_wait_s)
            link.stop_ledger()
            link.publish_final_state()
            _report_undelivered(link, health, logging.getLogger(log_name))


def _report_undelivered(link: ZenohLink, health: Health, logger: logging.Logger) -> None:
    """The warning naming the alerts that never reached the bus, if any."""
    _, gone, named = link.undelivered()
    if not gone:
        return
    logger.warning(
        "%d of %d alerts never reached the zenoh bus (exit status %d): %s%s",
        gone,
        health.alerts_raised,
        EXIT_UNDELIVERED,
        "; ".join(named),
        "" if gone <= len(named) else f"; and {gone - len(named)} older ones",
    )


def _publish_failure(bus: BusOutputs, alert: Alert) -> None:
    """Count, log and (when publishing) send an alert raised outside the frame loop."""
    bus.health.note_alert(alert)
    for sink in bus.sinks:
        if isinstance(sink, BusPublisher):
            sink.publish_alert(alert)
        elif isinstance(sink, VssPublisher):
            sink.publish_failure(alert.kind is AlertKind.PERMANENT_FAILURE)


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
    from roadgaze import capture
    from roadgaze.pipeline import Pipeline, create_detector
    from roadgaze.service.supervision import Supervisor

    stop = stop if stop is not None else StopFlag()
    with ExitStack() as stack:
        if handle_signals:
            stack.enter_context(signal_handlers(stop))
        supervisor = stack.enter_context(
            Supervisor.from_environment(stop, config.capture.reconnect_max_s)
        )
        bus = stack.enter_context(bus_outputs(config, source_spec, publish=True))
        health = bus.health
        extra: tuple[Sink, ...] = ()
        if record_dir is not None or foxglove is not None:
            from roadgaze.outputs.foxglove.open import vehicle_recorder

            recorder = vehicle_recorder(
                config, source_spec, record_dir, foxglove, health.state_json
            )
            health.problem_checks.append(recorder.problem)
            extra = (stack.enter_context(recorder),)
        # The model loads before the camera opens, so no frame waits for MediaPipe.
        supervisor.status("loading the face landmarker model")
        try:
            detector = stack.enter_context(closing(create_detector(config)))
        except RoadgazeError as exc:  # told on the bus before the one-line error
            _publish_failure(bus, failure_alert(0.0, f"model unusable: {exc}"))
            raise
        supervisor.status(f"opening {source_spec}")
        source = stack.enter_context(capture.open_source(source_spec, config, wait_for_camera=True))
        health.source = source
        watch = PermanentFailureWatch(
            health, lambda alert: _publish_failure(bus, alert), config.monitor.permanent_failure_s
        )
        stack.callback(watch.start().close)
        supervisor.watch(source, source_spec)
        log.info(
            "roadgaze run: source %s, vehicle %s, prefix %s",
            source_spec,
            health.keys.vehicle_id,
            health.keys.prefix,
        )
        pipeline = Pipeline.from_config(config, detector, speed=bus.speed)
        pipeline.run(
            source,
            (*bus.sinks, supervisor, *extra),
            realtime=realtime and not source.info.live,
            stop=stop,
        )
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
    return EXIT_UNDELIVERED if bus.undelivered() else 0
