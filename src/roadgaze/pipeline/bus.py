"""The run's bus: the health every run keeps and, when publishing, the Zenoh link and its sinks.

`bus_outputs` gives the `Health` sink (counts, the alert log lines, the state) and, with
`publish`, opens the `ZenohLink` with the `BusPublisher` and (with `zenoh.vss`) the
`VssPublisher` sinks, and the bus's speed input. On exit it publishes the final state, waits up
to `zenoh.delivery_wait_s` for a link for alerts still held, and names the alerts that never
reached the bus (`EXIT_UNDELIVERED`).
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from roadgaze.config import Config
from roadgaze.speed import SpeedSource, no_speed
from roadgaze.transport import BusPublisher, Health, Keys, SpeedInput, ZenohLink
from roadgaze.transport.health import ALERT_LOG
from roadgaze.transport.vss import VSS_PATHS, VssPublisher, vss_key
from roadgaze.types import Sink

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
    config: Config,
    source_label: str,
    publish: bool,
    *,
    log_name: str = ALERT_LOG,
    ending: str = "the daemon stopped",
) -> Iterator[BusOutputs]:
    """`Health` (always) and, when `publish`, the Zenoh link and its publisher; on exit the final
    state is published and everything undeclared. Alerts are logged once under `log_name`;
    `ending` says, for an alert that never reached the bus, what ended while it waited."""
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
            link.stop_ledger(ending)
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
