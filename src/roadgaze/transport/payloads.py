"""Bus payloads as hostile input: bounded JSON parsing and size limits (pure: no Zenoh import).

Everything that arrives on Zenoh (speed, alerts and states seen by `listen`, state replies) may
come from anyone on an open bus. `parse_json_value` checks the size before anything else, then
strict UTF-8, refuses `NaN`/`Infinity` literals and turns every failure of the `json` module
(nesting too deep, a 5000-digit integer, bad syntax) into `PayloadError`.
"""

from __future__ import annotations

import json
from typing import Any

SPEED_MAX_BYTES = 256
"""Largest speed payload read (`{"kmh": 57.5}` is 13 bytes); larger ones are dropped."""
MESSAGE_MAX_BYTES = 64 * 1024
"""Largest alert, yaw or state payload `listen` reads (a state is about 2 kB)."""


class PayloadError(ValueError):
    """A payload that is not a bounded, valid JSON document; the message says why."""


def _refuse_constant(name: str) -> float:
    raise PayloadError(f"{name} is not allowed")


def parse_json_value(raw: bytes, max_bytes: int) -> Any:
    """The JSON value of `raw`; raises `PayloadError` when it is over `max_bytes`, not UTF-8,
    not JSON, nested too deeply, or contains `NaN`/`Infinity` or an integer over 4300 digits."""
    if len(raw) > max_bytes:
        raise PayloadError(f"payload of {len(raw)} bytes, limit {max_bytes}")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise PayloadError("payload is not UTF-8") from None
    try:
        return json.loads(text, parse_constant=_refuse_constant)
    except RecursionError:
        raise PayloadError("JSON nested too deeply") from None
    except PayloadError:
        raise
    except ValueError as exc:  # JSONDecodeError, integer digit limit
        raise PayloadError(f"not JSON: {str(exc)[:80]}") from None


def parse_json_object(raw: bytes, max_bytes: int = MESSAGE_MAX_BYTES) -> dict[str, Any]:
    """A JSON object from `raw` (see `parse_json_value`); anything else is `PayloadError`."""
    value = parse_json_value(raw, max_bytes)
    if not isinstance(value, dict):
        raise PayloadError(f"expected a JSON object, found {type(value).__name__}")
    return value


def printable(text: str, max_chars: int = 120) -> str:
    """`text` cut to `max_chars`, with characters that cannot be encoded (lone surrogates) and
    control characters escaped: safe to print on any terminal."""
    cut = text[:max_chars] + ("..." if len(text) > max_chars else "")
    escaped = cut.encode("utf-8", errors="backslashreplace").decode("utf-8")
    return "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in escaped)
