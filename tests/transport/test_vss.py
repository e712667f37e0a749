"""COVESA VSS signals: their values from frame records (closed forms of the levels), keys and text,
the on-change and 10 Hz publishing, and real Zenoh delivery with Kuksa's attachment."""

from __future__ import annotations

import itertools
import sys
import threading
from dataclasses import replace
from typing import Any

import pytest

from fakes import BLANK_FRAME, eyes_of
from repo_paths import child_env
from roadgaze.config import Config, MonitorConfig
from roadgaze.monitor import Monitor
from roadgaze.transport import (
    Keys,
    PayloadError,
    VssPublisher,
    ZenohLink,
    parse_vss_text,
    vss_key,
    vss_text,
    vss_values,
)
from roadgaze.transport.vss import VSS_PATHS
from roadgaze.types import EyesFeatures, EyeStatus, EyesVerdict, FrameRecord, PoseSample
from zenoh_helpers import (
    LineReader,
    endpoint,
    free_port,
    router,
    stop_process,
    wait_for,
    wait_for_subscribers,
)

CONFIG = MonitorConfig(neutral_yaw_deg=5.0, neutral_pitch_deg=-10.0)
FPS = 30.0


def drive(script: list[tuple[float, float, EyesFeatures | None]]) -> list[FrameRecord]:
    """Records of (seconds, head yaw, eyes) segments through the monitor."""
    monitor = Monitor(CONFIG)
    records: list[FrameRecord] = []
    t_s = 0.0
    for seconds, yaw_deg, eyes in script:
        for _ in range(round(seconds * FPS)):
            face = eyes is not None
            sample = PoseSample(
                t_s,
                len(records),
                face,
                yaw_deg if face else None,
                yaw_deg if face else None,
                0.0,
                1.0,
                pitch_deg=-10.0 if face else None,
                roll_deg=3.0 if face else None,
                eyes=eyes,
            )
            alerts = monitor.update(sample, None)
            records.append(FrameRecord(sample, monitor.verdict, alerts))
            t_s += 1 / FPS
    return records


def test_keys_and_text() -> None:
    assert vss_key("Vehicle.Driver.IsEyesOnRoad") == "Vehicle/Driver/IsEyesOnRoad"
    assert vss_key("Vehicle.ADAS.DMS.IsError", "/car-7/") == "car-7/Vehicle/ADAS/DMS/IsError"
    assert (vss_text(True), vss_text(False), vss_text(12.5), vss_text(0)) == (
        b"true",
        b"false",
        b"12.5",
        b"0.0",
    )
    assert len(VSS_PATHS) == 13  # VSS 6.0 signals and roadgaze's support overlay (2)


@pytest.mark.parametrize(
    ("key", "raw", "prefix", "expected"),
    [
        ("Vehicle/Driver/IsEyesOnRoad", b"true", "", "true"),
        ("car-0/Vehicle/ADAS/DMS/IsError", b"false", "car-0", "false"),
        ("Vehicle/Driver/FatigueLevel", b"100.0", "", "100.0"),
        ("Vehicle/Occupant/Row1/DriverSide/HeadPosition/Yaw", b"-12.5", "", "-12.5"),
        ("Vehicle/Speed", b"57.5", "", "57.5"),  # not roadgaze's: short printable text
        ("Vehicle/Driver/IsEyesOnRoad", b"True", "", "true or false"),
        ("Vehicle/Driver/FatigueLevel", b"100.1", "", "outside 0..100"),
        ("Vehicle/Driver/DistractionLevel", b"-0.5", "", "outside 0..100"),
        ("Vehicle/Driver/AttentiveProbability", b"nan", "", "decimal number"),
        ("Vehicle/Driver/AttentiveProbability", b"1e3", "", "decimal number"),
        ("Vehicle/Occupant/Row1/DriverSide/MidEyeGaze/Elevation", b"95.0", "", "outside -90..90"),
        ("Vehicle/Occupant/Row1/DriverSide/HeadPosition/Roll", b" 5", "", "decimal number"),
        ("Vehicle/Driver/FatigueLevel", b"\xff", "", "not UTF-8"),
        ("Vehicle/Cabin/Note", b"\x1b[2J", "", "printable"),
        ("Vehicle/Cabin/Note", b"x" * 300, "", "limit 256"),
    ],
)
def test_vss_values_from_the_bus_are_checked(
    key: str, raw: bytes, prefix: str, expected: str
) -> None:
    if expected in ("true", "false", "100.0", "-12.5", "57.5"):
        assert parse_vss_text(key, raw, prefix) == expected
    else:
        with pytest.raises(PayloadError, match=expected):
            parse_vss_text(key, raw, prefix)


def test_what_roadgaze_publishes_passes_its_own_check() -> None:
    monitor = MonitorConfig()
    records = drive([(1.0, 0.0, eyes_of()), (1.0, 40.0, None), (1.0, -179.0, eyes_of())])
    for record in records:
        for path, value in vss_values(record, monitor).items():
            assert parse_vss_text(vss_key(path), vss_text(value)) == vss_text(value).decode()
    turned = vss_values(records[-1], monitor)  # yaw -179 with the neutral at +5: wrapped
    assert turned["Vehicle.Occupant.Row1.DriverSide.HeadPosition.Yaw"] == 176.0


def test_angles_are_relative_to_the_neutral_and_wrapped() -> None:
    monitor = MonitorConfig()
    records = drive([(1.0, 0.0, eyes_of()), (1.0, -179.0, eyes_of())])
    ahead = vss_values(records[0], monitor)
    assert ahead["Vehicle.Occupant.Row1.DriverSide.HeadPosition.Yaw"] == -5.0  # neutral +5
    assert ahead["Vehicle.Occupant.Row1.DriverSide.HeadPosition.Pitch"] == 0.0
    turned = vss_values(records[-1], monitor)  # yaw -179 with the neutral at +5: wrapped
    assert turned["Vehicle.Occupant.Row1.DriverSide.HeadPosition.Yaw"] == 176.0


def test_levels_follow_their_closed_forms() -> None:
    records = drive(
        [(2.0, 5.0, eyes_of()), (2.0, 5.0, eyes_of(openness=0.05)), (2.0, -22.0, eyes_of())]
    )
    on_road = vss_values(records[round(1.9 * FPS)], CONFIG)
    assert on_road["Vehicle.Driver.IsEyesOnRoad"] is True
    assert on_road["Vehicle.Driver.DistractionLevel"] == 0.0
    assert on_road["Vehicle.Driver.AttentiveProbability"] == 100.0
    assert on_road["Vehicle.Occupant.Row1.DriverSide.HeadPosition.Yaw"] == 0.0  # rel. neutral
    assert on_road["Vehicle.Occupant.Row1.DriverSide.HeadPosition.Pitch"] == 0.0
    assert on_road["Vehicle.Occupant.Row1.DriverSide.HeadPosition.Roll"] == 3.0
    assert on_road["Vehicle.Occupant.Row1.DriverSide.MidEyeGaze.Azimuth"] == 0.0
    # 0.5 s into the closure: fatigue 50 % (closure / microsleep_s), eyes not on the road.
    closed = records[round(2.5 * FPS)]
    values = vss_values(closed, CONFIG)
    assert closed.verdict.eyes.status is EyeStatus.CLOSED
    assert values["Vehicle.Driver.IsEyesOnRoad"] is False
    assert values["Vehicle.Driver.FatigueLevel"] == pytest.approx(50.0, abs=100 / FPS)
    assert values["Vehicle.Driver.AttentiveProbability"] == pytest.approx(
        100.0 - values["Vehicle.Driver.FatigueLevel"]
    )
    assert vss_values(records[round(3.5 * FPS)], CONFIG)["Vehicle.ADAS.DMS.IsWarning"] is True
    # 1.5 s into a head glance 27 deg right of neutral (zone away; 30 is now the right mirror's
    # edge): distraction 50 %.
    glance = vss_values(records[round(5.5 * FPS)], CONFIG)
    assert glance["Vehicle.Driver.DistractionLevel"] == pytest.approx(50.0, abs=100 / FPS)
    assert glance["Vehicle.Driver.IsEyesOnRoad"] is False
    assert glance["Vehicle.Occupant.Row1.DriverSide.HeadPosition.Yaw"] == -27.0


def test_unknown_is_not_on_the_road_and_degraded_is_an_error() -> None:
    records = drive([(1.0, 5.0, eyes_of()), (3.0, 5.0, None)])
    values = vss_values(records[-1], CONFIG)
    assert values["Vehicle.Driver.IsEyesOnRoad"] is False  # fail-safe
    assert values["Vehicle.Driver.AttentiveProbability"] == 50.0  # no measurement
    assert "Vehicle.Occupant.Row1.DriverSide.HeadPosition.Yaw" not in values
    record = records[-1]
    degraded = replace(
        record,
        verdict=replace(
            record.verdict, eyes=EyesVerdict(status=EyeStatus.UNAVAILABLE, degraded=True)
        ),
    )
    assert vss_values(degraded, CONFIG)["Vehicle.ADAS.DMS.IsError"] is True


class ListLink:
    """Keeps every put with the time of the record being published."""

    def __init__(self) -> None:
        self.now_s = 0.0
        self.puts: list[tuple[float, str, bytes]] = []

    def publish_vss(self, key: str, payload: bytes) -> None:
        self.puts.append((self.now_s, key, payload))


def test_values_go_out_on_change_at_most_ten_times_a_second() -> None:
    link = ListLink()
    publisher = VssPublisher(link, CONFIG, prefix="car-1")
    segments = [(2.0, 5.0, eyes_of()), (3.0, 5.0, eyes_of(openness=0.05)), (1.0, 5.0, eyes_of())]
    for record in drive(segments):
        link.now_s = record.t_s
        publisher.on_record(record, BLANK_FRAME)
    fatigue = [(t, payload) for t, key, payload in link.puts if key.endswith("FatigueLevel")]
    assert fatigue[0][1] == b"0.0" and fatigue[-1][1] == b"0.0"
    assert min(b[0] - a[0] for a, b in itertools.pairwise(fatigue)) >= 0.1 - 1e-6
    # rising through the closure: about 10 values a second until 100 %, then once a second
    assert b"100.0" in [payload for _, payload in fatigue]
    assert 8 <= sum(1 for _, p in fatigue if p not in (b"0.0", b"100.0")) <= 12
    assert 2 <= sum(1 for _, p in fatigue if p == b"100.0") <= 3
    assert "car-1/Vehicle/Driver/IsEyesOnRoad" in {key for _, key, _ in link.puts}
    eyes_on_road = [(t, p) for t, k, p in link.puts if k.endswith("IsEyesOnRoad")]
    # the changes (at 2.0 and 5.0 s), and the value again every second without a change
    changes = [
        (t, p) for i, (t, p) in enumerate(eyes_on_road) if i == 0 or p != eyes_on_road[i - 1][1]
    ]
    assert [p for _, p in changes] == [b"true", b"false", b"true"]
    assert [round(t, 1) for t, _ in changes] == [0.0, 2.0, 5.0]
    assert len(eyes_on_road) == 6  # 0, 1, 2 (false), 3, 4, 5 (true)
    assert max(b[0] - a[0] for a, b in itertools.pairwise(eyes_on_road)) <= 1.0 + 1e-6
    assert publisher.published == len(link.puts)


def test_vss_values_reach_a_zenoh_subscriber_with_kuksas_attachment() -> None:
    port = free_port()
    config = Config.model_validate(
        {
            "zenoh": {
                "mode": "client",
                "connect": [endpoint(port)],
                "listen": [],
                "vss": True,
            }
        }
    )
    keys = Keys.from_config(config.zenoh)
    vss_keys = tuple(vss_key(path) for path in VSS_PATHS)
    received: list[tuple[str, bytes, bytes | None]] = []
    lock = threading.Lock()

    def on_sample(sample: Any) -> None:
        attachment = None if sample.attachment is None else sample.attachment.to_bytes()
        with lock:
            received.append((str(sample.key_expr), sample.payload.to_bytes(), attachment))

    with router(port) as hub:
        subscriber = hub.declare_subscriber("Vehicle/**", on_sample)
        with ZenohLink(config.zenoh, keys, vss_keys=vss_keys) as link:
            assert wait_for(lambda: link.status().connected)
            assert wait_for_subscribers(link, ("vss",))
            publisher = VssPublisher(link, config.monitor)
            for record in drive([(1.0, 0.0, eyes_of())]):
                publisher.on_record(record, BLANK_FRAME)
            assert wait_for(lambda: len(received) >= 9, timeout_s=10.0)
            assert link.status().vss_sent == publisher.published
        subscriber.undeclare()
    by_key = {key: (payload, attachment) for key, payload, attachment in received}
    assert by_key["Vehicle/Driver/IsEyesOnRoad"] == (b"true", b"currentValue")
    assert by_key["Vehicle/ADAS/DMS/IsError"] == (b"false", b"currentValue")
    assert float(by_key["Vehicle/Driver/AttentiveProbability"][0]) == 100.0


def test_listen_vss_prints_the_signals() -> None:
    import subprocess

    port = free_port()
    config = Config.model_validate(
        {"zenoh": {"mode": "client", "connect": [endpoint(port)], "listen": [], "vss": True}}
    )
    with router(port):
        listener = subprocess.Popen(
            [
                *(sys.executable, "-m", "roadgaze", "listen", "--vss", "--no-yaw"),
                *("--zenoh-connect", endpoint(port), "--timeout", "30"),
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=child_env(),
        )
        try:
            reader = LineReader(listener)
            vss_keys = tuple(vss_key(path) for path in VSS_PATHS)
            lines: list[str] = []
            with ZenohLink(config.zenoh, Keys.from_config(config.zenoh), vss_keys=vss_keys) as link:
                for _ in range(100):  # until the subscription has propagated
                    link.publish_vss("Vehicle/Driver/IsEyesOnRoad", b"true")
                    line = reader.next(0.1)
                    while line is not None:
                        lines.append(line)
                        line = reader.next(0.05)
                    if any(item.startswith("vss") for item in lines):
                        break
        finally:
            stop_process(listener)
    assert "vss    Vehicle/Driver/IsEyesOnRoad = true" in lines
