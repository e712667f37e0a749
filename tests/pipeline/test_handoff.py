"""A step of the loop in its own thread: order, bounds, errors, stopping (`pipeline.handoff`)."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import pytest

from roadgaze.errors import SourceError
from roadgaze.pipeline.handoff import Handoff


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
