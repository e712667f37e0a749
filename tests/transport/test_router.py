"""`roadgaze router`: relays between real Zenoh sessions, stops cleanly on signals, refuses bad
input in one line, and honours a full router configuration file (mutual TLS)."""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
import zenoh

from repo_paths import child_env
from roadgaze.errors import TransportError
from roadgaze.transport import DEFAULT_LISTEN, Router, RouterSettings, router_config
from zenoh_helpers import LineReader, endpoint, free_port, session_config, stop_process, wait_for

ENV = child_env()


@contextmanager
def router_process(*args: str) -> Iterator[tuple[subprocess.Popen[str], LineReader]]:
    """`roadgaze router ARGS` in a child process, always stopped at the end."""
    process = subprocess.Popen(
        [sys.executable, "-m", "roadgaze", "router", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
    )
    try:
        yield process, LineReader(process, process.stderr)
    finally:
        stop_process(process)


def lines_until(reader: LineReader, text: str, timeout_s: float = 30.0) -> list[str]:
    """Lines read until one containing `text` (included); fails after `timeout_s`."""
    seen: list[str] = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = reader.next(0.2)
        if line is not None:
            seen.append(line)
            if text in line:
                return seen
    raise AssertionError(f"no line with {text!r} within {timeout_s} s; read {seen}")


def relay_once(connect: zenoh.Config, other: zenoh.Config, key: str = "rg/test/a") -> list[str]:
    """A subscriber on one session, a put on the other: what the subscriber got."""
    received: list[str] = []
    with zenoh.open(connect) as subscriber_session, zenoh.open(other) as publisher_session:
        subscriber = subscriber_session.declare_subscriber(
            "rg/test/**", lambda sample: received.append(sample.payload.to_string())
        )
        publisher = publisher_session.declare_publisher(key)
        assert wait_for(lambda: publisher.matching_status.matching, timeout_s=10.0)
        publisher.put("hello through the router")
        wait_for(lambda: len(received) >= 1, timeout_s=10.0)
        subscriber.undeclare()
    return received


def test_router_relays_between_a_publisher_and_a_subscriber_and_logs_the_sessions() -> None:
    port = free_port()
    with router_process("--listen", endpoint(port), "--log-json") as (process, reader):
        started = lines_until(reader, "listening on")
        client = session_config("client", [], [endpoint(port)])
        received = relay_once(client, client)
        assert received == ["hello through the router"]
        log = [json.loads(line) for line in lines_until(reader, "(0 open)", timeout_s=10.0)]
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=10) == 0
    listening = json.loads(started[-1])
    assert listening["listen"] == [endpoint(port)]
    assert "multicast scouting off" in listening["message"]
    opened = [entry["message"] for entry in log if "session opened" in entry["message"]]
    closed = [entry["message"] for entry in log if "session closed" in entry["message"]]
    assert len(opened) == 2 and len(closed) == 2
    assert all("client" in text and "from tcp/127.0.0.1:" in text for text in opened)
    assert opened[1].endswith("(2 open)")


@pytest.mark.parametrize("stop_signal", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP])
def test_router_stops_cleanly_with_exit_0_on_a_signal(stop_signal: signal.Signals) -> None:
    port = free_port()
    with router_process("--listen", endpoint(port)) as (process, reader):
        lines_until(reader, "listening on")
        with zenoh.open(session_config("client", [], [endpoint(port)])):
            lines_until(reader, "session opened", timeout_s=10.0)
            process.send_signal(stop_signal)
            assert process.wait(timeout=10) == 0
        rest = lines_until(reader, "router stopped", timeout_s=5.0)
    assert any(f"{stop_signal.name} received: stopping the router" in line for line in rest)
    assert not any("Traceback" in line for line in rest)


def test_router_peer_in_the_middle_relays_a_peer_and_a_client() -> None:
    """Daemons run in peer mode by default: a peer connecting to the router reaches clients."""
    port = free_port()
    with router_process("--listen", endpoint(port)) as (_, reader):
        lines_until(reader, "listening on")
        peer = session_config("peer", ["tcp/127.0.0.1:0"], [endpoint(port)])
        client = session_config("client", [], [endpoint(port)])
        assert relay_once(client, peer) == ["hello through the router"]


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


BAD_INPUT: list[tuple[str, Any, str]] = [
    ("unknown protocol", lambda tmp, port: ["--listen", "bogus/127.0.0.1:1"], "not supported"),
    ("unknown host", lambda tmp, port: ["--listen", "tcp/300.1.1.1:7447"], "cannot start"),
    (
        "port in use",
        lambda tmp, port: ["--listen", endpoint(port)],
        "Address already in use",
    ),
    (
        "missing file",
        lambda tmp, port: ["--zenoh-config", str(tmp / "none.json5")],
        "not found",
    ),
    (
        "file for a peer",
        lambda tmp, port: ["--zenoh-config", str(_write(tmp / "peer.json5", '{mode: "peer"}'))],
        "is for mode peer",
    ),
    (
        "unknown key",
        lambda tmp, port: ["--zenoh-config", str(_write(tmp / "bad.json5", "{bogus: 1}"))],
        "unknown field `bogus`",
    ),
    (
        "not a config file",
        lambda tmp, port: ["--zenoh-config", str(_write(tmp / "router.txt", "{}"))],
        "Unsupported file type",
    ),
]


@pytest.mark.parametrize(
    ("case", "arguments", "expected"), BAD_INPUT, ids=[c[0] for c in BAD_INPUT]
)
def test_router_bad_input_is_one_line_and_exit_2(
    case: str, arguments: Any, expected: str, tmp_path: Path
) -> None:
    import socket

    with socket.socket() as holder:
        holder.bind(("127.0.0.1", 0))
        holder.listen()
        busy_port = holder.getsockname()[1]
        result = subprocess.run(
            [sys.executable, "-m", "roadgaze", "router", *arguments(tmp_path, busy_port)],
            capture_output=True,
            text=True,
            env=ENV,
            timeout=60,
            check=False,
        )
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith("roadgaze router: error: ") and expected in lines[0]


# --- the configuration, in process ------------------------------------------------------------


def _listen_of(config: Any) -> Any:
    return json.loads(config.zenoh_config.get_json("listen/endpoints"))


def test_router_defaults_are_loopback_and_no_multicast_scouting() -> None:
    config = router_config(RouterSettings())
    assert config.listen == DEFAULT_LISTEN == ("tcp/127.0.0.1:7447",)
    assert _listen_of(config) == ["tcp/127.0.0.1:7447"]
    assert json.loads(config.zenoh_config.get_json("mode")) == "router"
    assert config.multicast_scouting is False
    assert json.loads(config.zenoh_config.get_json("scouting/multicast/enabled")) is False


def test_router_file_endpoints_apply_and_the_flags_replace_them(tmp_path: Path) -> None:
    file = _write(
        tmp_path / "router.json5",
        '{mode: "router", listen: {endpoints: ["tcp/127.0.0.1:7001"]}, '
        "scouting: {multicast: {enabled: true}}}",
    )
    from_file = router_config(RouterSettings(config_file=file))
    assert from_file.listen == ("tcp/127.0.0.1:7001",) and from_file.multicast_scouting is True
    overridden = router_config(RouterSettings(listen=("tcp/127.0.0.1:7002",), config_file=file))
    assert overridden.listen == ("tcp/127.0.0.1:7002",)
    assert _listen_of(overridden) == ["tcp/127.0.0.1:7002"]
    per_mode = _write(
        tmp_path / "modes.json5",
        '{listen: {endpoints: {router: ["tcp/127.0.0.1:7003"], peer: ["tcp/127.0.0.1:0"]}}}',
    )
    assert router_config(RouterSettings(config_file=per_mode)).listen == ("tcp/127.0.0.1:7003",)


def test_router_file_without_endpoints_listens_on_loopback_not_every_interface(
    tmp_path: Path,
) -> None:
    file = _write(tmp_path / "router.json5", "{transport: {unicast: {max_sessions: 16}}}")
    config = router_config(RouterSettings(config_file=file))
    assert config.listen == DEFAULT_LISTEN
    assert json.loads(config.zenoh_config.get_json("transport/unicast/max_sessions")) == 16
    assert config.multicast_scouting is False


def test_router_in_process_counts_sessions_and_refuses_a_used_port() -> None:
    port = free_port()
    with Router(RouterSettings(listen=(endpoint(port),))) as router:
        with zenoh.open(session_config("client", [], [endpoint(port)])):
            assert wait_for(lambda: router.open_sessions == 1, timeout_s=10.0)
        assert wait_for(lambda: router.open_sessions == 0, timeout_s=10.0)
        with (
            pytest.raises(TransportError, match="cannot start the router"),
            Router(RouterSettings(listen=(endpoint(port),))),
        ):
            pass
    assert router.sessions_opened == 1


# --- a full router configuration: mutual TLS --------------------------------------------------


def _openssl(*args: str) -> None:
    subprocess.run(["openssl", *args], check=True, capture_output=True, timeout=60)


@pytest.fixture(scope="module")
def certificates(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A CA, a router certificate for localhost/127.0.0.1 and a client certificate (openssl)."""
    if shutil.which("openssl") is None:
        pytest.skip("openssl is not installed")
    folder = tmp_path_factory.mktemp("tls")
    ec = ("-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes")
    _openssl(
        "req", "-x509", *ec, "-keyout", str(folder / "ca.key"), "-out", str(folder / "ca.pem"),
        "-days", "2", "-subj", "/CN=roadgaze-test-ca",
        "-addext", "basicConstraints=critical,CA:TRUE",
        "-addext", "keyUsage=critical,keyCertSign,cRLSign",
    )  # fmt: skip
    for name in ("router", "client"):
        extensions = _write(
            folder / f"{name}.ext",
            "subjectAltName=DNS:localhost,IP:127.0.0.1\nbasicConstraints=CA:FALSE\n"
            "extendedKeyUsage=serverAuth,clientAuth\n",
        )
        _openssl(
            "req", *ec, "-keyout", str(folder / f"{name}.key"), "-out", str(folder / f"{name}.csr"),
            "-subj", f"/CN={name}",
        )  # fmt: skip
        _openssl(
            "x509", "-req", "-in", str(folder / f"{name}.csr"), "-CA", str(folder / "ca.pem"),
            "-CAkey", str(folder / "ca.key"), "-CAcreateserial", "-days", "2",
            "-out", str(folder / f"{name}.pem"), "-extfile", str(extensions),
        )  # fmt: skip
    return folder


def _tls_client(folder: Path, port: int, with_certificate: bool) -> zenoh.Config:
    tls: dict[str, Any] = {"root_ca_certificate": str(folder / "ca.pem")}
    if with_certificate:
        tls |= {
            "connect_certificate": str(folder / "client.pem"),
            "connect_private_key": str(folder / "client.key"),
            "enable_mtls": True,
        }
    settings = {
        "mode": "client",
        "connect": {"endpoints": [f"tls/localhost:{port}"], "timeout_ms": 2000},
        "scouting": {"multicast": {"enabled": False}},
        "transport": {"link": {"tls": tls}},
    }
    return zenoh.Config.from_json5(json.dumps(settings))


def test_router_runs_a_mutual_tls_configuration_file(certificates: Path, tmp_path: Path) -> None:
    port = free_port()
    router_file = _write(
        tmp_path / "router.json5",
        json.dumps(
            {
                "mode": "router",
                "listen": {"endpoints": [f"tls/127.0.0.1:{port}"]},
                "transport": {
                    "link": {
                        "tls": {
                            "root_ca_certificate": str(certificates / "ca.pem"),
                            "listen_certificate": str(certificates / "router.pem"),
                            "listen_private_key": str(certificates / "router.key"),
                            "enable_mtls": True,
                        }
                    }
                },
            }
        ),
    )
    with router_process("--zenoh-config", str(router_file)) as (process, reader):
        started = lines_until(reader, "listening on")
        client = _tls_client(certificates, port, with_certificate=True)
        assert relay_once(client, client) == ["hello through the router"]
        with pytest.raises(zenoh.ZError):
            zenoh.open(_tls_client(certificates, port, with_certificate=False))
        opened = lines_until(reader, "session opened")
        # Refused handshakes open no transport: Zenoh's own TLS log names them, relayed from
        # Zenoh's writer (stdout) to stderr through roadgaze's log.
        refused = lines_until(reader, "peer sent no certificates")
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=10) == 0
    assert f"listening on tls/127.0.0.1:{port}" in started[-1]
    assert "from tls/127.0.0.1:" in opened[-1] and "as client" in opened[-1]
    assert "roadgaze.zenoh: zenoh zenoh_link_tls" in refused[-1] and "\x1b[" not in refused[-1]


def test_router_runs_the_router_file_of_security_init(tmp_path: Path) -> None:
    """`roadgaze router --zenoh-config DIR/router/zenoh.json5`: only certified TLS sessions get
    in, each is logged by its certificate name, the daemon's alert reaches a consumer and another
    consumer's forged alert does not (the file's access control applies)."""
    from roadgaze.config import ZenohConfig
    from roadgaze.security import init_bundle
    from roadgaze.transport import Keys

    port = free_port()
    keys = Keys.from_config(ZenohConfig(), "car-1")
    bundle = init_bundle(tmp_path / "bundle", keys, ["fcw", "rogue"], f"tls/127.0.0.1:{port}")
    role = {name: zenoh.Config.from_file(str(path)) for name, path in bundle.items()}
    key = "vehicle/car-1/dms/alert"
    with router_process("--zenoh-config", str(bundle["router"])) as (process, reader):
        started = lines_until(reader, "listening on")
        with pytest.raises(zenoh.ZError):  # plain TCP on the TLS port: no session
            zenoh.open(session_config("client", [], [f"tcp/127.0.0.1:{port}"]))
        received: list[str] = []
        with (
            zenoh.open(role["consumer-fcw"]) as consumer,
            zenoh.open(role["consumer-rogue"]) as rogue,
            zenoh.open(role["daemon"]) as daemon,
        ):
            consumer.declare_subscriber(key, lambda s: received.append(s.payload.to_string()))
            publisher = daemon.declare_publisher(key)
            assert wait_for(lambda: publisher.matching_status.matching, timeout_s=15.0)
            rogue.put(key, "forged by another consumer")
            publisher.put("from the daemon")
            assert wait_for(lambda: "from the daemon" in received, timeout_s=10.0)
            time.sleep(0.5)  # the forged put, had it passed, would have arrived by now
            opened = lines_until(reader, "as daemon.car-1", timeout_s=10.0)
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=10) == 0
    assert f"listening on tls/127.0.0.1:{port}" in started[-1]
    assert received == ["from the daemon"]
    assert any("as consumer.fcw.car-1" in line for line in opened)
