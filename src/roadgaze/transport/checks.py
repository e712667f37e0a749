"""Checks a consumer applies to every message it receives (pure: no Zenoh import).

A message is accepted only when it is a bounded JSON object that validates against its schema
(`schema` names the version), its `vehicle_id` is the one in its key, and, for alerts, its `seq`
continues the sequence of its publisher (a restarted daemon is a new publisher and starts at 0).
`MessageChecker.check` raises `PayloadError` with the reason otherwise (`DuplicateSeqError` for a
number already seen); a gap is accepted and reported with the alert, and an alert of that gap
arriving after all is accepted as `late`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pydantic import ValidationError

from roadgaze.transport.messages import MESSAGE_MODELS
from roadgaze.transport.payloads import MESSAGE_MAX_BYTES, PayloadError, parse_json_object

MISSING_RANGES = 64
"""Gaps remembered per publisher, so a late alert is told from a duplicate (the oldest go)."""
PLAIN_PUBLISHER = "plain"
"""Source of a sample without Zenoh source information (not from an advanced publisher)."""


@dataclass(frozen=True, slots=True)
class Checked:
    """A message that passed the checks, and what a reader should know about it."""

    kind: str
    key: str
    vehicle_id: str
    payload: dict[str, Any]
    missing_before: int = 0
    """Alerts only: how many sequence numbers of this publisher were skipped just before it."""
    first: bool = False
    """Alerts only: the first alert seen from this publisher (numbers before it were not seen)."""
    late: bool = False
    """Alerts only: its number was in an earlier gap (it arrives out of order, after later ones)."""
    expected: int = 0
    """Alerts only, when `late`: the number this publisher's next alert was expected to have."""


class DuplicateSeqError(PayloadError):
    """An alert whose number its publisher already used (a replay, or sent twice)."""

    def __init__(self, seq: int, expected: int) -> None:
        super().__init__(f"duplicate or out of order: seq {seq}, expected {expected}")
        self.seq = seq
        self.expected = expected


def vehicle_of(key: str, prefix_template: str) -> str:
    """The vehicle id in `key`, at the place of `{vehicle_id}` in the prefix template; '?' when
    the template has no placeholder or the key is too short."""
    parts = prefix_template.strip("/").split("/")
    if "{vehicle_id}" in parts:
        index = parts.index("{vehicle_id}")
        key_parts = key.split("/")
        if index < len(key_parts):
            return key_parts[index]
    return "?"


class MessageChecker:
    """Validates received yaw, alert and state messages; keeps alert `seq` per publisher."""

    MAX_PUBLISHERS = 1024
    """Publishers remembered for `seq` continuity (bounded: the oldest are forgotten)."""

    def __init__(self, prefix_template: str, max_bytes: int = MESSAGE_MAX_BYTES) -> None:
        self._prefix_template = prefix_template
        self._max_bytes = max_bytes
        self._next_seq: dict[tuple[str, str], int] = {}
        self._gaps: dict[tuple[str, str], list[tuple[int, int]]] = {}
        """Per publisher: the ranges of numbers skipped so far (first, last), oldest first."""

    def check(self, kind: str, key: str, raw: bytes, source: str | None = None) -> Checked:
        """The checked message; raises `PayloadError` saying why it is refused."""
        vehicle = vehicle_of(key, self._prefix_template)
        payload = parse_json_object(raw, self._max_bytes)
        model = MESSAGE_MODELS.get(kind)
        if model is None:
            raise PayloadError(f"no message is expected on {key}")
        try:
            message = model.model_validate(payload)
        except ValidationError as exc:
            first = exc.errors()[0]
            where = ".".join(str(part) for part in first["loc"]) or "message"
            raise PayloadError(
                f"not a valid {kind} message ({exc.error_count()} problems; {where}: "
                f"{first['msg']})"
            ) from None
        vehicle_id = getattr(message, "vehicle_id", None)
        if vehicle != "?" and vehicle_id != vehicle:
            raise PayloadError(f"vehicle_id {str(vehicle_id)[:64]!r} on the key of {vehicle!r}")
        if kind != "alert":
            return Checked(kind, key, vehicle, payload)
        stream = (vehicle, source or PLAIN_PUBLISHER)
        first_seen = stream not in self._next_seq
        seq = int(payload["seq"])
        expected = self._next_seq.get(stream, 0)
        if not first_seen and seq < expected:
            self._fill(stream, seq)  # raises DuplicateAlert unless it was in a gap
            return Checked(kind, key, vehicle, payload, late=True, expected=expected)
        missing = self._continue(stream, seq)
        return Checked(kind, key, vehicle, payload, missing, first_seen)

    def _continue(self, stream: tuple[str, str], seq: int) -> int:
        expected = self._next_seq.get(stream)
        if expected is None and len(self._next_seq) >= self.MAX_PUBLISHERS:
            forgotten = next(iter(self._next_seq))
            self._next_seq.pop(forgotten)
            self._gaps.pop(forgotten, None)
        self._next_seq[stream] = seq + 1
        start = 0 if expected is None else expected
        if seq > start:
            gaps = self._gaps.setdefault(stream, [])
            gaps.append((start, seq - 1))
            del gaps[:-MISSING_RANGES]
        return 0 if expected is None else seq - expected

    def _fill(self, stream: tuple[str, str], seq: int) -> None:
        """Take `seq` out of its publisher's gaps; `DuplicateAlert` when it was in none."""
        gaps = self._gaps.get(stream, [])
        for index, (first, last) in enumerate(gaps):
            if first <= seq <= last:
                parts = [(first, seq - 1), (seq + 1, last)]
                gaps[index : index + 1] = [(a, b) for a, b in parts if a <= b]
                return
        raise DuplicateSeqError(seq, self._next_seq[stream])
