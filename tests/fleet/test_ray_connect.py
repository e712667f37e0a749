"""The bounded, thread-kept Ray start and the token rule, without Ray."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from roadgaze.fleet.ray_connect import KeeperThread, use_ray_token


def test_the_keeper_thread_outlives_the_call_until_released() -> None:
    started: list[threading.Thread] = []
    keeper = KeeperThread(lambda: started.append(threading.current_thread()))
    keeper.start(time.monotonic() + 5.0)
    assert started and started[0].is_alive()  # processes tied to this thread would live on
    keeper.release()
    assert not started[0].is_alive()


def test_the_keeper_gives_up_at_the_deadline_and_reraises_failures() -> None:
    release = threading.Event()
    with pytest.raises(TimeoutError):
        KeeperThread(release.wait).start(time.monotonic() + 0.2)
    release.set()

    def fail() -> None:
        raise ConnectionError("nothing there")

    with pytest.raises(ConnectionError, match="nothing there"):
        KeeperThread(fail).start(time.monotonic() + 5.0)


@pytest.mark.parametrize(
    ("environ", "token_file", "expected"),
    [
        ({}, True, "token"),  # `ray start --head` wrote ~/.ray/auth_token
        ({"RAY_AUTH_TOKEN": "abc"}, False, "token"),
        ({"RAY_AUTH_TOKEN_PATH": "/run/ray-token"}, False, "token"),
        ({}, False, None),  # no token anywhere: nothing to send
        ({"RAY_AUTH_MODE": "disabled"}, True, "disabled"),  # the user's choice stands
    ],
)
def test_the_token_is_sent_when_one_is_at_hand_and_no_mode_is_set(
    tmp_path: Path, environ: dict[str, str], token_file: bool, expected: str | None
) -> None:
    if token_file:
        (tmp_path / ".ray").mkdir()
        (tmp_path / ".ray" / "auth_token").write_text("0" * 64)
    env = dict(environ)
    use_ray_token(env, tmp_path)
    assert env.get("RAY_AUTH_MODE") == expected
