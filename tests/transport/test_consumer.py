"""`AlertConsumer`: the checked events a consumer gets, on real Zenoh sessions on loopback.

A Python router session on a free port stands in for zenohd and plays the attacker; the daemon
is a real `ZenohLink` (its advanced publisher, cache, token and state). The pure parts (numbers
late or repeated, the book's publishers) are checked without Zenoh.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import pytest
import zenoh

from fakes import alert_message
from roadgaze.config import Config, ZenohConfig
from roadgaze.transport import Health, Keys, ZenohLink
from roadgaze.transport import consumer_events as events
from roadgaze.transport.alert_book import AlertBook
from roadgaze.transport.checks import DuplicateSeqError, MessageChecker
from roadgaze.transport.consumer import AlertConsumer
from roadgaze.types import AlertKind, AlertLevel
from zenoh_helpers import advanced_publisher, client_config, endpoint, free_port, router, wait_for

VEHICLE = "car-1"
ALERT_KEY = f"vehicle/{VEHICLE}/dms/alert"
TEMPLATE = "vehicle/{vehicle_id}/dms"


def until(
    consumer: AlertConsumer, done: Callable[[list[Any]], bool], timeout_s: float = 20.0
) -> list[Any]:
    """The events read until `done(events)` holds; AssertionError after `timeout_s`."""
    seen: list[Any] = []
    deadline = time.monotonic() + timeout_s
    for event in consumer.events(timeout_s):
        seen.append(event)
        if done(seen):
            return seen
        if time.monotonic() > deadline:
            break
    raise AssertionError(f"not done in {timeout_s} s: {seen[-8:]}")


def alerts_of(seen: list[Any]) -> list[events.AlertReceived]:
    return [event for event in seen if isinstance(event, events.AlertReceived)]


def daemon(port: int) -> ZenohLink:
    """The daemon's link, answering with its real state (`Health`)."""
    config = Config(zenoh=ZenohConfig(vehicle_id=VEHICLE, connect=[endpoint(port)]))
    keys = Keys.from_config(config.zenoh)
    health: list[Health] = []
    link = ZenohLink(config.zenoh, keys, state_reply=lambda: health[0].state_json())
    health.append(Health(config, keys, link, "test"))
    health[0].status = "stopped"
    return link


def consumer_of(port: int, **settings: Any) -> AlertConsumer:
    config = ZenohConfig(connect=[endpoint(port)], **settings)
    return AlertConsumer.connect(config, VEHICLE, wait_s=20.0)


def test_history_first_then_live_alerts_a_gap_a_duplicate_and_a_forgery() -> None:
    port = free_port()
    with router(port) as attacker, daemon(port) as link:
        assert wait_for(lambda: link.status().connected, 15.0)
        for seq in range(2):  # before the consumer exists: from the cache
            link.publish_alert(alert_message(seq, VEHICLE))
        with consumer_of(port) as consumer:
            seen = until(consumer, lambda seen: len(alerts_of(seen)) == 2)
            kinds = [type(event) for event in seen]
            assert kinds.index(events.LinkUp) < kinds.index(events.PublisherJoined)
            assert kinds.index(events.PublisherJoined) < kinds.index(events.AlertReceived)
            block = zenoh.CongestionControl.BLOCK
            attacker.put(
                ALERT_KEY, alert_message(0, VEHICLE).to_json_bytes(), congestion_control=block
            )
            attacker.put(ALERT_KEY, b"[" * 50_000, congestion_control=block)
            attacker.put(ALERT_KEY, b"x" * 100_000, congestion_control=block)
            for seq in (2, 2, 4):  # #2 twice, #3 never
                link.publish_alert(alert_message(seq, VEHICLE))
            seen += until(consumer, lambda more: len(alerts_of(more)) == 2)
    refused = [event for event in seen if isinstance(event, events.AlertRefused)]
    rejected = [event for event in seen if isinstance(event, events.MessageRejected)]
    assert [alert.seq for alert in alerts_of(seen)] == [0, 1, 2, 4]
    assert all(alert.suspicious is None for alert in alerts_of(seen))
    assert len(refused) == 1 and "a plain put" in refused[0].describe()
    assert [r.reason for r in rejected] == ["JSON nested too deeply", "100000 bytes, limit 65536"]
    (duplicate,) = [event for event in seen if isinstance(event, events.DuplicateAlert)]
    assert (duplicate.seq, duplicate.expected) == (2, 3)
    (missed,) = [event for event in seen if isinstance(event, events.AlertsMissed)]
    assert (missed.span, missed.count) == ("#3", 1)
    assert missed.describe().startswith("MISSED alerts #3 of car-1 (1): lost while a link")
    assert consumer.book.printed == 4 and consumer.book.foreign == 1
    assert consumer.book.rejected == 3 and consumer.book.missed == 1


def test_a_second_publisher_is_handed_on_flagged_even_when_it_spoke_first() -> None:
    """Issue 34: a forger that spoke first was taken as the vehicle and the daemon's real alert
    was hidden. Both are handed on now, each naming its publisher."""

    port = free_port()
    with router(port), zenoh.open(client_config([endpoint(port)])) as forger_session:
        forger = advanced_publisher(forger_session, ALERT_KEY)
        with daemon(port) as link, consumer_of(port) as consumer:
            assert wait_for(lambda: link.status().connected, 15.0)
            until(consumer, lambda seen: isinstance(seen[-1], events.PublisherJoined))
            cleared = alert_message(0, VEHICLE).model_copy(
                update={"kind": AlertKind.CLEARED, "level": AlertLevel.INFO}
            )
            forger.put(cleared.to_json_bytes())  # live, or from its cache once detected
            seen = until(consumer, lambda seen: len(alerts_of(seen)) == 1)
            link.publish_alert(alert_message(0, VEHICLE))
            seen += until(consumer, lambda more: len(alerts_of(more)) == 1)
    real = next(a for a in alerts_of(seen) if a.alert["kind"] == "long_distraction")
    forged = alerts_of(seen)[0]
    assert forged.alert["kind"] == "cleared" and not forged.second_publisher
    assert real.second_publisher and real.suspicious is not None
    assert real.suspicious.startswith(f"publisher 2 of 2 of {VEHICLE}")
    assert "a second publisher" in (real.describe_second() or "")
    second = [event for event in seen if isinstance(event, events.SecondPublisher)]
    assert len(second) == 1 and second[0].publishers == real.publishers
    assert consumer.book.flagged == 1


def test_the_final_state_comes_before_the_daemon_is_gone() -> None:
    port = free_port()
    with router(port), consumer_of(port) as consumer:
        consumer.subscribe()
        with daemon(port) as link:
            assert wait_for(lambda: link.status().connected, 15.0)
            until(consumer, lambda seen: isinstance(seen[-1], events.PublisherJoined))
            link.publish_final_state()
        seen = until(consumer, lambda seen: isinstance(seen[-1], events.PublisherGone))
    assert [type(event) for event in seen[-2:]] == [events.MessageReceived, events.PublisherGone]
    assert seen[-2].kind == "state" and seen[-2].payload["status"] == "stopped"
    assert seen[-1].vehicle_id == VEHICLE


def test_run_calls_back_with_each_event_until_stopped() -> None:
    port = free_port()
    seen: list[Any] = []
    with router(port), consumer_of(port) as consumer, daemon(port) as link:
        assert wait_for(lambda: link.status().connected, 15.0)
        link.publish_alert(alert_message(0, VEHICLE))
        consumer.run(seen.append, timeout_s=30.0, stopped=lambda: bool(alerts_of(seen)))
    assert [type(event) for event in seen if not isinstance(event, events.LinkUp)] == [
        events.PublisherJoined,
        events.AlertReceived,
    ]


def test_a_late_alert_is_told_from_a_duplicate() -> None:
    checker = MessageChecker(TEMPLATE)

    def check(seq: int) -> Any:
        return checker.check("alert", ALERT_KEY, alert_message(seq, VEHICLE).to_json_bytes(), "s")

    assert check(0).first and check(3).missing_before == 2  # #1 and #2 skipped
    late = check(2)
    assert late.late and late.expected == 4 and late.missing_before == 0
    with pytest.raises(DuplicateSeqError, match="seq 2, expected 4"):
        check(2)
    with pytest.raises(DuplicateSeqError, match="seq 3, expected 4"):
        check(3)
    assert check(1).late


def test_the_book_keeps_every_publisher_first_first_and_says_what_it_printed() -> None:
    book = AlertBook()
    assert book.foreign_source(VEHICLE, "forger") is None  # the first one seen
    assert "a second publisher (daemon; the vehicle's first is forger)" in (
        book.foreign_source(VEHICLE, "daemon") or ""
    )
    assert book.publishers(VEHICLE) == ("forger", "daemon")
    book.printed, book.foreign, book.flagged = 1, 3, 2
    assert "3 foreign alerts (another publisher: 2 of a second publisher, printed flagged; " in (
        book.totals(0)
    )
    book.on_alive(VEHICLE, alive=True)
    assert book.publishers(VEHICLE) == ()
