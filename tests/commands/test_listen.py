"""`roadgaze listen` on real Zenoh sessions: hostile payloads, forged answers, timeouts, signals.

A router session on a free loopback port stands in for zenohd and plays the attacker; `listen`
runs as a child process (its exit code and both streams are what a user sees).
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from typing import Any

import pytest
import zenoh

from fakes import BLANK_FRAME, alert_message, record_of
from repo_paths import child_env
from roadgaze.config import Config, ZenohConfig
from roadgaze.transport import Health, Keys
from roadgaze.types import PoseSample
from zenoh_helpers import (
    LineReader,
    advanced_publisher,
    client_config,
    endpoint,
    free_port,
    router,
    stop_process,
    wait_for,
)

VEHICLE = "car-1"
ALERT_KEY = f"vehicle/{VEHICLE}/dms/alert"
STATE_KEY = f"vehicle/{VEHICLE}/dms/state"


def listen(port: int, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "roadgaze", "listen", "--vehicle-id", VEHICLE,
         "--zenoh-connect", endpoint(port), *args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
    )  # fmt: skip


def stop_cleanly(process: subprocess.Popen[str]) -> str:
    """SIGTERM `listen` as systemd would; its stderr, once it has exited 0 without a traceback."""
    process.send_signal(signal.SIGTERM)
    code = process.wait(timeout=20)
    stderr = process.stderr.read() if process.stderr else ""
    assert code == 0, stderr[-2000:]
    assert "Traceback" not in stderr, stderr[-2000:]
    return stderr


def valid_state(**changes: Any) -> bytes:
    config = Config(zenoh=ZenohConfig(vehicle_id=VEHICLE))
    health = Health(config, Keys.from_config(config.zenoh), None, "test")
    health.on_record(record_of(PoseSample(0.0, 0, True, 0.0, 0.0, 0.0, 1.0)), BLANK_FRAME)
    document = json.loads(health.state_json()) | changes
    return json.dumps(document).encode()


def daemon_publisher(session: zenoh.Session) -> Any:
    """An advanced publisher of the vehicle's alerts, as the daemon declares it."""
    return advanced_publisher(session, ALERT_KEY)


def test_hostile_payloads_are_reported_and_the_valid_alert_printed_once() -> None:
    port = free_port()
    with router(port) as attacker, zenoh.open(client_config([endpoint(port)])) as session:
        daemon = daemon_publisher(session)
        process = listen(port, "--json", "--no-yaw", "--timeout", "30")
        try:
            reader = LineReader(process)
            # Until the subscription has propagated: the daemon's first alert (history gives
            # it once the subscriber is there).
            probe = alert_message(0, VEHICLE).to_json_bytes()
            daemon.put(probe)
            line = reader.next(20.0)
            assert line is not None and json.loads(line)["payload"]["seq"] == 0
            hostile = [
                b"[" * 100_000,  # over the size limit: not even copied
                b"[" * 50_000,  # within it: nested too deeply
                b"x" * 10_000_000,
                b"\xff\xfe\x00",
                alert_message(1, "car-2").to_json_bytes(),  # another vehicle's id on our key
                b'{"schema": "roadgaze.alert/1", "vehicle_id": "car-1\\ud800"}',
                probe,  # a duplicate of seq 0
            ]
            block = zenoh.CongestionControl.BLOCK  # the default (DROP) may lose some under load
            for payload in hostile:
                attacker.put(ALERT_KEY, payload, congestion_control=block)
            daemon.put(probe)  # a duplicate of seq 0 from the daemon's own publisher
            state = valid_state(source="cam\ud800\x1b[2J", problems=["\udfff"])
            attacker.put(STATE_KEY, state, congestion_control=block)
            daemon.put(alert_message(1, VEHICLE).to_json_bytes())
            received = [json.loads(reader.next(10.0) or "null") for _ in range(2)]
            stderr = stop_cleanly(process)
        finally:
            stop_process(process)
    by_type = {record["type"]: record["payload"] for record in received}  # keys are not ordered
    assert sorted(by_type) == ["alert", "state"]
    assert by_type["state"]["source"] == "cam\ud800\x1b[2J"  # escaped by json.dumps
    assert by_type["alert"]["seq"] == 1
    assert "message rejected" in stderr and "limit 65536" in stderr
    # The plain put of a valid alert (the duplicate in `hostile`) is another publisher's.
    assert stderr.count("SUSPICIOUS alert #0") == 1
    assert "totals: 2 alerts printed, 0 missed, 7 messages rejected, 1 foreign" in stderr


def test_vss_values_from_the_bus_are_checked_before_they_are_printed() -> None:
    port = free_port()
    eyes_key = "Vehicle/Driver/IsEyesOnRoad"
    with router(port) as attacker:
        process = listen(port, "--vss", "--json", "--no-yaw", "--timeout", "30")
        try:
            reader = LineReader(process)
            for _ in range(100):  # until the subscription has propagated
                attacker.put(eyes_key, b"false")
                line = reader.next(0.2)
                if line is not None:
                    break
            assert line is not None
            block = zenoh.CongestionControl.BLOCK
            hostile = [
                ("Vehicle/Driver/IsEyesOnRoad", b"yes"),
                ("Vehicle/Driver/FatigueLevel", b"250.0"),  # outside 0-100 %
                ("Vehicle/Driver/FatigueLevel", b"nan"),
                ("Vehicle/Driver/DistractionLevel", b"1e308"),
                ("Vehicle/Occupant/Row1/DriverSide/HeadPosition/Yaw", b"\xff\xfe"),
                ("Vehicle/Cabin/Note", b"x" * 10_000),  # over the size limit: not even copied
                ("Vehicle/Cabin/Note", b"\x1b[2J"),  # a terminal escape
            ]
            for key, payload in hostile:
                attacker.put(key, payload, congestion_control=block)
            attacker.put("Vehicle/Driver/FatigueLevel", b"60.0", congestion_control=block)
            attacker.put("Vehicle/Speed", b"57.5", congestion_control=block)  # another provider's
            received = [json.loads(reader.next(10.0) or "null") for _ in range(2)]
            stderr = stop_cleanly(process)
        finally:
            stop_process(process)
    assert json.loads(line) == {"type": "vss", "key": eyes_key, "value": "false"}
    assert sorted((r["key"], r["value"]) for r in received) == [
        ("Vehicle/Driver/FatigueLevel", "60.0"),
        ("Vehicle/Speed", "57.5"),
    ]
    assert "message rejected" in stderr and "must be true or false" in stderr


def test_pretty_printing_survives_lone_surrogates() -> None:
    port = free_port()
    with router(port) as attacker:
        process = listen(port, "--no-yaw", "--count", "1", "--timeout", "30")
        try:
            payload = valid_state(problems=["\ud800 lost"], source="\udfff")
            assert wait_for(
                lambda: attacker.put(STATE_KEY, payload) or process.poll() is not None, 20.0, 0.2
            )
            stdout, stderr = process.communicate(timeout=20)
        finally:
            stop_process(process)
    assert process.returncode == 0, stderr[-2000:]
    assert "state  car-1 status=running" in stdout and "\\ud800" in stdout


def query_state(port: int, timeout_s: float) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "roadgaze", "listen", "--query-state", "--vehicle-id", VEHICLE,
         "--zenoh-connect", endpoint(port), "--timeout", str(timeout_s)],
        capture_output=True, text=True, timeout=60, env=child_env(), check=False,
    )  # fmt: skip


def test_query_state_rejects_a_hostile_answer_and_flags_a_second_answerer() -> None:
    port = free_port()
    with router(port) as attacker:
        deep = attacker.declare_queryable(
            STATE_KEY, lambda query: query.reply(STATE_KEY, b"[" * 60_000)
        )
        result = query_state(port, 3)
        assert result.returncode == 1 and "Traceback" not in result.stderr, result.stderr
        assert "rejected" in result.stderr and "no answer" in result.stderr
        valid = attacker.declare_queryable(
            STATE_KEY, lambda query: query.reply(STATE_KEY, valid_state())
        )
        result = query_state(port, 5)
        valid.undeclare()
        deep.undeclare()
        # A hostile answer beside the daemon's: the health check is not to be trusted.
        assert result.returncode == 3 and "Traceback" not in result.stderr, result.stderr
        assert "answer(s) rejected beside" in result.stderr and "status=running" in result.stdout
        answers = [
            attacker.declare_queryable(STATE_KEY, lambda q: q.reply(STATE_KEY, valid_state()))
            for _ in range(2)
        ]
        result = query_state(port, 5)
        for answer in answers:
            answer.undeclare()
    assert result.returncode == 3, result.stderr
    assert "suspicious" in result.stderr and result.stdout.count("status=running") == 2


def test_timeout_says_whether_nothing_was_connected_or_nothing_received() -> None:
    port = free_port()
    started = time.monotonic()
    alone = subprocess.run(
        [sys.executable, "-m", "roadgaze", "listen", "--zenoh-connect", endpoint(port),
         "--timeout", "1.5"],
        capture_output=True, text=True, timeout=60, env=child_env(), check=False,
    )  # fmt: skip
    assert alone.returncode == 1
    assert "connected to nothing" in alone.stderr and endpoint(port) in alone.stderr
    assert time.monotonic() - started < 30.0
    with router(port):
        quiet = subprocess.run(
            [sys.executable, "-m", "roadgaze", "listen", "--zenoh-connect", endpoint(port),
             "--timeout", "1.5"],
            capture_output=True, text=True, timeout=60, env=child_env(), check=False,
        )  # fmt: skip
    assert quiet.returncode == 1
    assert "received nothing" in quiet.stderr and "connected to router" in quiet.stderr


@pytest.mark.parametrize("number", [signal.SIGTERM, signal.SIGHUP])  # SIGINT: test_daemon
def test_listen_stopped_by_a_signal_exits_0(number: int) -> None:
    port = free_port()
    with router(port):
        process = listen(port)
        try:
            LineReader(process, process.stderr).until("connected to router", 30.0)
            process.send_signal(number)
            code = process.wait(timeout=20)
        finally:
            stop_process(process)
    assert code == 0
