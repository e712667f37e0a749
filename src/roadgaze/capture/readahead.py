"""Decoding a file source in its own thread, a bounded number of frames ahead of the loop.

A video file decodes on the loop's thread unless something overlaps it; `ReadAhead` iterates the
wrapped source in a thread and hands frames over through a queue of `depth` frames, so decoding
frame n+1 runs while MediaPipe works on frame n (OpenCV releases the GIL while it decodes). Live
sources need none of this: a camera already grabs in its own thread into a one-frame slot.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace

from roadgaze.capture.base import FrameSource, SourceBase, SourceInfo, SourceStatus
from roadgaze.handoff import Handoff
from roadgaze.types import Frame

READ_AHEAD_FRAMES = 2
"""Frames decoded ahead of the loop: enough to hide decoding, few enough to keep latency and
memory flat."""


class ReadAhead(SourceBase):
    """`source` iterated in a decoding thread, at most `depth` frames ahead; a FrameSource.

    Frames, their order and `t_s` are the wrapped source's. `status` is the wrapped source's,
    except that `frames_delivered` counts the frames this wrapper handed out and `ended` turns
    true only once the loop has taken the last frame. An error in the wrapped source is raised
    to the loop at the point it happened. Closing stops the thread and, with `close_source`,
    closes the wrapped source.
    """

    def __init__(
        self, source: FrameSource, depth: int = READ_AHEAD_FRAMES, close_source: bool = True
    ) -> None:
        self._source = source
        self._close_source = close_source
        self._handoff: Handoff[Frame] = Handoff(iter(source), "roadgaze-decode", depth)
        self._delivered = 0

    @property
    def info(self) -> SourceInfo:
        return self._source.info

    @property
    def status(self) -> SourceStatus:
        return replace(
            self._source.status, frames_delivered=self._delivered, ended=self._handoff.finished
        )

    def __iter__(self) -> Iterator[Frame]:
        for frame in self._handoff:
            self._delivered += 1
            yield frame

    def close(self) -> None:
        self._handoff.close()
        if self._close_source:
            self._source.close()
