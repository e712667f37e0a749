"""`roadgaze listen --query-state`: ask the state queryable once, as a health check."""

from __future__ import annotations

import sys
import time
from typing import Any


def _say(text: str) -> None:
    print(f"roadgaze listen: {text}", file=sys.stderr, flush=True)


def query_state(listener: Any, timeout_s: float) -> int:
    """Ask every state queryable of `listener`'s keys (no consolidation: a second answerer is
    seen), print the answers and return the exit status: 0 all running, 3 degraded or
    suspicious, 1 no answer."""
    import zenoh

    from roadgaze.transport import PayloadError, printable

    deadline = time.monotonic() + timeout_s
    answers: dict[str, list[str]] = {}
    rejected = 0
    while not answers and time.monotonic() < deadline:
        # Right after opening, the routes to the queryable may not be known yet: ask again.
        wait_s = max(0.05, min(1.0, deadline - time.monotonic()))
        replies = listener.session.get(
            listener.keys.state,
            timeout=wait_s,
            target=zenoh.QueryTarget.ALL,
            consolidation=zenoh.ConsolidationMode.NONE,
        )
        for reply in replies:
            if reply.ok is None:
                continue
            key = str(reply.ok.key_expr)
            try:
                checked = listener.checker.check("state", key, reply.ok.payload.to_bytes())
            except PayloadError as exc:
                _say(f"state answer on {printable(key, 80)} rejected: {printable(str(exc))}")
                rejected += 1
                continue
            answers.setdefault(checked.vehicle_id, []).append(str(checked.payload["status"]))
            listener._show("state", key, checked.vehicle_id, checked.payload)
    if not answers:
        _say(f"no answer from {listener.keys.state}")
        return 1
    twice = {vehicle: n for vehicle, statuses in answers.items() if (n := len(statuses)) > 1}
    if twice:
        _say(
            f"suspicious: several answers for one vehicle {twice}: another process answers "
            "on its state key (see docs/security.md)"
        )
        return 3
    if rejected:
        _say(
            f"suspicious: {rejected} answer(s) rejected beside the valid one: another process "
            "answers on the state key (see docs/security.md)"
        )
        return 3
    statuses = [status for found in answers.values() for status in found]
    return 0 if all(status == "running" for status in statuses) else 3
