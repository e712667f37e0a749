"""Bus payloads as hostile input: speed, JSON bounds, message checks, throttled warnings.

The parsers must only ever raise `PayloadError` (a ValueError), whatever the bytes: tables of
known attacks, then hypothesis fuzzing.
"""

from __future__ import annotations

import contextlib
import json
import logging
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fakes import alert_message, yaw_message
from roadgaze.transport import (
    PayloadError,
    SpeedInput,
    ThrottledWarning,
    parse_json_object,
    parse_speed_kmh,
    printable,
)
from roadgaze.transport.checks import MessageChecker

PREFIX = "vehicle/{vehicle_id}/dms"


@pytest.mark.parametrize(
    ("payload", "expected"),
    [
        (b'{"kmh": 42.5}', 42.5),
        (b'{"kmh": 0}', 0.0),
        (b"88", 88.0),
        (b" 12.25 ", 12.25),
        (b"400", 400.0),
    ],
)
def test_speed_payloads_accepted(payload: bytes, expected: float) -> None:
    assert parse_speed_kmh(payload) == expected


@pytest.mark.parametrize(
    ("payload", "reason"),
    [
        (b"fast", "not JSON"),
        (b'{"mph": 30}', "expected"),
        (b'{"kmh": "30"}', "must be a number"),
        (b'{"kmh": true}', "must be a number"),
        (b"-5", "within 0-400"),
        (b"400.5", "within 0-400"),
        (b"1e308", "within 0-400"),
        (b"1e999", "within 0-400"),  # json reads it as inf
        (b"9" * 200, "within 0-400"),  # a 200-digit integer
        (b"9" * 5000, "limit 256"),  # size first
        (b"NaN", "NaN is not allowed"),
        (b"Infinity", "Infinity is not allowed"),
        (b"[1]", "must be a number"),
        (b"\xff", "not UTF-8"),
        (b"[" * 200, "not JSON"),
        (b"[" * 100_000, "limit 256"),
    ],
)
def test_speed_payloads_rejected(payload: bytes, reason: str) -> None:
    with pytest.raises(PayloadError, match=reason):
        parse_speed_kmh(payload)


def test_deep_nesting_within_the_size_limit_is_rejected_not_a_crash() -> None:
    with pytest.raises(PayloadError, match="nested too deeply"):
        parse_json_object(b"[" * 50_000, max_bytes=100_000)
    with pytest.raises(PayloadError, match="nested too deeply"):
        parse_json_object(b'{"a":' * 30_000, max_bytes=1_000_000)


def test_speed_times_out_and_an_invalid_one_is_unknown_at_once() -> None:
    now = [100.0]
    speed = SpeedInput(timeout_s=2.0, clock=lambda: now[0])
    assert speed.kmh() is None and speed.current() == (None, "waiting")
    speed.on_payload(b'{"kmh": 30}')
    assert speed.kmh() == 30.0
    now[0] += 1.9
    assert speed.kmh() == 30.0  # nothing new: the last speed holds for timeout_s
    now[0] += 0.2
    assert (speed.kmh(), speed.current()[1]) == (None, "stale")
    speed.on_payload(b"20")
    assert speed.kmh() == 20.0
    speed.on_payload(b'{"kmh": 1e308}')
    assert (speed.kmh(), speed.current()[1]) == (None, "invalid")
    assert (speed.messages, speed.rejected) == (3, 1)


def test_speed_is_read_from_a_ring_once_per_frame_and_oversize_payloads_are_not_copied() -> None:
    class Payload:
        copies = 0

        def __init__(self, data: bytes) -> None:
            self.data = data

        def __len__(self) -> int:
            return len(self.data)

        def to_bytes(self) -> bytes:
            Payload.copies += 1
            return self.data

    ring: list[Payload] = [Payload(b"x" * 10_000_000)]
    speed = SpeedInput()
    speed.attach(lambda: ring.pop() if ring else None)
    assert speed.kmh() is None
    assert (speed.oversize, Payload.copies) == (1, 0)
    assert speed.current() == (None, "invalid")  # not a speed: unknown at once, said so
    ring.append(Payload(b"55"))
    assert speed.kmh() == 55.0 and speed.messages == 2
    ring.append(Payload(b"x" * 257))  # after a valid speed too: not kept until it is stale
    assert speed.kmh() is None and speed.current() == (None, "invalid")
    assert (speed.oversize, speed.rejected) == (2, 0)


def test_checker_accepts_valid_messages_and_follows_alert_sequences() -> None:
    checker = MessageChecker(PREFIX)
    key = "vehicle/car-1/dms/alert"
    for seq in (0, 1):
        checked = checker.check("alert", key, alert_message(seq, "car-1").to_json_bytes(), "pub-a")
        assert (checked.vehicle_id, checked.missing_before) == ("car-1", 0)
    gap = checker.check("alert", key, alert_message(4, "car-1").to_json_bytes(), "pub-a")
    assert gap.missing_before == 2
    with pytest.raises(PayloadError, match="duplicate or out of order"):
        checker.check("alert", key, alert_message(4, "car-1").to_json_bytes(), "pub-a")
    restarted = checker.check("alert", key, alert_message(0, "car-1").to_json_bytes(), "pub-b")
    assert restarted.missing_before == 0  # a restarted daemon is a new publisher
    yaw = checker.check(
        "yaw", "vehicle/car-1/dms/yaw", yaw_message(3, vehicle_id="car-1").to_json_bytes()
    )
    assert yaw.payload["seq"] == 3


@pytest.mark.parametrize(
    ("key", "payload", "reason"),
    [
        ("vehicle/car-2/dms/alert", alert_message(0, "car-1").to_json_bytes(), "on the key of"),
        ("vehicle/car-1/dms/alert", b'{"schema": "roadgaze.alert/9"}', "not a valid alert"),
        ("vehicle/car-1/dms/alert", b"[" * 100_000, "limit"),
        ("vehicle/car-1/dms/alert", b"[" * 10_000, "nested too deeply"),
        ("vehicle/car-1/dms/alert", b'"\\ud800"', "expected a JSON object"),
        (
            "vehicle/car-1/dms/alert",
            alert_message(0, "car-1")
            .to_json_bytes()
            .replace(b'"yaw_deg":45.0', b'"yaw_deg":1e999'),
            "finite",
        ),
        ("vehicle/car-1/dms/state", b'{"status": "running"}', "not a valid state"),
        ("vehicle/car-1/dms/other", b"{}", "no message is expected"),
    ],
)
def test_checker_rejects_forged_and_hostile_messages(key: str, payload: bytes, reason: str) -> None:
    kind = key.rsplit("/", 1)[-1]
    with pytest.raises(PayloadError, match=reason):
        MessageChecker(PREFIX).check(kind, key, payload, "pub")


def test_printable_escapes_lone_surrogates_and_control_characters() -> None:
    text = printable("car\ud800\x1b[2J" + "x" * 200, max_chars=20)
    text.encode("utf-8")  # would raise on a lone surrogate
    assert "\\ud800" in text and "\x1b" not in text and text.endswith("...")


def test_throttled_warning_logs_the_first_then_one_per_period(
    caplog: pytest.LogCaptureFixture,
) -> None:
    now = [0.0]
    logger = logging.getLogger("roadgaze.test.throttle")
    warn = ThrottledWarning(logger, "bad input", period_s=10.0, clock=lambda: now[0])
    with caplog.at_level(logging.WARNING, logger="roadgaze.test.throttle"):
        for _ in range(1000):
            warn("x")
        now[0] = 10.5
        warn("y")
    assert [r.getMessage() for r in caplog.records] == [
        "bad input: x",
        "bad input: y (999 more since the last warning, 1001 in all)",
    ]


JSON_SCALARS = st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=20)
JSON_VALUES = st.recursive(
    JSON_SCALARS,
    lambda children: (
        st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=8), children, max_size=4)
    ),
    max_leaves=20,
)
HOSTILE_BYTES = (
    st.binary(max_size=400)
    | JSON_VALUES.map(lambda v: json.dumps(v).encode())
    | st.integers(1, 3000).map(lambda n: b"[" * n)
    | st.integers(1, 6000).map(lambda n: b"9" * n)
    | st.text(max_size=50).map(lambda t: t.encode("utf-8", errors="surrogatepass"))
)
FUZZ = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@FUZZ
@given(HOSTILE_BYTES)
def test_fuzz_speed_parser_only_rejects(payload: bytes) -> None:
    try:
        speed = parse_speed_kmh(payload)
    except PayloadError:
        return
    assert 0.0 <= speed <= 400.0


@FUZZ
@given(HOSTILE_BYTES, st.sampled_from(["alert", "yaw", "state", "alive"]))
def test_fuzz_message_checker_only_rejects(payload: bytes, kind: str) -> None:
    checker = MessageChecker(PREFIX)
    try:
        checked = checker.check(kind, f"vehicle/car-1/dms/{kind}", payload, "pub")
    except PayloadError as exc:
        printable(str(exc)).encode("utf-8")
        return
    assert checked.vehicle_id == "car-1"


@FUZZ
@given(JSON_VALUES)
def test_fuzz_alert_fields_mutated_are_rejected_or_valid(value: object) -> None:
    document = json.loads(alert_message(0, "car-1").to_json_bytes())
    for field in ("seq", "yaw_deg", "kind", "t_s"):
        mutated = json.dumps(document | {field: value}, allow_nan=True).encode()
        started = time.monotonic()
        with contextlib.suppress(PayloadError):
            MessageChecker(PREFIX).check("alert", "vehicle/car-1/dms/alert", mutated, "pub")
        assert time.monotonic() - started < 1.0
