"""The alert ledger: every alert sent, held for recovery or gone, and the exit status saying so.

Issue 24's cases: 4 alerts in an outage with a cache of 1 (3 lost, named); a daemon whose link
never came up before the end (exit 4, the alerts named, after a bounded wait); the wait ending
early when a link comes; `replay --publish` with no one to publish to (exit 4); a consumer's or
a router's Zenoh file given to the daemon (refused at start). Loopback only, no router unless
the case needs one.
"""

from __future__ import annotations

import logging
import subprocess
import sys
import threading
import time
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import pytest

from fakes import ListSource, ScriptedDetector, alert_message
from repo_paths import child_env
from roadgaze.config import Config, ZenohConfig
from roadgaze.daemon import EXIT_UNDELIVERED, bus_outputs
from roadgaze.errors import ConfigError
from roadgaze.pipeline import Pipeline
from roadgaze.transport import Keys, ZenohLink
from roadgaze.transport.ledger import AlertId, AlertLedger
from roadgaze.transport.link_state import LinkState
from zenoh_helpers import LineReader, endpoint, free_port, router, stop_process, wait_for

FAKE_DAEMON = Path(__file__).resolve().parents[1] / "fake_daemon.py"
GLANCE = [0.0] * 10 + [-30.0] * 50
"""Road 1 s, then away: long_distraction warning at t = 4.1 s (10 fps)."""


def alert_id(seq: int) -> AlertId:
    return AlertId(seq, "long_distraction", "warning", float(seq))


PUSHED_OUT = "pushed out of the publisher's cache (zenoh.alert_cache_size = 1) while no link was up"


def test_four_alerts_in_one_outage_with_a_cache_of_one_three_are_named_lost() -> None:
    ledger = AlertLedger(cache_size=1, grace_s=2.0)
    ledger.published(alert_id(9), True, 0.0, PUSHED_OUT)  # a subscriber was there: delivered
    for seq in range(4):
        ledger.published(alert_id(seq), False, 1.0, PUSHED_OUT)
    assert ledger.lost_total == 3 and len(ledger.held) == 1
    assert [line.split(":")[0] for line in ledger.undelivered()] == [
        "#0 long_distraction warning t=0.00s",
        "#1 long_distraction warning t=1.00s",
        "#2 long_distraction warning t=2.00s",
        "#3 long_distraction warning t=3.00s",
    ]
    assert "pushed out of the publisher's cache" in ledger.undelivered()[0]
    assert ledger.undelivered()[3].endswith("held, no link yet")
    assert ledger.confirm(None, 9.0) == 0  # no link or no subscriber: still waiting
    assert ledger.confirm(5.0, 6.9) == 0  # a subscriber since 5 s: fetching it from the cache
    assert ledger.confirm(5.0, 7.0) == 1  # #3 is in the cache when the link is back: recovered
    assert ledger.stopped() == 0 and ledger.lost_total == 3


def test_alerts_held_when_the_daemon_stops_are_lost_and_the_newest_twenty_named() -> None:
    ledger = AlertLedger(cache_size=100, grace_s=2.0)
    for seq in range(30):
        ledger.published(alert_id(seq), False, 0.0, PUSHED_OUT)
    assert ledger.stopped() == 30 and ledger.lost_total == 30
    named = ledger.undelivered()
    assert len(named) == 20 and named[0].startswith("#10 ") and named[-1].startswith("#29 ")
    assert all(line.endswith("no link when the daemon stopped") for line in named)


class TransportEvent:
    """What Zenoh's transport events listener is given: a router's transport opened or closed."""

    def __init__(self, opened: bool) -> None:
        self.kind = "SampleKind.PUT" if opened else "SampleKind.DELETE"
        self.transport = type("Transport", (), {"zid": "r1", "whatami": "WhatAmI.ROUTER"})()


def test_an_alert_is_delivered_only_when_a_subscriber_could_have_it() -> None:
    now = [0.0]
    state = LinkState(cache_size=10, grace_s=2.0, clock=lambda: now[0])
    state.count_alert(True, alert_id(0))  # no link
    assert state.undelivered()[2] == ["#0 long_distraction warning t=0.00s: held, no link yet"]
    state.on_event(TransportEvent(opened=True))
    assert state.undelivered()[2][0].endswith("in the publisher's cache, no subscriber yet")
    now[0] = 1.0
    state.on_matching(True)  # a subscriber came: it fetches #0 from the cache
    now[0] = 2.9
    assert state.undelivered()[0] == 1 and state.settled_at() == 3.0
    now[0] = 3.0
    assert state.undelivered()[:2] == (0, 0)
    state.count_alert(True, alert_id(1))  # put while it is there: delivered at once
    assert state.undelivered()[0] == 0
    state.on_matching(False)
    state.count_alert(True, alert_id(2))
    now[0] = 10.0
    state.on_matching(True)
    now[0] = 10.1
    state.on_matching(False)  # it left on its own (listen --count): it had #2 to fetch
    assert state.undelivered()[0] == 0
    state.count_alert(True, alert_id(3))
    state.on_event(TransportEvent(opened=False))
    state.count_alert(True, alert_id(4))
    assert state.stopped() == []
    assert state.undelivered()[1:] == (
        2,
        [
            "#3 long_distraction warning t=3.00s: never delivered: no link when the daemon stopped",
            "#4 long_distraction warning t=4.00s: never delivered: no link when the daemon stopped",
        ],
    )


def test_alerts_after_the_last_subscriber_left_stay_on_the_bus_those_before_any_are_gone() -> None:
    """Subscribers come and go (`listen --count`): an alert published after the last one left
    is on the bus, named at exit; when no subscriber ever came, it is gone (exit 4)."""
    for ever in (True, False):
        state = LinkState(cache_size=2, grace_s=2.0, clock=lambda: 0.0)
        state.on_event(TransportEvent(opened=True))
        if ever:
            state.on_matching(True)
            state.on_matching(False)
        for seq in range(3):  # #0 pushed out of the cache of 2
            state.count_alert(True, alert_id(seq))
        left = state.stopped()
        waiting, gone, named = state.undelivered()
        if ever:
            assert left == [
                "#1 long_distraction warning t=1.00s",
                "#2 long_distraction warning t=2.00s",
            ]
            assert (waiting, gone, named) == (0, 0, [])
        else:
            assert left == [] and (waiting, gone) == (0, 3)
            assert named[0] == (
                "#0 long_distraction warning t=0.00s: pushed out of the publisher's cache "
                "(zenoh.alert_cache_size = 2) before any subscriber came"
            )


def dead_end_config(**zenoh: Any) -> Config:
    """A daemon connecting to a port nothing listens on (peer mode: the session opens)."""
    settings = {"vehicle_id": "car-1", "connect": [endpoint(free_port())]} | zenoh
    return Config(zenoh=ZenohConfig.model_validate(settings))


def feed_glance(sinks: tuple[Any, ...]) -> None:
    pipeline = Pipeline.from_config(Config(), ScriptedDetector(GLANCE))
    for processed in pipeline.frames(ListSource(len(GLANCE), fps=10.0)):
        for sink in sinks:
            sink.on_record(processed.record, processed.frame)


def test_no_link_until_the_end_the_bounded_wait_then_the_alert_is_named_and_counted(
    caplog: pytest.LogCaptureFixture,
) -> None:
    config = dead_end_config(delivery_wait_s=0.5)
    caplog.set_level(logging.INFO)
    with bus_outputs(config, "test", publish=True) as bus:
        feed_glance(bus.sinks)
        assert bus.link is not None
        waiting = bus.link.status()
        assert (waiting.alerts_waiting, waiting.alerts_lost) == (1, 0)
        assert waiting.undelivered_alerts == [
            "#0 long_distraction warning t=4.10s: held, no link yet"
        ]
        started = time.monotonic()
    waited_s = time.monotonic() - started
    assert 0.4 <= waited_s < 5.0
    assert bus.undelivered() == 1
    final = bus.link.status()
    assert (final.alerts_waiting, final.alerts_lost, final.alerts_sent) == (0, 1, 0)
    assert "waiting up to 0.5 s for a zenoh link and a subscriber" in caplog.text
    warning = [r.getMessage() for r in caplog.records if "never reached" in r.getMessage()]
    assert warning == [
        "1 of 1 alerts never reached the zenoh bus (exit status 4): #0 long_distraction warning "
        "t=4.10s: never delivered: no link when the daemon stopped"
    ]


def test_the_wait_ends_when_a_link_comes_and_nothing_is_lost() -> None:
    port = free_port()
    config = Config(
        zenoh=ZenohConfig(vehicle_id="car-1", connect=[endpoint(port)], delivery_wait_s=20.0)
    )
    started_router, done = threading.Event(), threading.Event()

    def router_later() -> None:
        time.sleep(0.5)
        with router(port) as bus:
            subscriber = bus.declare_subscriber("vehicle/car-1/dms/alert", lambda sample: None)
            started_router.set()
            done.wait(15.0)
            subscriber.undeclare()

    with bus_outputs(config, "test", publish=True) as bus:
        feed_glance(bus.sinks)
        thread = threading.Thread(target=router_later, daemon=True)
        thread.start()
        started = time.monotonic()
    waited_s = time.monotonic() - started
    done.set()
    thread.join(timeout=15)
    assert started_router.is_set() and waited_s < 10.0
    assert bus.undelivered() == 0
    assert bus.link is not None and bus.link.status().alerts_held_while_down == 1


GLANCE_AND_BACK = GLANCE + [0.0] * 15
"""Two alerts: long_distraction warning at t = 4.1 s, cleared at 6.2 s."""


def late_router_daemon(port: int, wait_s: float) -> Config:
    """A client-mode daemon whose router is not up yet (it re-opens every 0.25 s)."""
    settings = {"mode": "client", "connect": [endpoint(port)], "reconnect_max_s": 0.25}
    return dead_end_config(delivery_wait_s=wait_s, **settings)


def feed(sinks: tuple[Any, ...], yaws: list[float]) -> None:
    pipeline = Pipeline.from_config(Config(), ScriptedDetector(yaws))
    for processed in pipeline.frames(ListSource(len(yaws), fps=10.0)):
        for sink in sinks:
            sink.on_record(processed.record, processed.frame)


def test_alerts_pushed_when_the_router_came_just_before_the_end_reach_a_listener_then() -> None:
    """Issue 34: a client-mode daemon whose router came up just before its source ended pushed
    its 2 held alerts into a cache that lived under a second and exited 0; the listener started
    then received nothing. The daemon now waits (zenoh.delivery_wait_s) for a subscriber and
    gives it the time to fetch them."""
    port = free_port()
    with ExitStack() as stack:
        with bus_outputs(late_router_daemon(port, wait_s=60.0), "test", publish=True) as bus:
            feed(bus.sinks, GLANCE_AND_BACK)
            assert bus.link is not None and bus.link.undelivered()[0] == 2
            stack.enter_context(router(port))
            assert wait_for(lambda: bus.link is not None and bus.link.status().connected, 15.0)
            listener = subprocess.Popen(
                [sys.executable, "-m", "roadgaze", "listen", "--vehicle-id", "car-1", "--no-yaw",
                 "--zenoh-connect", endpoint(port), "--timeout", "90"],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
            )  # fmt: skip
            stack.callback(stop_process, listener)
            printed = LineReader(listener)
        # the source ended here
        lines = printed.until("alive  car-1 left", 60.0)
    alerts = [line.split(" t=")[0] for line in lines if line.startswith("ALERT")]
    assert alerts == [
        "ALERT  car-1 #0 long_distraction warning",
        "ALERT  car-1 #1 cleared info",
    ]
    assert bus.undelivered() == 0


def test_alerts_on_a_bus_nobody_subscribed_to_are_named_and_counted_lost(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The same daemon with no listener: it cannot have delivered them, so it says so (exit 4
    for `run` and `replay --publish`), where it exited 0 before."""
    port = free_port()
    caplog.set_level(logging.INFO)
    config = late_router_daemon(port, wait_s=1.0)
    with router(port), bus_outputs(config, "test", publish=True) as bus:
        feed(bus.sinks, GLANCE_AND_BACK)
        assert bus.link is not None
        assert wait_for(lambda: bus.link is not None and bus.link.status().connected, 15.0)
        status = bus.link.status()
        assert (status.alerts_sent, status.alerts_waiting) == (2, 2)
        assert status.undelivered_alerts[0] == (
            "#0 long_distraction warning t=4.10s: in the publisher's cache, no subscriber yet"
        )
    assert bus.undelivered() == 2
    warning = [r.getMessage() for r in caplog.records if "never reached" in r.getMessage()]
    assert warning == [
        "2 of 2 alerts never reached the zenoh bus (exit status 4): #0 long_distraction warning "
        "t=4.10s: never delivered: no subscriber came to the bus while the daemon ran; #1 "
        "cleared info t=6.20s: never delivered: no subscriber came to the bus while the daemon "
        "ran"
    ]


def test_alerts_before_a_client_session_opens_are_named_at_exit() -> None:
    config = dead_end_config(mode="client")
    link = ZenohLink(config.zenoh, Keys.from_config(config.zenoh))
    with link:
        link.publish_alert(alert_message(0, "car-1"))
        assert link.undelivered()[0] == 1
        link.stop_ledger()
    waiting, gone, named = link.undelivered()
    assert (waiting, gone) == (0, 1)
    assert named == [
        "#0 long_distraction warning t=7.00s: never published: no zenoh session when the daemon "
        "stopped"
    ]


def test_run_with_alerts_never_delivered_exits_4_naming_them() -> None:
    process = subprocess.Popen(
        [sys.executable, str(FAKE_DAEMON), "--vehicle-id", "car-1", "--zenoh-connect",
         endpoint(free_port()), "--set", "zenoh.delivery_wait_s=0.3",
         "--set", "monitor.long_distraction_s=0.5"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
    )  # fmt: skip
    try:
        reader = LineReader(process, process.stderr)
        reader.until("alert long_distraction warning", 60.0)
        process.terminate()
        stderr = "\n".join(reader.until("never reached the zenoh bus", 30.0))
        process.wait(timeout=30)
    finally:
        stop_process(process)
    assert process.returncode == EXIT_UNDELIVERED, stderr[-2000:]
    assert "1 of 1 alerts never reached the zenoh bus (exit status 4): #0 long_distraction" in (
        stderr
    )
    assert "Traceback" not in stderr


def test_replay_publish_that_could_not_publish_exits_4(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import roadgaze.capture
    import roadgaze.pipeline
    from roadgaze.cli import main

    monkeypatch.setattr(roadgaze.pipeline, "create_detector", lambda c: ScriptedDetector(GLANCE))
    monkeypatch.setattr(roadgaze.capture, "open_source", lambda *a, **k: ListSource(60, 10.0))
    video = tmp_path / "drive.mp4"
    video.write_bytes(b"x")
    code = main(
        ["replay", str(video), "--publish", "--out", str(tmp_path / "frames.jsonl"),
         "--zenoh-mode", "client", "--zenoh-connect", endpoint(free_port()),
         "--set", "zenoh.delivery_wait_s=0.2", "--no-progress"]
    )  # fmt: skip
    stderr = capsys.readouterr().err
    assert code == EXIT_UNDELIVERED, stderr[-2000:]
    assert "alerts never reached the zenoh bus" in stderr and "#0 long_distraction" in stderr


@pytest.fixture(scope="module")
def bundle(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from roadgaze.security import init_bundle

    folder = tmp_path_factory.mktemp("bundle")
    init_bundle(folder, Keys.from_config(ZenohConfig(), "car-42"), ["fcw"])
    return folder


@pytest.mark.parametrize(
    ("role", "says"),
    [
        ("consumer-fcw", r"is a consumer.s \(its certificate is consumer.fcw.car-42"),
        ("speed", "is the speed provider's"),
        ("router", "is a router's file"),
    ],
)
def test_a_zenoh_file_that_is_not_the_daemons_is_refused_at_start_with_the_fix(
    bundle: Path, role: str, says: str
) -> None:
    config = ZenohConfig(vehicle_id="car-42", config_file=bundle / role / "zenoh.json5")
    with pytest.raises(ConfigError, match=says) as caught:
        ZenohLink(config, Keys.from_config(config))
    assert "DIR/daemon/zenoh.json5" in str(caught.value)
    other = ZenohConfig(vehicle_id="car-7", config_file=bundle / "daemon" / "zenoh.json5")
    with pytest.raises(ConfigError, match="the daemon file of vehicle 'car-42'"):
        ZenohLink(other, Keys.from_config(other))
    own = ZenohConfig(vehicle_id="car-42", config_file=bundle / "daemon" / "zenoh.json5")
    ZenohLink(own, Keys.from_config(own))  # its own file: accepted (nothing is opened yet)
