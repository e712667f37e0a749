"""Zenoh's native log in `roadgaze router`: on stderr through roadgaze's log, without colour
codes, throttled, and saying what happened (a plain client knocking on a TLS port), where Zenoh
itself wrote to stdout, four lines a second, with the hint to raise the open-file limit."""

from __future__ import annotations

import logging
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

from repo_paths import child_env
from roadgaze.transport.zenoh_log import parse_zenoh_line
from zenoh_helpers import LineReader, free_port, stop_process

SEEN = (
    "\x1b[2m2026-12-06T22:05:05.646417Z\x1b[0m \x1b[33m WARN\x1b[0m acc-0 ThreadId(05) "
    "\x1b[2mzenoh_link_tls::unicast\x1b[0m\x1b[2m:\x1b[0m received corrupt message of type "
    "InvalidContentType. Hint: increase the system open file limit.\n"
)
"""A line Zenoh 1.10 wrote to stdout for a plain TCP client on a TLS endpoint."""


def test_a_plain_client_on_a_tls_port_is_named_as_such() -> None:
    line = parse_zenoh_line(SEEN)
    assert line is not None and line.level == logging.WARNING
    assert line.target == "zenoh_link_tls::unicast" and line.kind == "plain client on TLS"
    assert "did not speak TLS" in line.message and "open file limit" not in line.message
    other = parse_zenoh_line("2026-12-06T22:05:05Z ERROR zenoh::net: \x1b[1mboom\x1b[0m")
    assert other is not None and other.level == logging.ERROR and other.message == "boom"
    assert parse_zenoh_line("\x1b[0m  \n") is None


def test_the_router_tells_plain_clients_once_on_stderr_and_writes_nothing_to_stdout(
    tmp_path: Path,
) -> None:
    port = free_port()
    listen = f"tls/127.0.0.1:{port}"
    made = subprocess.run(
        [sys.executable, "-m", "roadgaze", "security", "init", str(tmp_path / "bundle"),
         "--vehicle-id", "car-0", "--endpoint", listen, "--listen", listen],
        capture_output=True, text=True, timeout=120, env=child_env(), check=False,
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    router = subprocess.Popen(
        [sys.executable, "-m", "roadgaze", "router", "--zenoh-config",
         str(tmp_path / "bundle" / "router" / "zenoh.json5")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
    )  # fmt: skip
    try:
        reader = LineReader(router, router.stderr)
        reader.until("listening on", 60.0)
        for _ in range(8):
            with socket.create_connection(("127.0.0.1", port), timeout=5.0) as knock:
                knock.sendall(b"GET / HTTP/1.0\r\n\r\n")
            time.sleep(0.1)
        told = reader.until("did not speak TLS", 30.0)
        router.send_signal(signal.SIGTERM)
        out, _ = router.communicate(timeout=30)
        rest = reader.rest()
    finally:
        stop_process(router)
    assert out == ""
    everything = "\n".join(told + rest)
    assert everything.count("did not speak TLS") == 1  # throttled: 8 knocks, one line
    assert "\x1b[" not in everything and "open file limit" not in everything
