"""The support message: built from the frame records, its schema (as `roadgaze schema` prints
it) round-trips, the state message and VSS carry the same levels, and a real Zenoh subscriber
receives one per frame."""

from __future__ import annotations

import json
import threading
from dataclasses import replace
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from fakes import ListSource, ScriptedDetector, eyes_of
from roadgaze.config import Config, MonitorConfig
from roadgaze.monitor import Monitor
from roadgaze.pipeline import Pipeline
from roadgaze.transport import (
    BusPublisher,
    Health,
    Keys,
    StateMessage,
    SupportMessage,
    ZenohLink,
    json_schemas,
    vss_values,
)
from roadgaze.transport.vss import SUPPORT_PATHS, VSS_PATHS, VSS_RANGES, parse_vss_text, vss_text
from roadgaze.types import FrameRecord, PoseSample
from zenoh_helpers import client, endpoint, free_port, router, wait_for, wait_for_subscribers

FPS = 15.0
CONFIG = MonitorConfig(neutral_yaw_deg=0.0, neutral_pitch_deg=0.0)


def mirror_look() -> list[FrameRecord]:
    """3 s ahead, then 1 s at the left mirror (yaw 35) at 70 km/h."""
    monitor = Monitor(CONFIG)
    records = []
    for frame in range(round(4.0 * FPS)):
        t_s = frame / FPS
        yaw_deg = 35.0 if t_s >= 3.0 - 1e-9 else 0.0
        sample = PoseSample(t_s, frame, True, yaw_deg, yaw_deg, 0.0, 1.0, eyes=eyes_of())
        alerts = monitor.update(sample, 70.0)
        records.append(FrameRecord(sample, monitor.verdict, alerts))
    return records


def test_the_message_round_trips_through_its_published_schema() -> None:
    schema = json_schemas()["support"]
    assert schema["properties"]["schema"]["const"] == "roadgaze.support/1"
    records = mirror_look()
    levels = []
    for seq, record in enumerate(records):
        message = SupportMessage.from_record(record, "car-1", seq, 1.0e9)
        document = json.loads(message.to_json_bytes())
        jsonschema.validate(document, schema)
        assert SupportMessage.model_validate(document) == message
        levels.append((round(message.t_s, 3), message.forward.level, message.lane.level))
    assert levels[29] == (1.933, "heightened", "heightened")  # trip start: not watched 2 s yet
    assert levels[30] == (2.0, "normal", "normal")
    assert levels[45] == (3.0, "heightened", "heightened")  # the mirror look's first frame
    last = SupportMessage.from_record(records[-1], "car-1", 59, 1.0e9)
    assert (last.forward.rule, last.forward.reason, last.forward.since_s) == (
        "euroncap.support.forward",
        "head in left_mirror",
        3.0,
    )
    assert "driving-task glances" in last.forward.source
    with pytest.raises(ValueError):
        SupportMessage.model_validate({**document, "forward": {"level": "low"}})


def test_vss_carries_support_on_roadgazes_overlay_paths() -> None:
    assert SUPPORT_PATHS == {
        "forward": "Vehicle.ADAS.DMS.Support.Forward.IsHeightened",
        "lane": "Vehicle.ADAS.DMS.Support.Lane.IsHeightened",
    }
    assert set(SUPPORT_PATHS.values()) <= set(VSS_PATHS)
    records = mirror_look()
    values = [vss_values(record, CONFIG) for record in (records[0], records[30], records[45])]
    forward = SUPPORT_PATHS["forward"]
    assert [v[forward] for v in values] == [True, False, True]
    assert [v[SUPPORT_PATHS["lane"]] for v in values] == [True, False, True]
    key = forward.replace(".", "/")
    assert parse_vss_text(key, vss_text(True)) == "true"
    assert VSS_RANGES[forward] is None  # boolean
    with pytest.raises(ValueError, match="true or false"):
        parse_vss_text(key, b"1")


def test_without_a_verdict_support_is_heightened() -> None:
    record = mirror_look()[0]
    bare = FrameRecord(record.sample, replace(record.verdict, outputs=()), ())
    message = SupportMessage.from_record(bare, "car-1", 0, 1.0)
    assert (message.forward.level, message.forward.reason) == ("heightened", "no verdict yet")
    assert vss_values(bare, CONFIG)[SUPPORT_PATHS["lane"]] is True


def test_a_zenoh_subscriber_receives_support_and_the_state_carries_it(tmp_path: Path) -> None:
    """Support is put with congestion control DROP: Zenoh drops a message its queue cannot take
    within `wait_before_drop` (1 ms by default), which a loaded CI machine once reached (fewer
    than 5 frames arrived in 10 s). The daemon accepts that (the next frame says it again); this
    test checks the routing, so its session waits up to 1 s instead."""
    port = free_port()
    patient = tmp_path / "zenoh.json5"
    patient.write_text(
        '{"transport": {"link": {"tx": {"queue": {"congestion_control":'
        ' {"drop": {"wait_before_drop": 1000000}}}}}}}'
    )
    config = Config.model_validate(
        {
            "zenoh": {
                "vehicle_id": "test-car",
                "mode": "client",
                "connect": [endpoint(port)],
                "listen": [],
                "config_file": str(patient),
            }
        }
    )
    keys = Keys.from_config(config.zenoh)
    assert keys.support == "vehicle/test-car/dms/support"
    received: list[bytes] = []
    lock = threading.Lock()

    def on_sample(sample: Any) -> None:
        with lock:
            received.append(sample.payload.to_bytes())

    health_holder: list[Health] = []
    with router(port) as hub:
        subscriber = hub.declare_subscriber(keys.support, on_sample)
        with ZenohLink(
            config.zenoh, keys, state_reply=lambda: health_holder[0].state_json()
        ) as link:
            health = Health(config, keys, link, "test-source")
            health_holder.append(health)
            assert wait_for(lambda: link.status().connected)
            assert wait_for_subscribers(link, ("support",))  # one CI run lost the first frames
            publisher = BusPublisher(keys.vehicle_id, link)
            pipeline = Pipeline.from_config(config, ScriptedDetector([40.0] * 5))
            pipeline.run(ListSource(5), [health, publisher])
            arrived = wait_for(lambda: len(received) >= 5, timeout_s=10.0)
            status = link.status()
            assert arrived, (len(received), status.support_sent, status.support_not_sent)
            assert status.support_sent == 5
            with client(port) as asker:
                replies = list(asker.get(keys.state, timeout=5.0))
        subscriber.undeclare()
    schema = json_schemas()["support"]
    messages = []
    for payload in received:
        document = json.loads(payload)
        jsonschema.validate(document, schema)
        messages.append(SupportMessage.model_validate(document))
    assert [m.seq for m in messages] == [0, 1, 2, 3, 4]
    assert all(m.vehicle_id == "test-car" for m in messages)
    assert all(m.forward.level == m.lane.level == "heightened" for m in messages)
    answers = [reply.ok for reply in replies if reply.ok is not None]
    state = StateMessage.model_validate(json.loads(answers[0].payload.to_bytes()))
    assert state.monitor.support_forward == messages[-1].forward
    assert state.monitor.support_lane == messages[-1].lane
    assert state.transport.support_sent == 5
