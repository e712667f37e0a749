"""Zenoh transport on real sessions over 127.0.0.1 (multicast off, free ports, timeouts)."""

from __future__ import annotations

import json
import logging
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import jsonschema
import pytest
import zenoh
from zenoh.ext import HistoryConfig, declare_advanced_subscriber

from fakes import ListSource, ScriptedDetector, alert_message, yaw_message
from repo_paths import child_env
from roadgaze.config import Config, ZenohConfig
from roadgaze.errors import ConfigError, TransportError
from roadgaze.pipeline import Pipeline
from roadgaze.transport import (
    BusPublisher,
    Health,
    Keys,
    SpeedInput,
    StateMessage,
    ZenohLink,
    build_zenoh_config,
    json_schemas,
    plan_session,
)
from zenoh_helpers import (
    LineReader,
    client,
    endpoint,
    free_port,
    router,
    stop_process,
    wait_for,
)

SCHEMAS = json_schemas()


def link_config(port: int, **extra: Any) -> ZenohConfig:
    settings: dict[str, Any] = {
        "vehicle_id": "test-car",
        "connect": [endpoint(port)],
    }
    return ZenohConfig.model_validate(settings | extra)


def test_keys_of_one_vehicle_and_of_all() -> None:
    config = ZenohConfig()
    keys = Keys.from_config(config, "car-7")
    assert (keys.yaw, keys.alert, keys.alive, keys.state, keys.speed) == (
        "vehicle/car-7/dms/yaw",
        "vehicle/car-7/dms/alert",
        "vehicle/car-7/dms/alive",
        "vehicle/car-7/dms/state",
        "vehicle/car-7/speed",
    )
    assert keys.advanced == "vehicle/car-7/dms/*/@adv/**"
    assert Keys.from_config(config.model_copy(update={"speed_key": ""})).speed is None
    assert Keys.matching(config, None).alert == "vehicle/*/dms/alert"
    assert Keys.matching(config, "*").state == "vehicle/*/dms/state"


@pytest.mark.parametrize("vehicle_id", ["*", "", "**", "a/b", "car 1", "$*", "car.1", "x" * 65])
def test_a_daemon_refuses_vehicle_ids_that_are_not_one_vehicle(vehicle_id: str) -> None:
    with pytest.raises(ConfigError, match="vehicle id must be 1-64"):
        Keys.from_config(ZenohConfig(), vehicle_id)


def test_bad_session_settings_are_one_line_errors(tmp_path: Path) -> None:
    with pytest.raises(TransportError, match="client needs a router"):
        build_zenoh_config(plan_session(ZenohConfig(mode="client", rendezvous="")))
    with pytest.raises(TransportError, match="not found"):
        build_zenoh_config(plan_session(ZenohConfig(config_file=tmp_path / "missing.json5")))
    with pytest.raises(TransportError, match="bad zenoh configuration"):
        build_zenoh_config(plan_session(ZenohConfig(connect=["nonsense"])))


def test_config_file_is_the_base_and_explicit_fields_override(tmp_path: Path) -> None:
    path = tmp_path / "zenoh.json5"
    path.write_text(
        '{ mode: "peer", listen: { endpoints: [] }, '
        'connect: { endpoints: ["tcp/127.0.0.1:7999"] } }'
    )
    config = ZenohConfig.model_validate({"config_file": path, "multicast_scouting": False})
    plan = plan_session(config, probe=lambda endpoint: pytest.fail("no rendezvous with a file"))
    assert plan.settings == {"scouting/multicast/enabled": False}
    _, resolved = build_zenoh_config(plan)  # parses; endpoints read back from the file
    assert (resolved.mode, resolved.connect, resolved.listen) == (
        "peer",
        ("tcp/127.0.0.1:7999",),
        (),
    )


def test_schemas_validate_the_messages() -> None:
    jsonschema.validate(json.loads(yaw_message(3).to_json_bytes()), SCHEMAS["yaw"])
    alert = json.loads(alert_message().to_json_bytes())
    jsonschema.validate(alert, SCHEMAS["alert"])
    assert alert["schema"] == "roadgaze.alert/4"
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(alert | {"kind": "sneeze"}, SCHEMAS["alert"])


def test_subscriber_in_another_process_receives_valid_yaw_and_alert() -> None:
    port = free_port()
    with router(port):
        listener = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "roadgaze",
                "listen",
                "--json",
                "--vehicle-id",
                "test-car",
                "--zenoh-connect",
                endpoint(port),
                "--timeout",
                "30",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=child_env(),
        )
        try:
            reader = LineReader(listener)
            with ZenohLink(link_config(port), Keys.from_config(link_config(port))) as link:
                first = reader.next(20.0)
                assert first is not None, "listener printed nothing"
                assert json.loads(first)["type"] == "alive"
                assert json.loads(first)["payload"] == {"alive": True}
                received: list[dict[str, Any]] = []
                for seq in range(100):  # until the yaw subscription has propagated
                    link.publish_yaw(yaw_message(seq))
                    line = reader.next(0.1)
                    if line is not None:
                        received.append(json.loads(line))
                        break
                assert received and received[0]["type"] == "yaw"
                link.publish_alert(alert_message(0))
                for _ in range(50):
                    line = reader.next(5.0)
                    assert line is not None, "no alert received"
                    record = json.loads(line)
                    if record["type"] == "alert":
                        received.append(record)
                        break
            gone = reader.next(10.0)
            while gone is not None and json.loads(gone)["type"] != "alive":
                gone = reader.next(10.0)
            listener.terminate()  # SIGTERM: a clean stop, exit 0
            code = listener.wait(timeout=10)
        finally:
            stop_process(listener)
    assert code == 0
    yaw, alert = received[0]["payload"], received[-1]["payload"]
    jsonschema.validate(yaw, SCHEMAS["yaw"])
    jsonschema.validate(alert, SCHEMAS["alert"])
    assert yaw["schema"] == "roadgaze.yaw/3" and yaw["vehicle_id"] == "test-car"
    assert alert["kind"] == "long_distraction" and alert["off_road_s"] == 3.0
    assert received[-1]["key"] == "vehicle/test-car/dms/alert"
    assert gone is not None and json.loads(gone)["payload"] == {"alive": False}


def test_liveliness_token_goes_away_when_the_link_closes() -> None:
    port = free_port()
    config = link_config(port)
    keys = Keys.from_config(config)
    events: list[str] = []
    with router(port) as hub:
        subscriber = hub.liveliness().declare_subscriber(
            keys.alive,
            lambda sample: events.append(
                "PUT" if sample.kind == zenoh.SampleKind.PUT else "DELETE"
            ),
            history=True,
        )
        link = ZenohLink(config, keys)
        link.start()
        try:
            assert wait_for(lambda: events == ["PUT"])
        finally:
            link.close()
        assert wait_for(lambda: events == ["PUT", "DELETE"])
        subscriber.undeclare()


def test_state_query_answers_the_current_state() -> None:
    port = free_port()
    config = Config(zenoh=link_config(port))
    keys = Keys.from_config(config.zenoh)
    health_holder: list[Health] = []
    with (
        router(port),
        ZenohLink(config.zenoh, keys, state_reply=lambda: health_holder[0].state_json()) as link,
    ):
        health = Health(config, keys, link, "test-source")
        health_holder.append(health)
        publisher = BusPublisher(keys.vehicle_id, link)
        pipeline = Pipeline.from_config(config, ScriptedDetector([40.0] * 5))
        assert wait_for(lambda: link.status().connected)
        pipeline.run(ListSource(5), [health, publisher])
        with client(port) as asker:
            replies = list(asker.get(keys.state, timeout=5.0))
    answers = [reply.ok for reply in replies if reply.ok is not None]
    assert len(answers) == 1
    assert answers[0].encoding == zenoh.Encoding.APPLICATION_JSON
    document = json.loads(answers[0].payload.to_bytes())
    jsonschema.validate(document, SCHEMAS["state"])
    state = StateMessage.model_validate(document)
    assert (state.status, state.frames, state.faces) == ("running", 5, 5)
    assert state.monitor.gaze == "off_road" and state.monitor.on_road is False
    assert state.monitor.off_road_s == pytest.approx(4 / 30)
    assert state.transport.yaw_sent == 5 and state.transport.connected
    assert (state.transport.routers, state.transport.connect) == (1, [endpoint(port)])
    assert state.transport.alert_cache_size == 100 and state.transport.listen == []
    assert state.config["monitor"]["long_distraction_s"] == 3.0
    assert state.config["keys"]["alert"] == "vehicle/test-car/dms/alert"


def test_speed_input_from_zenoh() -> None:
    port = free_port()
    config = link_config(port)
    keys = Keys.from_config(config)
    speed = SpeedInput(timeout_s=5.0)
    with router(port) as hub, ZenohLink(config, keys, speed=speed):
        assert keys.speed == "vehicle/test-car/speed"
        for _ in range(100):  # until the speed subscription has propagated
            hub.put(keys.speed, b'{"kmh": 57.5}')
            if speed.kmh() is not None:  # the frame loop takes the newest payload
                break
            time.sleep(0.1)
        assert speed.current() == (57.5, "fresh")

        def taken(payload: bytes) -> bool:
            hub.put(keys.speed, payload)
            time.sleep(0.05)
            speed.kmh()
            return True

        taken(b"not a speed")
        assert speed.rejected == 1 and speed.current() == (None, "invalid")  # fail-safe
        taken(b"x" * 10_000)
        assert speed.oversize == 1 and speed.current() == (None, "invalid")
        taken(b"12")
        assert speed.current() == (12.0, "fresh")


def test_unreachable_router_degrades_then_recovers_and_delivers_kept_alerts(
    caplog: pytest.LogCaptureFixture,
) -> None:
    port = free_port()
    config = link_config(port, mode="client")
    keys = Keys.from_config(config)
    link = ZenohLink(config, keys, state_reply=lambda: b"{}")
    try:
        link.start()  # nothing listens on the port: must not raise
        status = link.status()
        assert not status.session_open and not status.connected
        with caplog.at_level(logging.WARNING, logger="roadgaze.transport.link"):
            link.publish_final_state()  # no session to put it on: said, not silently skipped
        assert "final state not published: no zenoh session" in caplog.text
        link.publish_yaw(yaw_message(0))
        link.publish_alert(alert_message(0))
        assert link.status().pending_alerts == 1 and link.status().not_sent == 1
        received: list[bytes] = []
        with router(port) as hub:
            subscriber = declare_advanced_subscriber(
                hub,
                keys.alert,
                lambda sample: received.append(sample.payload.to_bytes()),
                history=HistoryConfig(detect_late_publishers=True),
            )
            assert wait_for(lambda: link.status().connected, timeout_s=15.0)
            assert wait_for(lambda: len(received) == 1, timeout_s=5.0)
            subscriber.undeclare()
        assert json.loads(received[0])["kind"] == "long_distraction"
        assert link.status().pending_alerts == 0 and link.status().session_reopens >= 1
    finally:
        link.close()


def test_peer_gone_is_reported_and_publishing_goes_on() -> None:
    port = free_port()
    config = link_config(port)
    keys = Keys.from_config(config)
    with ZenohLink(config, keys) as link:
        with router(port):
            assert wait_for(lambda: link.status().connected, timeout_s=15.0)
        assert wait_for(lambda: not link.status().connected, timeout_s=10.0)
        link.publish_yaw(yaw_message(1))
        link.publish_alert(alert_message(1))
        assert link.status().session_open
        with router(port):
            assert wait_for(lambda: link.status().connected, timeout_s=15.0)
