"""`roadgaze listen` tells what it did not print: missing alert ranges, foreign publishers, totals.

Issue 24's cases on loopback: 4 alerts in an outage with `alert_cache_size = 1` and a listener
connected before it (#0-#2 named missing); a second publisher of the vehicle's alerts (flagged
every time, not printed); the order a late listener prints in (`alive joined` before the cached
alerts, the final state before `alive left`); the hint when something listens but refuses the
session.
"""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import threading
import time
from typing import Any

import zenoh

import zenoh_helpers as zh
from fakes import alert_message
from repo_paths import child_env
from roadgaze.commands.listen_alerts import AlertBook
from roadgaze.config import Config, ZenohConfig
from roadgaze.transport import Health, Keys, ZenohLink
from roadgaze.transport.session import SessionPlan, unreachable_hint
from roadgaze.types import AlertKind, AlertLevel
from zenoh_helpers import LineReader, RouterProcess, endpoint, free_port

VEHICLE = "car-1"
SOURCE = "EntityGlobalId { zid: aa, eid: 6 }"


def test_the_book_names_missing_ranges_and_foreign_publishers() -> None:
    book = AlertBook()
    assert book.foreign_source(VEHICLE, SOURCE) is None
    assert book.gap(VEHICLE, SOURCE, 0, 0, first=True) is None
    book.on_zenoh_miss(SOURCE, 2)
    line = book.gap(VEHICLE, SOURCE, 4, 3, first=False)
    assert line == (
        "MISSED alerts #1-#3 of car-1 (3): lost while a link was down: more alerts than the "
        "daemon's cache holds (zenoh.alert_cache_size); zenoh reported 2 missed"
    )
    assert book.gap("car-2", "other", 3, 0, first=True) is not None  # #0-#2 before it joined
    assert book.foreign_source(VEHICLE, None) is not None  # a plain put
    assert "a second publisher (x" in (book.foreign_source(VEHICLE, "x") or "")
    book.on_alive(VEHICLE, alive=False)  # the daemon went: its successor is the vehicle's
    assert book.foreign_source(VEHICLE, "x") is None
    book.on_zenoh_miss("x", 5)
    assert book.unmatched_misses() == [
        "MISSED 5 alerts of car-1 (zenoh sample-miss from x; no later alert gave their numbers)"
    ]
    assert book.totals(dropped=0) == (
        "totals: 0 alerts printed, 11 missed (#1-#3 of car-1, #0-#2 of car-2, 5 unnumbered of "
        "car-1), 0 messages rejected, 0 foreign alerts (another publisher), 0 dropped "
        "(printing too slow)"
    )


def listen(port: int, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "roadgaze", "listen", "--vehicle-id", VEHICLE, "--no-yaw",
         "--zenoh-connect", endpoint(port), *args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
    )  # fmt: skip


def stop(process: subprocess.Popen[str]) -> str:
    process.send_signal(signal.SIGTERM)
    assert process.wait(timeout=20) == 0
    return process.stderr.read() if process.stderr else ""


def daemon_link(port: int, **settings: Any) -> tuple[ZenohLink, Health]:
    config = Config(
        zenoh=ZenohConfig.model_validate(
            {"vehicle_id": VEHICLE, "connect": [endpoint(port)]} | settings
        )
    )
    keys = Keys.from_config(config.zenoh)
    holder: list[Health] = []
    link = ZenohLink(config.zenoh, keys, state_reply=lambda: holder[0].state_json())
    holder.append(Health(config, keys, link, "test"))
    return link, holder[0]


def test_alerts_pushed_out_of_a_cache_of_one_are_named_missing_by_a_listener() -> None:
    """The issue: 4 alerts while the router was down, the listener printed #3 and said nothing."""
    port = free_port()
    router_process = RouterProcess(port)
    router_process.start()
    link, _ = daemon_link(port, alert_cache_size=1)
    process = listen(port)
    try:
        with link:
            reader = LineReader(process, process.stderr)
            reader.until("connected to router", 30.0)
            assert zh.wait_for(lambda: link.status().connected, 15.0)
            router_process.kill()
            assert zh.wait_for(lambda: not link.status().connected, 10.0)
            for seq in range(4):
                link.publish_alert(alert_message(seq, VEHICLE))
            router_process.start()
            lines = reader.until("MISSED alerts #0-#2 of car-1 (3)", 30.0)
            printed = LineReader(process).until("ALERT", 10.0)
            assert next(line for line in printed if "ALERT" in line).startswith("ALERT  car-1 #3 ")
            assert link.status().alerts_lost == 3
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=20) == 0
        totals = reader.until("totals:", 10.0)[-1]
    finally:
        zh.stop_process(process)
        router_process.stop()
    assert "Traceback" not in "".join(lines)
    assert "totals: 1 alerts printed, 3 missed (#0-#2 of car-1)" in totals


def test_a_second_publisher_of_the_vehicles_alerts_is_flagged_every_time() -> None:

    port = free_port()
    with zh.router(port), zenoh.open(zh.client_config([endpoint(port)])) as intruder:
        link, _ = daemon_link(port)
        with link:
            assert zh.wait_for(lambda: link.status().connected, 15.0)
            link.publish_alert(alert_message(0, VEHICLE))
            process = listen(port, "--timeout", "30")
            try:
                assert process.stdout is not None
                assert "ALERT  car-1 #0" in (LineReader(process).until("ALERT", 20.0)[-1])
                second = zh.advanced_publisher(intruder, f"vehicle/{VEHICLE}/dms/alert")
                for seq in (100, 101):
                    second.put(alert_message(seq, VEHICLE).to_json_bytes())
                intruder.put(
                    f"vehicle/{VEHICLE}/dms/alert",
                    alert_message(102, VEHICLE).to_json_bytes(),
                    congestion_control=zenoh.CongestionControl.BLOCK,
                )
                link.publish_alert(alert_message(1, VEHICLE))
                assert zh.wait_for(lambda: link.status().alerts_sent == 2, 5.0)
                time.sleep(1.0)  # the three foreign alerts and #1 reach the listener
                stderr = stop(process)
            finally:
                zh.stop_process(process)
    assert stderr.count("SUSPICIOUS alert #") == 3, stderr
    assert "SUSPICIOUS alert #100 long_distraction warning of car-1 from a second publisher" in (
        stderr
    )
    assert "#102" in stderr and "a plain put" in stderr
    assert "totals: 2 alerts printed, 0 missed, 0 messages rejected, 3 foreign" in stderr


def test_a_forger_that_speaks_first_never_hides_the_daemons_real_alert() -> None:
    """Issue 34: a second publisher putting forged `cleared` alerts before the daemon's first
    alert was taken as the vehicle, and the real `long_distraction` was hidden ("not
    printed"). Both are printed now, each flagged with its publisher."""

    port = free_port()
    with zh.router(port), zenoh.open(zh.client_config([endpoint(port)])) as forger_session:
        link, _ = daemon_link(port)
        with link:
            assert zh.wait_for(lambda: link.status().connected, 15.0)
            process = listen(port, "--timeout", "60")
            try:
                reader = LineReader(process)
                assert reader.until("alive  car-1 joined", 30.0)
                forger = zh.advanced_publisher(forger_session, f"vehicle/{VEHICLE}/dms/alert")
                cleared = alert_message(0, VEHICLE).model_copy(
                    update={"kind": AlertKind.CLEARED, "level": AlertLevel.INFO}
                )
                forger.put(cleared.to_json_bytes())
                forged = reader.until("ALERT", 20.0)[-1]
                link.publish_alert(alert_message(0, VEHICLE))
                real = reader.until("ALERT", 20.0)[-1]
                stderr = stop(process)
            finally:
                zh.stop_process(process)
    assert forged.startswith("ALERT  car-1 #0 cleared info") and "SUSPICIOUS" not in forged
    assert real.startswith("ALERT  car-1 #0 long_distraction warning")
    assert "[SUSPICIOUS: publisher 2 of 2 of car-1 (" in real
    assert "SUSPICIOUS: 2 publishers of car-1's alerts" in stderr
    assert "SUSPICIOUS alert #0 long_distraction warning of car-1 from a second publisher" in (
        stderr
    )
    assert "): not printed" not in stderr  # nothing hidden
    assert (
        "totals: 1 alerts printed, 0 missed, 0 messages rejected, 1 foreign alerts (another "
        "publisher: 1 of a second publisher, printed flagged; 0 plain puts, not printed)"
    ) in stderr


def test_a_late_listener_prints_joined_first_and_the_final_state_before_left() -> None:
    port = free_port()
    with zh.router(port):
        link, health = daemon_link(port)
        process = listen(port, "--timeout", "30")
        try:
            with link:
                assert zh.wait_for(lambda: link.status().connected, 15.0)
                link.publish_alert(alert_message(0, VEHICLE))
                reader = LineReader(process)
                first = reader.until("ALERT", 20.0)
                health.status = "stopped"
                link.publish_final_state()
            rest = reader.until("alive  car-1 left", 20.0)
            stop(process)
        finally:
            zh.stop_process(process)
    assert first[0] == "alive  car-1 joined" and "#0 long_distraction" in first[-1]
    assert "status=stopped" in rest[-2] and "alerts_sent=1 held=0 lost=0" in rest[-2]


def test_something_listening_that_refuses_the_session_gets_a_tls_hint() -> None:
    with socket.socket() as server:  # like a TLS router given zenoh's plain TCP: hangs up
        server.bind(("127.0.0.1", 0))
        server.listen(16)
        port = server.getsockname()[1]

        def hang_up() -> None:
            while True:
                try:
                    connection, _ = server.accept()
                except OSError:
                    return
                connection.close()

        threading.Thread(target=hang_up, daemon=True).start()
        plain = SessionPlan("client", (f"tcp/127.0.0.1:{port}",), (), {})
        tls = SessionPlan("client", (f"tls/127.0.0.1:{port}",), (), {})
        assert "takes tls/ endpoints and a consumer's file" in unreachable_hint(plain)
        assert "refused the TLS session: a certificate from another CA" in unreachable_hint(tls)
        result = subprocess.run(
            [sys.executable, "-m", "roadgaze", "listen", "--zenoh-connect", plain.connect[0],
             "--timeout", "2"],
            capture_output=True, text=True, timeout=60, env=child_env(), check=False,
        )  # fmt: skip
        waiting = subprocess.Popen(  # no --timeout: it waits, and says why at once
            [sys.executable, "-m", "roadgaze", "listen", "--zenoh-connect", plain.connect[0]],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
        )  # fmt: skip
        try:
            said = LineReader(waiting, waiting.stderr).until("zenoh session refused", 30.0)
            waiting.send_signal(signal.SIGTERM)
            assert waiting.wait(timeout=20) == 0
        finally:
            zh.stop_process(waiting)
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert "something listens at tcp/127.0.0.1" in result.stderr
    assert "takes tls/ endpoints" in said[-1]
    nobody = SessionPlan("client", (endpoint(free_port()),), (), {})
    assert unreachable_hint(nobody) == "is `roadgaze run` or a router up?"
