"""Progress bars draw on a terminal only: stderr redirected to a file gets no carriage-return
frames (a log full of them was the first thing a user met with `2> log`)."""

from __future__ import annotations

import io

import pytest

from roadgaze.outputs.progress import terminal_bar


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.mark.parametrize(
    ("stream", "enabled", "drawn"),
    [
        (io.StringIO(), True, False),  # a file or a pipe
        (Terminal(), True, True),
        (Terminal(), False, False),  # --no-progress
    ],
)
def test_a_bar_draws_only_on_a_terminal_and_when_enabled(
    monkeypatch: pytest.MonkeyPatch, stream: io.StringIO, enabled: bool, drawn: bool
) -> None:
    monkeypatch.setattr("sys.stderr", stream)
    bar = terminal_bar(3, "replay", "frame", enabled)
    for _ in range(3):
        bar.update(1)
    bar.close()
    assert ("\r" in stream.getvalue()) is drawn
