"""Which endpoints a daemon and a consumer use, the insecure-endpoint warning, and the link's
alert accounting from transport events (no network needed)."""

from __future__ import annotations

import logging
from dataclasses import dataclass

import pytest

from roadgaze.config import ZenohConfig
from roadgaze.transport import (
    LinkState,
    build_zenoh_config,
    endpoint_in_use,
    insecure_endpoints,
    plan_session,
)
from zenoh_helpers import endpoint, free_port, router

RENDEZVOUS = "tcp/127.0.0.1:7447"


@pytest.mark.parametrize(
    ("settings", "taken", "expected"),
    [
        ({}, False, ("peer", (), (RENDEZVOUS,))),  # nothing there: the daemon listens
        ({}, True, ("peer", (RENDEZVOUS,), ())),  # a router or daemon there: connect
        ({"mode": "client"}, False, ("client", (RENDEZVOUS,), ())),
        ({"connect": ["tcp/10.0.0.5:7447"]}, False, ("peer", ("tcp/10.0.0.5:7447",), ())),
        ({"listen": ["tcp/127.0.0.1:9000"]}, True, ("peer", (), ("tcp/127.0.0.1:9000",))),
        ({"rendezvous": ""}, False, ("peer", (), ())),
    ],
)
def test_daemon_endpoints(
    settings: dict[str, object], taken: bool, expected: tuple[str, tuple[str, ...], tuple[str, ...]]
) -> None:
    plan = plan_session(ZenohConfig.model_validate(settings), "daemon", probe=lambda e: taken)
    assert (plan.mode, plan.connect, plan.listen) == expected
    if plan.connect:
        retry = plan.settings["connect/retry"]
        assert (retry["period_init_ms"], retry["period_max_ms"]) == (250, 1000)
    assert plan.settings["scouting/multicast/enabled"] is False
    build_zenoh_config(plan)  # Zenoh accepts it


def test_consumers_are_clients_of_the_rendezvous_unless_told() -> None:
    never = lambda endpoint: pytest.fail("a consumer does not probe")  # noqa: E731
    plan = plan_session(ZenohConfig(), "consumer", probe=never)
    assert (plan.mode, plan.connect, plan.listen) == ("client", (RENDEZVOUS,), ())
    assert "connecting to tcp/127.0.0.1:7447" in plan.describe()
    peer = plan_session(ZenohConfig(connect=["tcp/127.0.0.1:9"]), "consumer", mode="peer")
    assert (peer.mode, peer.connect) == ("peer", ("tcp/127.0.0.1:9",))


def test_the_rendezvous_probe_sees_a_listening_router() -> None:
    port = free_port()
    assert not endpoint_in_use(endpoint(port))
    with router(port):
        assert endpoint_in_use(endpoint(port))
    assert endpoint_in_use("udp/127.0.0.1:9")  # cannot be probed: connect to it


def test_insecure_endpoints_are_the_plain_ones_off_this_machine() -> None:
    endpoints = [
        "tcp/127.0.0.1:7447",
        "tcp/localhost:7447",
        "tcp/[::1]:7447",
        "tls/10.0.0.5:7447",
        "tcp/10.0.0.5:7447",
        "udp/192.168.1.2:7447",
    ]
    assert insecure_endpoints(endpoints) == ["tcp/10.0.0.5:7447", "udp/192.168.1.2:7447"]


def test_the_daemon_warns_at_start_about_plain_tcp_off_this_machine(
    caplog: pytest.LogCaptureFixture,
) -> None:
    from roadgaze.transport import Keys, ZenohLink

    config = ZenohConfig(connect=["tcp/192.0.2.1:7447"], listen=[])  # TEST-NET-1: unreachable
    with caplog.at_level(logging.INFO), ZenohLink(config, Keys.from_config(config)) as link:
        assert not link.status().connected
    messages = [record.getMessage() for record in caplog.records]
    assert any("connecting to tcp/192.0.2.1:7447" in m for m in messages)
    assert any("leave this machine without TLS" in m for m in messages)
    assert not any("zenoh connected" in m for m in messages)


@dataclass
class Transport:
    zid: str
    whatami: str


@dataclass
class Event:
    kind: str
    transport: Transport


def test_alerts_are_sent_only_while_a_transport_is_open_and_beyond_the_cache_counted(
    caplog: pytest.LogCaptureFixture,
) -> None:
    state = LinkState(cache_size=3)
    router_event = Transport("r1", "WhatAmI.ROUTER")
    with caplog.at_level(logging.INFO):
        state.count_alert(published=True)  # before any link: held
        state.on_event(Event("SampleKind.PUT", router_event))
        state.count_alert(published=True)  # sent
        state.on_event(Event("SampleKind.DELETE", router_event))
        for _ in range(5):  # one outage: 3 fit the cache, 2 pushed out
            state.count_alert(published=True)
        state.count_alert(published=False)
        state.on_event(Event("SampleKind.PUT", router_event))
        state.on_event(Event("SampleKind.PUT", Transport("c1", "WhatAmI.CLIENT")))
    counts = state.snapshot()
    assert (counts.published, counts.sent, counts.held_while_down) == (7, 1, 6)
    assert (counts.beyond_cache, counts.failed) == (2, 1)
    assert state.remotes() == (1, 0, 1) and (state.ups, state.downs) == (2, 1)
    messages = [record.getMessage() for record in caplog.records]
    assert sum("zenoh connected: router r1" in m for m in messages) == 2
    assert sum("zenoh link down" in m for m in messages) == 1
