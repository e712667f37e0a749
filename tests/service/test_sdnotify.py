"""The notify protocol against a fake `$NOTIFY_SOCKET`: exact datagrams, abstract names, the
watchdog environment, and a socket that is gone (never an exception)."""

from __future__ import annotations

import logging
from collections.abc import Iterator
from pathlib import Path

import pytest

from fakes import FakeNotifySocket
from roadgaze.service.sdnotify import Notifier, socket_address
from zenoh_helpers import wait_for


@pytest.fixture(params=["path", "abstract"])
def notify_socket(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[FakeNotifySocket]:
    fake = FakeNotifySocket(tmp_path, abstract=request.param == "abstract")
    try:
        yield fake
    finally:
        fake.close()


def test_each_call_is_one_datagram_of_key_value_lines(notify_socket: FakeNotifySocket) -> None:
    notifier = Notifier.from_environment({"NOTIFY_SOCKET": notify_socket.address}, pid=1234)
    assert notifier.enabled and notifier.watchdog_s is None
    assert notifier.status("loading the model")
    assert notifier.ready("monitoring /dev/video0: first frame processed")
    assert notifier.watchdog()
    assert notifier.stopping("stopping (SIGTERM)\nafter 3 frames")
    assert wait_for(lambda: len(notify_socket.raw) == 4, timeout_s=5.0)
    notifier.close()
    assert notify_socket.raw == [
        b"STATUS=loading the model",
        b"READY=1\nSTATUS=monitoring /dev/video0: first frame processed",
        b"WATCHDOG=1",
        b"STOPPING=1\nSTATUS=stopping (SIGTERM) after 3 frames",  # a newline would start a field
    ]
    assert notifier.sent == 4


@pytest.mark.parametrize(
    ("environ", "watchdog_s"),
    [
        ({"WATCHDOG_USEC": "20000000"}, 20.0),
        ({"WATCHDOG_USEC": "20000000", "WATCHDOG_PID": "1234"}, 20.0),
        ({"WATCHDOG_USEC": "20000000", "WATCHDOG_PID": "999"}, None),  # for another process
        ({"WATCHDOG_USEC": "0"}, None),
        ({"WATCHDOG_USEC": "twenty"}, None),
        ({}, None),
    ],
)
def test_the_watchdog_period_comes_from_the_environment_for_this_process_only(
    environ: dict[str, str], watchdog_s: float | None
) -> None:
    notifier = Notifier.from_environment({"NOTIFY_SOCKET": "/run/x.sock", **environ}, pid=1234)
    assert notifier.watchdog_s == watchdog_s


def test_without_notify_socket_nothing_is_sent_and_no_watchdog_is_expected() -> None:
    notifier = Notifier.from_environment({"WATCHDOG_USEC": "1000000"}, pid=1)
    assert not notifier.enabled and notifier.watchdog_s is None
    assert notifier.ready("x") is False and notifier.watchdog() is False


@pytest.mark.parametrize(
    ("value", "address"),
    [
        ("/run/systemd/notify", "/run/systemd/notify"),
        ("@/org/freedesktop/systemd1/notify/123", "\0/org/freedesktop/systemd1/notify/123"),
        ("@", None),
        ("vsock:2:1234", None),
        ("relative.sock", None),
    ],
)
def test_socket_addresses(value: str, address: str | None) -> None:
    assert socket_address(value) == address


def test_a_socket_that_is_gone_is_logged_once_and_never_raises(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    notifier = Notifier(str(tmp_path / "gone.sock"), watchdog_usec=1_000_000)
    with caplog.at_level(logging.WARNING, logger="roadgaze.daemon"):
        assert notifier.ready("x") is False
        assert notifier.watchdog() is False
    warnings = [r.getMessage() for r in caplog.records if "cannot notify systemd" in r.getMessage()]
    assert len(warnings) == 1 and "No such file" in warnings[0]
    assert notifier.sent == 0


def test_a_vsock_notify_socket_disables_notification_with_a_warning(
    caplog: pytest.LogCaptureFixture,
) -> None:
    with caplog.at_level(logging.WARNING, logger="roadgaze.daemon"):
        notifier = Notifier("vsock:2:1234", watchdog_usec=1_000_000)
    assert not notifier.enabled and notifier.watchdog_s is None
    assert "not a unix socket path" in caplog.text
