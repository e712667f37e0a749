"""Progress bars on stderr: the one way roadgaze draws them, and the pipeline sink."""

from __future__ import annotations

from typing import Any

from roadgaze.types import ClosesOnExit, Frame, FrameRecord, Sink


def terminal_bar(total: int | None, description: str, unit: str, enabled: bool = True) -> Any:
    """A tqdm bar on stderr, drawn only where stderr is a terminal: redirected to a file or a
    pipe it stays off (its carriage-return frames would fill the log), as with `enabled` False."""
    from tqdm import tqdm

    return tqdm(
        total=total,
        desc=description,
        unit=unit,
        dynamic_ncols=True,
        disable=None if enabled else True,  # None: tqdm's own "off unless a terminal"
    )


class ProgressBar(ClosesOnExit, Sink):
    """A progress bar (frames, fps, ETA) as a sink; see `terminal_bar`."""

    def __init__(self, total: int | None, description: str = "replay") -> None:
        self._bar = terminal_bar(total, description, "frame")

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self._bar.update(1)

    def close(self) -> None:
        self._bar.close()
