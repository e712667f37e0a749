"""Steps of the loop in their own threads: order, bounds, errors and stopping (`roadgaze.handoff`,
`roadgaze.capture.ReadAhead`)."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import pytest

from fakes import ListSource
from roadgaze.capture import ReadAhead
from roadgaze.errors import SourceError
from roadgaze.handoff import Handoff


def counting(produced: list[int], count: int) -> Iterator[int]:
    for value in range(count):
        produced.append(value)
        yield value


def test_items_arrive_in_order_from_another_thread() -> None:
    names: list[str] = []

    def items() -> Iterator[int]:
        names.append(threading.current_thread().name)
        yield from range(50)

    with Handoff(items(), "worker", depth=2) as handoff:
        assert list(handoff) == list(range(50))
        assert handoff.finished
    assert names == ["worker"]


@pytest.mark.parametrize("depth", [1, 2, 3])
def test_the_producer_runs_at_most_depth_plus_one_items_ahead(depth: int) -> None:
    produced: list[int] = []
    with Handoff(counting(produced, 100), "worker", depth=depth) as handoff:
        iterator = iter(handoff)
        assert next(iterator) == 0
        time.sleep(0.3)  # ample time for the producer to run ahead as far as it may
        # item 0 consumed, `depth` items queued, one more produced and waiting for room
        assert len(produced) == 1 + depth + 1


def test_an_error_is_raised_to_the_consumer_after_the_items_before_it() -> None:
    def failing() -> Iterator[int]:
        yield 1
        yield 2
        raise SourceError("video ended badly")

    received = []
    with Handoff(failing(), "worker") as handoff, pytest.raises(SourceError, match="badly"):
        for item in handoff:
            received.append(item)
    assert received == [1, 2]
    assert not handoff.finished


def test_close_stops_a_producer_waiting_for_room() -> None:
    produced: list[int] = []
    handoff = Handoff(counting(produced, 10_000), "worker", depth=1)
    iterator = iter(handoff)
    next(iterator)
    handoff.close()
    assert not handoff._thread.is_alive()
    assert len(produced) < 10


def test_bad_depth_and_second_iteration_are_refused() -> None:
    with pytest.raises(ValueError, match="at least 1"):
        Handoff(iter(()), "worker", depth=0)
    handoff = Handoff(iter(()), "worker")
    assert list(handoff) == []
    with pytest.raises(RuntimeError, match="only once"):
        list(handoff)


def test_read_ahead_delivers_every_frame_and_reports_the_wrapped_status() -> None:
    source = ListSource(40)
    with ReadAhead(source) as ahead:
        assert ahead.info == source.info
        frames = list(ahead)
        assert [frame.index for frame in frames] == list(range(40))
        assert ahead.status.frames_delivered == 40 and ahead.status.ended


def test_read_ahead_counts_only_frames_handed_out() -> None:
    with ReadAhead(ListSource(40), depth=2) as ahead:
        iterator = iter(ahead)
        next(iterator)
        next(iterator)
        time.sleep(0.2)
        status = ahead.status
    assert status.frames_delivered == 2 and not status.ended


class ClosingSource(ListSource):
    closed = False

    def close(self) -> None:
        self.closed = True


@pytest.mark.parametrize("close_source", [True, False])
def test_read_ahead_closes_the_wrapped_source_only_when_asked(close_source: bool) -> None:
    source = ClosingSource(5)
    with ReadAhead(source, close_source=close_source) as ahead:
        list(ahead)
    assert source.closed is close_source
