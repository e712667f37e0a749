"""Ask the state queryables of one vehicle (or all) once, as a health check does."""

from __future__ import annotations

import time
from typing import Any

from roadgaze.transport.checks import Checked, MessageChecker
from roadgaze.transport.keys import Keys
from roadgaze.transport.payloads import PayloadError


def query_states(
    session: Any, keys: Keys, checker: MessageChecker, timeout_s: float
) -> tuple[list[Checked], list[tuple[str, str]]]:
    """Ask every state queryable of `keys` (no consolidation: a second answerer is seen), again
    until one answers or `timeout_s`: the checked answers and the rejected ones (key, why)."""
    import zenoh

    deadline = time.monotonic() + timeout_s
    answers: list[Checked] = []
    rejected: list[tuple[str, str]] = []
    while not answers and time.monotonic() < deadline:
        # Right after opening, the routes to the queryable may not be known yet: ask again.
        wait_s = max(0.05, min(1.0, deadline - time.monotonic()))
        replies = session.get(
            keys.state,
            timeout=wait_s,
            target=zenoh.QueryTarget.ALL,
            consolidation=zenoh.ConsolidationMode.NONE,
        )
        for reply in replies:
            if reply.ok is None:
                continue
            key = str(reply.ok.key_expr)
            try:
                answers.append(checker.check("state", key, reply.ok.payload.to_bytes()))
            except PayloadError as exc:
                rejected.append((key, str(exc)))
    return answers, rejected
