"""A progress bar on stderr as a pipeline sink."""

from __future__ import annotations

from roadgaze.types import ClosesOnExit, Frame, FrameRecord, Sink


class ProgressBar(ClosesOnExit, Sink):
    """A tqdm progress bar on stderr (frames, fps, ETA) as a sink."""

    def __init__(self, total: int | None, description: str = "replay") -> None:
        from tqdm import tqdm

        self._bar = tqdm(total=total, desc=description, unit="frame", dynamic_ncols=True)

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self._bar.update(1)

    def close(self) -> None:
        self._bar.close()
