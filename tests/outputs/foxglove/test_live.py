"""The live view on loopback, tested with a WebSocket client speaking Foxglove's protocol: the
server advertises every channel with its schema, a client subscribes and receives each record
(JSON) and camera frame (a JPEG) as binary message-data frames stamped with the capture time;
camera frames are encoded only while a client wants them; `[HOST:]PORT`; the warning off
loopback.

foxglove-sdk 0.30's server speaks the protocol under its current subprotocol name
`foxglove.sdk.v1` (the same messages as `foxglove.websocket.v1`, which it no longer accepts).
"""

from __future__ import annotations

import json
import logging
import struct
import time
from collections.abc import Iterator
from typing import Any

import cv2
import numpy as np
import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import ClientConnection, connect

from foxglove_helpers import pipeline_records, protobuf_message, read_mcap
from roadgaze.config import Config, RecordConfig
from roadgaze.errors import ConfigError
from roadgaze.outputs.foxglove.channels import TOPIC_IMAGE, TOPIC_RECORD, TOPICS
from roadgaze.outputs.foxglove.live import LiveServer, is_loopback, parse_address
from roadgaze.outputs.foxglove.open import vehicle_recorder
from roadgaze.outputs.foxglove.recorder import FoxgloveRecorder
from roadgaze.outputs.records import record_fields

SUBPROTOCOL = "foxglove.sdk.v1"
MESSAGE_DATA = 0x01
RECORDS = pipeline_records()


@pytest.fixture
def live() -> Iterator[tuple[FoxgloveRecorder, LiveServer]]:
    recorder = vehicle_recorder(Config(), "numbered", None, "127.0.0.1:0", state=lambda: b"{}")
    (server,) = recorder.targets
    assert isinstance(server, LiveServer)
    with recorder:
        yield recorder, server


def advertised(client: ClientConnection) -> dict[str, dict[str, Any]]:
    """The channels of the server's `advertise` (after its `serverInfo`), by topic."""
    channels: dict[str, dict[str, Any]] = {}
    deadline = time.monotonic() + 5.0
    while set(channels) != set(TOPICS) and time.monotonic() < deadline:
        message = json.loads(client.recv(timeout=5.0))
        if message["op"] == "advertise":
            channels.update({channel["topic"]: channel for channel in message["channels"]})
    return channels


def message_data(client: ClientConnection, until_s: float) -> list[tuple[int, int, bytes]]:
    """(subscription id, timestamp ns, payload) of each binary message-data frame received."""
    received: list[tuple[int, int, bytes]] = []
    deadline = time.monotonic() + until_s
    while time.monotonic() < deadline:
        try:
            frame = client.recv(timeout=max(0.01, deadline - time.monotonic()))
        except TimeoutError:
            break
        if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
            _, subscription, stamp_ns = struct.unpack_from("<BIQ", frame)
            received.append((subscription, stamp_ns, frame[13:]))
    return received


def test_a_client_is_told_every_channel_subscribes_and_receives_records_and_images(
    live: tuple[FoxgloveRecorder, LiveServer],
) -> None:
    recorder, server = live
    with connect(server.url, subprotocols=[SUBPROTOCOL]) as client:
        assert client.subprotocol == SUBPROTOCOL
        channels = advertised(client)
        assert {topic: c["schemaName"] for topic, c in channels.items()} == {
            "/camera/image": "foxglove.CompressedImage",
            "/roadgaze/annotations": "foxglove.ImageAnnotations",
            "/roadgaze/record": "roadgaze.record",
            "/roadgaze/limits": "roadgaze.limits",
            "/roadgaze/alerts": "roadgaze.alert/4",
            "/roadgaze/state": "roadgaze.state/6",
            "/roadgaze/support": "roadgaze.support/1",
            "/roadgaze/log": "foxglove.Log",
            "/roadgaze/driver": "roadgaze.driver/1",
        }
        assert channels[TOPIC_RECORD]["encoding"] == "json"
        assert json.loads(channels[TOPIC_RECORD]["schema"])["title"] == "roadgaze.record"
        subscriptions = [
            {"id": 1, "channelId": channels[TOPIC_RECORD]["id"]},
            {"id": 2, "channelId": channels[TOPIC_IMAGE]["id"]},
        ]
        client.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
        assert _wait(lambda: server.images_wanted())
        for record, frame in RECORDS[:60]:
            recorder.on_record(record, frame)
            time.sleep(0.005)
        received = message_data(client, 3.0)
    records = [(stamp, json.loads(data)) for sub, stamp, data in received if sub == 1]
    images = [(stamp, data) for sub, stamp, data in received if sub == 2]
    assert [fields for _, fields in records] == [record_fields(r) for r, _ in RECORDS[:60]]
    offsets = [
        stamp - round(record.t_s * 1e9)
        for (stamp, _), (record, _) in zip(records, RECORDS, strict=False)
    ]
    assert len(set(offsets)) == 1  # every message on one capture clock: the wall clock's offset
    assert abs(offsets[0] / 1e9 - time.time()) < 60.0
    assert len(images) == 10  # 2 s at 5 fps
    decoded = _jpeg_of(images[0][1])
    assert decoded.shape == RECORDS[0][1].image.shape
    assert np.abs(decoded.astype(int) - RECORDS[0][1].image).mean() < 3.0


def _jpeg_of(payload: bytes) -> np.ndarray:
    """The JPEG inside a protobuf `CompressedImage` (its `data` field, number 3)."""
    from foxglove.messages import CompressedImage

    schema = CompressedImage.get_schema()
    from roadgaze.capture.mcap_images import protobuf_class

    message = protobuf_class(schema.name, schema.data)(payload)
    assert message.format == "jpeg"
    return cv2.imdecode(np.frombuffer(message.data, np.uint8), cv2.IMREAD_COLOR)


def _wait(predicate: Any, timeout_s: float = 5.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.02)
    return False


def test_no_camera_frame_is_encoded_while_nobody_watches(
    live: tuple[FoxgloveRecorder, LiveServer],
) -> None:
    recorder, server = live
    for record, frame in RECORDS[:30]:
        recorder.on_record(record, frame)
    assert not server.images_wanted()
    time.sleep(0.2)
    assert recorder.images_written == 0 and recorder.records_queued == 30


def test_the_old_subprotocol_name_is_refused(live: tuple[FoxgloveRecorder, LiveServer]) -> None:
    with pytest.raises(InvalidStatus), connect(live[1].url, subprotocols=["foxglove.websocket.v1"]):
        pass


def test_recording_and_live_view_together_share_the_channels(tmp_path: Any) -> None:
    config = Config(record=RecordConfig(flush_s=0.05, images=True))
    recorder = vehicle_recorder(config, "numbered", tmp_path, "127.0.0.1:0")
    recorder.block_on_images = True  # a loaded machine's image thread may fall behind: count all
    with recorder:
        server = recorder.targets[1]
        assert isinstance(server, LiveServer)
        with connect(server.url, subprotocols=[SUBPROTOCOL]) as client:
            channels = advertised(client)
            client.send(
                json.dumps(
                    {
                        "op": "subscribe",
                        "subscriptions": [{"id": 7, "channelId": channels[TOPIC_RECORD]["id"]}],
                    }
                )
            )
            time.sleep(0.3)
            for record, frame in RECORDS[:20]:
                recorder.on_record(record, frame)
                time.sleep(0.02)  # a camera's pace
            received = message_data(client, 2.0)
    assert len([r for r in received if r[0] == 7]) == 20
    (segment,) = tmp_path.glob("*.mcap")
    contents = read_mcap(segment)
    assert contents.counts[TOPIC_RECORD] == 20 and contents.counts[TOPIC_IMAGE] == 4
    first = protobuf_message(contents, TOPIC_IMAGE, contents.messages[TOPIC_IMAGE][0].data)
    assert first.format == "jpeg"


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("8765", ("127.0.0.1", 8765)),
        ("0.0.0.0:9000", ("0.0.0.0", 9000)),
        ("localhost:1", ("localhost", 1)),
        ("[::1]:8765", ("::1", 8765)),
        ("192.168.1.10:0", ("192.168.1.10", 0)),
    ],
)
def test_addresses(text: str, expected: tuple[str, int]) -> None:
    assert parse_address(text) == expected


@pytest.mark.parametrize("text", ["", "port", "70000", ":8765", "[::1]8765", "host:", "-1"])
def test_bad_addresses_are_one_line(text: str) -> None:
    with pytest.raises(ConfigError, match=r"^--foxglove '.*': expected \[HOST:\]PORT"):
        parse_address(text)


@pytest.mark.parametrize(
    ("host", "loopback"),
    [
        ("127.0.0.1", True),
        ("127.0.0.2", True),
        ("::1", True),
        ("localhost", True),
        ("0.0.0.0", False),
        ("192.168.1.10", False),
        ("car.local", False),
    ],
)
def test_loopback(host: str, loopback: bool) -> None:
    assert is_loopback(host) is loopback


def test_bound_off_loopback_it_warns_that_the_stream_shows_the_face(
    caplog: pytest.LogCaptureFixture,
) -> None:
    with caplog.at_level(logging.WARNING, logger="roadgaze"):
        recorder = vehicle_recorder(Config(), "numbered", None, "0.0.0.0:0")
        recorder.close()
    (warning,) = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert "reachable from the network" in warning and "driver's face" in warning


def test_a_port_in_use_is_one_line() -> None:
    first = vehicle_recorder(Config(), "numbered", None, "127.0.0.1:0")
    try:
        port = first.targets[0].port  # type: ignore[attr-defined]
        with pytest.raises(
            ConfigError, match=rf"^cannot serve the Foxglove live view on 127\.0\.0\.1:{port}: "
        ):
            vehicle_recorder(Config(), "numbered", None, f"127.0.0.1:{port}")
    finally:
        first.close()


def test_a_hostile_client_gets_one_log_line_per_period_not_one_per_bad_frame(
    live: tuple[FoxgloveRecorder, LiveServer], caplog: pytest.LogCaptureFixture
) -> None:
    """Issue 34: a client sending bad frames got one log line each (36,150 in 45 s). Now the
    first is logged, then one per 10 s with the count held back, and the rest at the stop."""
    recorder, server = live
    sent = 1000  # each gets a status reply; a client whose reply queue fills is dropped
    frames = ["not json", b"\x99garbage", '{"op": "subscribe", "subscriptions": [{"id": 1}]}']
    with (
        caplog.at_level(logging.WARNING),
        connect(server.url, subprotocols=[SUBPROTOCOL]) as client,
    ):
        channels = advertised(client)
        for index in range(sent):
            client.send(frames[index % len(frames)])
            if index % 100 == 99:  # read its status replies, or it drops a client too slow
                message_data(client, 0.01)
        # The server reads a client's frames in order: data on this subscription means it has
        # read (and logged about) every bad frame before it.
        subscribe = {"id": 7, "channelId": channels[TOPIC_RECORD]["id"]}
        client.send(json.dumps({"op": "subscribe", "subscriptions": [subscribe]}))
        received: list[tuple[int, int, bytes]] = []
        for record, frame in RECORDS:
            recorder.on_record(record, frame)
            received += message_data(client, 0.05)
            if received:
                break
        assert received and received[0][0] == 7
    recorder.close()
    about_client = [r.getMessage() for r in caplog.records if "127.0.0.1:" in r.getMessage()]
    assert len(about_client) == 1 and about_client[0].startswith("Invalid message from 127.0.0.1")
    summary = [r.getMessage() for r in caplog.records if "held back" in r.getMessage()]
    assert summary == [
        f"foxglove: {sent - 1} more lines about client 127.0.0.1 held back ({sent} in all: bad "
        "frames from it)"
    ]
