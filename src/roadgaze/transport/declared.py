"""Everything the daemon's link declares on one open Zenoh session, closed together.

The alert advanced publisher (cache, sample-miss detection, publisher detection) with a plain
publisher on the same key that is never put on (its matching status tells the alert ledger
whether a subscriber is there, which the advanced publisher does not say), the VSS and yaw
publishers, the speed subscriber (a ring of one), the state queryable with its responder thread
and the liveliness token; see `roadgaze.transport.link` for their QoS and meaning.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from roadgaze.transport.responder import QUERY_RING, StateResponder

if TYPE_CHECKING:
    from roadgaze.transport.link import ZenohLink

log = logging.getLogger("roadgaze.transport.link")

HEARTBEAT_S = 0.5
"""How often the alert publisher announces its last sequence number (lost-alert detection)."""


def undeclare_all(entities: list[Any]) -> None:
    """Undeclare Zenoh entities newest first and forget them; a failure is logged, never raised
    (the session may be closing under them)."""
    for entity in reversed(entities):
        try:
            entity.undeclare()
        except Exception as exc:
            log.debug("undeclare failed: %s", exc)
    entities.clear()


class Declared:
    """Everything declared on one open session; closed together."""

    def __init__(self, session: Any, link: ZenohLink) -> None:
        import zenoh
        from zenoh.ext import CacheConfig, MissDetectionConfig, declare_advanced_publisher

        self.session = session
        self._entities: list[Any] = []
        self.responder: StateResponder | None = None
        self._on_matching = link.link_state.on_matching
        keys = link.keys
        try:
            self._entities.append(
                session.info.declare_transport_events_listener(
                    link.link_state.on_event, history=True
                )
            )
            self.alert = declare_advanced_publisher(
                session,
                keys.alert,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                reliability=zenoh.Reliability.RELIABLE,
                congestion_control=zenoh.CongestionControl.BLOCK,
                priority=zenoh.Priority.REAL_TIME,
                express=True,
                cache=CacheConfig(max_samples=link.config.alert_cache_size),
                # The stub lists both keywords as required; the runtime takes one (zenoh 1.10).
                sample_miss_detection=MissDetectionConfig(heartbeat=HEARTBEAT_S),  # type: ignore[call-arg]
                publisher_detection=True,
            )
            self._entities.append(self.alert)
            matching = session.declare_publisher(keys.alert)
            self._entities.append(matching)
            self._entities.append(
                matching.declare_matching_listener(
                    lambda status: self._on_matching(bool(status.matching))
                )
            )
            self._on_matching(bool(matching.matching_status.matching))
            self.vss: dict[str, Any] = {}
            for key in link.vss_keys:
                self.vss[key] = session.declare_publisher(
                    key,
                    encoding=zenoh.Encoding.TEXT_PLAIN,
                    congestion_control=zenoh.CongestionControl.BLOCK,
                    priority=zenoh.Priority.DATA,
                )
                self._entities.append(self.vss[key])
            self.yaw = session.declare_publisher(
                keys.yaw,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.DROP,
                priority=zenoh.Priority.DATA,
            )
            self._entities.append(self.yaw)
            self.support = session.declare_publisher(
                keys.support,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.DROP,
                priority=zenoh.Priority.REAL_TIME,
                express=True,
            )
            self._entities.append(self.support)
            if link.speed is not None and keys.speed is not None:
                speed_subscriber = session.declare_subscriber(
                    keys.speed, zenoh.handlers.RingChannel(1)
                )
                self._entities.append(speed_subscriber)

                def newest_payload() -> Any:
                    sample = speed_subscriber.try_recv()
                    return None if sample is None else sample.payload

                link.speed.attach(newest_payload)
            if link.state_reply is not None:
                queryable = session.declare_queryable(
                    keys.state, zenoh.handlers.RingChannel(QUERY_RING)
                )
                self._entities.append(queryable)
                self.responder = StateResponder(queryable.handler, link.state_reply, link.reply)
            self._entities.append(session.liveliness().declare_token(keys.alive))
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        undeclare_all(self._entities)
        self._on_matching(False)
        if self.responder is not None:
            self.responder.close()
        try:
            self.session.close()
        except Exception as exc:
            log.debug("session close failed: %s", exc)
