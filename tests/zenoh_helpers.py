"""Zenoh test hygiene: loopback endpoints, multicast off, free ports, bounded waits."""

from __future__ import annotations

import json
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import IO, Any

import zenoh
from zenoh.ext import HistoryConfig, RecoveryConfig, declare_advanced_subscriber


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def endpoint(port: int) -> str:
    return f"tcp/127.0.0.1:{port}"


def session_config(mode: str, listen: list[str], connect: list[str]) -> zenoh.Config:
    settings: dict[str, Any] = {
        "mode": mode,
        "listen": {"endpoints": listen},
        "connect": {"endpoints": connect},
        "scouting": {"multicast": {"enabled": False}},
    }
    return zenoh.Config.from_json5(json.dumps(settings))


@contextmanager
def router(port: int) -> Iterator[zenoh.Session]:
    """A Python session in router mode standing in for zenohd."""
    session = zenoh.open(session_config("router", [endpoint(port)], []))
    try:
        yield session
    finally:
        session.close()


@contextmanager
def client(port: int) -> Iterator[zenoh.Session]:
    session = zenoh.open(session_config("client", [], [endpoint(port)]))
    try:
        yield session
    finally:
        session.close()


def wait_for(predicate: Callable[[], bool], timeout_s: float = 10.0, every_s: float = 0.05) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(every_s)
    return predicate()


def wait_for_subscribers(link: Any, names: tuple[str, ...], timeout_s: float = 10.0) -> bool:
    """Wait until a subscriber reaches each of the link's publishers `names` (`support`, `vss`:
    all of its keys; Zenoh's matching status). A router's subscriber reaches them a little after
    the link is up, and a put before that is not routed."""
    declared = link._declared
    if declared is None:
        return False
    publishers = []
    for name in names:
        entity = getattr(declared, name)
        publishers += list(entity.values()) if isinstance(entity, dict) else [entity]
    return wait_for(lambda: all(p.matching_status.matching for p in publishers), timeout_s)


class LineReader:
    """Reads a subprocess's stdout lines into a queue on a thread (never blocks the test)."""

    def __init__(self, process: subprocess.Popen[str], stream: IO[str] | None = None) -> None:
        self.lines: queue.Queue[str] = queue.Queue()
        stream = stream if stream is not None else process.stdout
        assert stream is not None
        self._thread = threading.Thread(target=self._pump, args=(stream,), daemon=True)
        self._thread.start()

    def _pump(self, stream: IO[str]) -> None:
        for line in stream:
            self.lines.put(line.rstrip("\n"))

    def next(self, timeout_s: float) -> str | None:
        try:
            return self.lines.get(timeout=timeout_s)
        except queue.Empty:
            return None

    def rest(self, timeout_s: float = 30.0) -> list[str]:
        """The lines still to come up to the end of the stream (the process has ended, or is
        ending): waits for the stream to close, not for a quiet spell; at most `timeout_s`."""
        self._thread.join(timeout_s)
        lines: list[str] = []
        while (line := self.next(0.0)) is not None:
            lines.append(line)
        return lines

    def until(self, text: str, timeout_s: float) -> list[str]:
        """The lines read up to and including the first containing `text`; AssertionError when
        none comes within `timeout_s`."""
        deadline = time.monotonic() + timeout_s
        lines: list[str] = []
        while not lines or text not in lines[-1]:
            line = self.next(max(0.0, deadline - time.monotonic()))
            assert line is not None, f"no line with {text!r} in {timeout_s} s; got {lines[-5:]}"
            lines.append(line)
        return lines


def stop_process(process: subprocess.Popen[str], timeout_s: float = 10.0) -> None:
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=timeout_s)


FAST_RETRY = {"period_init_ms": 250, "period_max_ms": 1000, "period_increase_factor": 2}
"""What roadgaze uses (zenoh.reconnect_*): a restarted router is seen within about 1 s."""


def client_config(connect: list[str], **extra: Any) -> zenoh.Config:
    """A client of `connect` that reconnects quickly (a consumer as docs/zenoh.md shows it)."""
    settings: dict[str, Any] = {
        "mode": "client",
        "connect": {"endpoints": connect, "retry": FAST_RETRY},
        "scouting": {"multicast": {"enabled": False}},
    }
    settings.update(extra)
    return zenoh.Config.from_json5(json.dumps(settings))


class RouterProcess:
    """A Python session in router mode in a child process, so it can be killed with SIGKILL.

    `config_file` (a Zenoh JSON5 file, e.g. from `roadgaze security init`) replaces the plain
    loopback router configuration.
    """

    def __init__(self, port: int, config_file: str | None = None) -> None:
        self.port = port
        self.config_file = config_file
        self.process: subprocess.Popen[str] | None = None

    def start(self, timeout_s: float = 20.0) -> float:
        """Start and wait until it listens; returns the monotonic time it was ready (after
        `spawned_at`, the time the process was started)."""
        self.spawned_at = time.monotonic()
        command = [sys.executable, __file__, endpoint(self.port)]
        if self.config_file is not None:
            command.append(self.config_file)
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
        reader = LineReader(self.process)
        line = reader.next(timeout_s)
        if line is None or not line.startswith("ready"):
            self.stop()
            raise RuntimeError(f"router did not start: {line!r}")
        return time.monotonic()

    def kill(self) -> float:
        """SIGKILL (no goodbye on its links); returns the monotonic time it was gone."""
        assert self.process is not None
        self.process.send_signal(signal.SIGKILL)
        self.process.wait(timeout=10)
        return time.monotonic()

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.kill()
            self.process.wait(timeout=10)

    def __enter__(self) -> RouterProcess:
        self.start()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.stop()


def _serve_router(listen: str, config_file: str | None) -> None:
    if config_file is not None:
        conf = zenoh.Config.from_file(config_file)
    else:
        conf = session_config("router", [listen], [])
    session = zenoh.open(conf)
    print("ready", session.info.zid(), flush=True)
    try:
        while True:
            time.sleep(3600)
    finally:
        session.close()


class AdvancedListener:
    """An advanced subscriber with history and recovery; records (arrival time, alert)."""

    def __init__(self, session: zenoh.Session, key: str, history: int = 100) -> None:
        self._lock = threading.Lock()
        self.alerts: list[tuple[float, dict[str, Any]]] = []
        self.misses: list[int] = []
        self.subscriber = declare_advanced_subscriber(
            session,
            key,
            self._on_sample,
            history=HistoryConfig(detect_late_publishers=True, max_samples=history),
            recovery=RecoveryConfig(heartbeat=True),  # type: ignore[call-arg]
        )
        self.miss_listener = self.subscriber.sample_miss_listener(
            lambda miss: self.misses.append(miss.nb)
        )

    def _on_sample(self, sample: zenoh.Sample) -> None:
        alert = json.loads(sample.payload.to_bytes())
        with self._lock:
            self.alerts.append((time.monotonic(), alert))

    def seqs(self) -> list[int]:
        with self._lock:
            return [alert["seq"] for _, alert in self.alerts]

    def kinds(self) -> list[str]:
        with self._lock:
            return [f"{alert['kind']}:{alert['level']}" for _, alert in self.alerts]

    def close(self) -> None:
        self.miss_listener.undeclare()
        self.subscriber.undeclare()


def advanced_publisher(session: zenoh.Session, key: str) -> Any:
    """An advanced publisher on `key` as the daemon declares its alert publisher (a cache,
    sample-miss detection, publisher detection): a second publisher of a vehicle's alerts."""
    from zenoh.ext import CacheConfig, MissDetectionConfig, declare_advanced_publisher

    return declare_advanced_publisher(
        session,
        key,
        cache=CacheConfig(max_samples=10),
        sample_miss_detection=MissDetectionConfig(heartbeat=0.5),  # type: ignore[call-arg]
        publisher_detection=True,
    )


if __name__ == "__main__":
    _serve_router(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else None)
