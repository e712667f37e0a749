"""Zenoh test hygiene: loopback endpoints, multicast off, free ports, bounded waits."""

from __future__ import annotations

import json
import queue
import socket
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import IO, Any

import zenoh


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


def stop_process(process: subprocess.Popen[str], timeout_s: float = 10.0) -> None:
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=timeout_s)
