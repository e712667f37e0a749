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
from zenoh_helpers import LineReader, endpoint, free_port, router, stop_process

FAKE_DAEMON = Path(__file__).resolve().parents[1] / "fake_daemon.py"
GLANCE = [0.0] * 10 + [-30.0] * 50
"""Road 1 s, then away: long_distraction warning at t = 4.1 s (10 fps)."""


def alert_id(seq: int) -> AlertId:
    return AlertId(seq, "long_distraction", "warning", float(seq))


def test_four_alerts_in_one_outage_with_a_cache_of_one_three_are_named_lost() -> None:
    ledger = AlertLedger(cache_size=1)
    ledger.published(alert_id(9), link_up=True)  # sent: never held
    for seq in range(4):
        ledger.published(alert_id(seq), link_up=False)
    assert ledger.lost_total == 3 and len(ledger.held) == 1
    assert [line.split(":")[0] for line in ledger.undelivered()] == [
        "#0 long_distraction warning t=0.00s",
        "#1 long_distraction warning t=1.00s",
        "#2 long_distraction warning t=2.00s",
        "#3 long_distraction warning t=3.00s",
    ]
    assert "pushed out of the publisher's cache" in ledger.undelivered()[0]
    assert ledger.undelivered()[3].endswith("held, no link yet")
    assert ledger.link_up() == 1  # #3 is in the cache when the link is back: recoverable
    assert ledger.stopped() == 0 and ledger.lost_total == 3


def test_alerts_held_when_the_daemon_stops_are_lost_and_the_newest_twenty_named() -> None:
    ledger = AlertLedger(cache_size=100)
    for seq in range(30):
        ledger.published(alert_id(seq), link_up=False)
    assert ledger.stopped() == 30 and ledger.lost_total == 30
    named = ledger.undelivered()
    assert len(named) == 20 and named[0].startswith("#10 ") and named[-1].startswith("#29 ")
    assert all(line.endswith("no link when the daemon stopped") for line in named)


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
    assert "waiting up to 0.5 s for a zenoh link" in caplog.text
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
        with router(port):
            started_router.set()
            done.wait(15.0)

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
