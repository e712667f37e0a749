"""`roadgaze listen --query-state`: ask the state queryable once, as a health check."""

from __future__ import annotations

import sys
from typing import Any


def _say(text: str) -> None:
    print(f"roadgaze listen: {text}", file=sys.stderr, flush=True)


def query_state(printer: Any, timeout_s: float) -> int:
    """Ask every state queryable of the printer's consumer (no consolidation: a second answerer
    is seen), print the answers and return the exit status: 0 all running, 3 degraded or
    suspicious, 1 no answer."""
    from roadgaze.transport import printable
    from roadgaze.transport.state_query import query_states

    consumer = printer.consumer
    answers, rejected = query_states(consumer.session, consumer.keys, consumer.checker, timeout_s)
    while (event := consumer.next_event(0.0)) is not None:  # the link, as `follow` logs it
        printer.handle(event)
    statuses: dict[str, list[str]] = {}
    for key, why in rejected:
        _say(f"state answer on {printable(key, 80)} rejected: {printable(why)}")
    for checked in answers:
        statuses.setdefault(checked.vehicle_id, []).append(str(checked.payload["status"]))
        printer.show("state", checked.key, checked.vehicle_id, checked.payload)
    if not answers:
        _say(f"no answer from {consumer.keys.state}")
        return 1
    twice = {vehicle: n for vehicle, found in statuses.items() if (n := len(found)) > 1}
    if twice:
        _say(
            f"suspicious: several answers for one vehicle {twice}: another process answers "
            "on its state key (see docs/security.md)"
        )
        return 3
    if rejected:
        _say(
            f"suspicious: {len(rejected)} answer(s) rejected beside the valid one: another "
            "process answers on the state key (see docs/security.md)"
        )
        return 3
    every = [status for found in statuses.values() for status in found]
    return 0 if all(status == "running" for status in every) else 3
