"""Access control: the files of `roadgaze security init` on a TLS router in a child process.

One bundle and one router serve the module (each TLS session costs a handshake); every check
is a role doing what it may, or an attack the router must stop.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import zenoh

from fakes import BLANK_FRAME, alert_message, record_of
from repo_paths import child_env
from roadgaze.config import Config, ZenohConfig
from roadgaze.errors import ConfigError
from roadgaze.security import init_bundle
from roadgaze.transport import (
    VSS_PATHS,
    Health,
    Keys,
    SpeedInput,
    StateMessage,
    ZenohLink,
    vss_key,
)
from roadgaze.types import PoseSample
from zenoh_helpers import AdvancedListener, RouterProcess, free_port, router, wait_for

VEHICLE = "car-1"


def role_config(bundle: dict[str, Path], role: str, **patch: Any) -> zenoh.Config:
    settings = json.loads(bundle[role].read_text())
    for path, value in patch.items():
        cursor = settings
        *parents, last = path.split("__")
        for part in parents:
            cursor = cursor.setdefault(part, {})
        cursor[last] = value
    return zenoh.Config.from_json5(json.dumps(settings))


@pytest.fixture(scope="module")
def secured(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[dict[str, Path], int]]:
    port = free_port()
    folder = tmp_path_factory.mktemp("bundle")
    keys = Keys.from_config(ZenohConfig(), VEHICLE)
    bundle = init_bundle(folder, keys, ["fcw", "logger"], f"tls/127.0.0.1:{port}")
    with RouterProcess(port, config_file=str(bundle["router"])):
        yield bundle, port


@pytest.fixture(scope="module")
def daemon(secured: tuple[dict[str, Path], int]) -> Iterator[tuple[ZenohLink, SpeedInput]]:
    bundle, _ = secured
    config = Config(
        zenoh=ZenohConfig(vehicle_id=VEHICLE, config_file=bundle["daemon"], speed_timeout_s=30.0)
    )
    keys = Keys.from_config(config.zenoh)
    speed = SpeedInput(config.zenoh.speed_timeout_s)
    holder: list[Health] = []
    link = ZenohLink(
        config.zenoh,
        keys,
        state_reply=lambda: holder[0].state_json(),
        speed=speed,
        vss_keys=tuple(vss_key(path) for path in VSS_PATHS),
    )
    health = Health(config, keys, link, "test")
    holder.append(health)
    health.on_record(record_of(PoseSample(0.0, 0, True, 0.0, 0.0, 0.0, 1.0)), BLANK_FRAME)
    with link:
        assert wait_for(lambda: link.status().connected, timeout_s=15.0)
        yield link, speed


def test_bundle_files_are_private_and_refuse_bad_input(
    secured: tuple[dict[str, Path], int], tmp_path: Path
) -> None:
    bundle, port = secured
    folder = bundle["router"].parent.parent
    assert (folder / "ca" / "ca.key").stat().st_mode & 0o777 == 0o600
    assert (folder / "daemon" / "key.pem").stat().st_mode & 0o777 == 0o600
    router_conf = json.loads(bundle["router"].read_text())
    assert router_conf["transport"]["link"]["protocols"] == ["tls"]
    assert router_conf["transport"]["shared_memory"] == {"enabled": False}
    acl = router_conf["access_control"]
    assert acl["default_permission"] == "deny"
    assert {s["id"]: s["cert_common_names"] for s in acl["subjects"]}["consumer-subject"] == [
        "consumer.fcw.car-1",
        "consumer.logger.car-1",
    ]
    assert "vehicle/car-1/dms/*/@adv/**" in acl["rules"][0]["key_exprs"]
    keys = Keys.from_config(ZenohConfig(), VEHICLE)
    with pytest.raises(ConfigError, match="not empty"):
        init_bundle(folder, keys, ["fcw"], f"tls/127.0.0.1:{port}")
    with pytest.raises(ConfigError, match="tls/HOST:PORT"):
        init_bundle(tmp_path / "new", keys, ["fcw"], "tcp/127.0.0.1:7447")
    with pytest.raises(ConfigError, match="consumer name"):
        init_bundle(tmp_path / "new", keys, ["a/b"])
    assert not (tmp_path / "new").exists()  # refused before anything is written


def test_each_role_does_what_it_may(
    secured: tuple[dict[str, Path], int], daemon: tuple[ZenohLink, SpeedInput]
) -> None:
    bundle, port = secured
    link, speed = daemon
    with (
        zenoh.open(role_config(bundle, "speed")) as provider,
        zenoh.open(role_config(bundle, "consumer-fcw")) as fcw,
    ):
        listener = AdvancedListener(fcw, link.keys.alert)
        time.sleep(0.5)
        link.publish_alert(alert_message(0, VEHICLE))
        assert wait_for(lambda: listener.seqs() == [0], timeout_s=10.0)
        # The router lets the consumer's subscription reach the daemon: its matching status,
        # hence its alert ledger, sees the FCW, and counts the alert delivered.
        assert link.link_state.ever_matched
        assert wait_for(lambda: link.status().alerts_waiting == 0, timeout_s=10.0)

        def speed_arrives() -> bool:
            provider.put(link.keys.speed, b'{"kmh": 50}')
            time.sleep(0.1)
            return speed.kmh() == 50.0

        assert wait_for(speed_arrives, timeout_s=10.0, every_s=0.1)
        replies = list(
            fcw.get(link.keys.state, timeout=5.0, consolidation=zenoh.ConsolidationMode.NONE)
        )
        states = [
            StateMessage.model_validate_json(reply.ok.payload.to_bytes())
            for reply in replies
            if reply.ok is not None
        ]
        assert [state.status for state in states] == ["running"]
        assert states[0].transport.connect == [f"tls/127.0.0.1:{port}"]
        assert states[0].transport.mode == "peer" and states[0].transport.listen == []
        listener.close()


def test_attacks_by_a_consumer_are_stopped_by_the_router(
    secured: tuple[dict[str, Path], int], daemon: tuple[ZenohLink, SpeedInput]
) -> None:
    bundle, _ = secured
    link, speed = daemon
    keys = link.keys
    with (
        zenoh.open(role_config(bundle, "speed")) as provider,
        zenoh.open(role_config(bundle, "consumer-fcw")) as fcw,
        zenoh.open(role_config(bundle, "consumer-logger")) as attacker,
    ):
        listener = AdvancedListener(fcw, keys.alert)
        rogue = attacker.declare_queryable(
            keys.state, lambda query: query.reply(keys.state, b'{"status": "running"}')
        )
        time.sleep(0.5)
        provider.put(keys.speed, b'{"kmh": 50}')
        assert wait_for(lambda: speed.kmh() == 50.0, timeout_s=10.0)
        block = zenoh.CongestionControl.BLOCK  # not lost to a busy machine: denied
        for _ in range(5):  # forged speed, forged alert, forged heartbeat
            attacker.put(keys.speed, b'{"kmh": 0}', congestion_control=block)
            forged = alert_message(99, VEHICLE).to_json_bytes()
            attacker.put(keys.alert, forged, congestion_control=block)
            heartbeat = f"{keys.alert}/@adv/pub/1/1/_"
            attacker.put(heartbeat, b"\x63\x00\x00\x00", congestion_control=block)
            time.sleep(0.1)
        time.sleep(0.5)
        assert speed.kmh() == 50.0  # the consumer's 0 km/h never reached the daemon
        assert 99 not in listener.seqs()
        replies = list(fcw.get(keys.state, timeout=3.0, consolidation=zenoh.ConsolidationMode.NONE))
        answers = [r.ok.payload.to_bytes() for r in replies if r.ok is not None]
        assert len(answers) == 1 and StateMessage.model_validate_json(answers[0]).uptime_s > 0
        sniffer: list[str] = []
        wide = attacker.declare_subscriber("vehicle/**", lambda s: sniffer.append(str(s.key_expr)))
        link.publish_alert(alert_message(1, VEHICLE))
        assert wait_for(lambda: 1 in listener.seqs(), timeout_s=5.0)
        time.sleep(0.3)
        assert sniffer == []  # a subscription wider than its vehicle gets nothing
        wide.undeclare()
        rogue.undeclare()
        listener.close()


def test_only_the_daemon_may_put_vss_signals_and_consumers_receive_them(
    secured: tuple[dict[str, Path], int], daemon: tuple[ZenohLink, SpeedInput]
) -> None:
    bundle, _ = secured
    link, _ = daemon
    key = vss_key("Vehicle.Driver.IsEyesOnRoad")
    router_conf = json.loads(bundle["router"].read_text())
    rules = {rule["id"]: rule for rule in router_conf["access_control"]["rules"]}
    assert rules["daemon-vss"]["key_exprs"] == ["Vehicle/**"]
    assert rules["consumer-vss-ask"]["messages"] == ["declare_subscriber"]
    with (
        zenoh.open(role_config(bundle, "consumer-fcw")) as fcw,
        zenoh.open(role_config(bundle, "consumer-logger")) as attacker,
    ):
        received: list[tuple[str, bytes]] = []
        subscriber = fcw.declare_subscriber(
            "Vehicle/**", lambda s: received.append((str(s.key_expr), s.payload.to_bytes()))
        )

        def daemon_value_arrives() -> bool:
            link.publish_vss(key, b"false")
            time.sleep(0.1)
            return (key, b"false") in received

        assert wait_for(daemon_value_arrives, timeout_s=10.0, every_s=0.1)
        block = zenoh.CongestionControl.BLOCK
        for _ in range(5):  # a forged "eyes on the road" and an oversized value
            attacker.put(key, b"true", congestion_control=block)
            link.publish_vss(key, b"1" * 300)
            time.sleep(0.1)
        link.publish_vss(key, b"false")
        time.sleep(0.5)
        values = {payload for found, payload in received if found == key}
        assert values == {b"false"}  # neither the forgery nor the oversized put got through
        subscriber.undeclare()


@pytest.mark.parametrize(
    ("what", "patch"),
    [
        ("no certificate", {"transport__link__tls": {"root_ca_certificate": "CA"}}),
        ("mutual TLS off", {"transport__link__tls__enable_mtls": False}),
        ("plain TCP on the TLS port", {"transport__link__protocols": ["tcp"]}),
    ],
)
def test_clients_without_a_valid_certificate_are_refused(
    secured: tuple[dict[str, Path], int], what: str, patch: dict[str, Any]
) -> None:
    bundle, port = secured
    ca = str(bundle["consumer-fcw"].parent / "ca.pem")
    patch = {k: ({"root_ca_certificate": ca} if v == {"root_ca_certificate": "CA"} else v)
             for k, v in patch.items()}  # fmt: skip
    if what == "plain TCP on the TLS port":
        patch["connect__endpoints"] = [f"tcp/127.0.0.1:{port}"]
    zenoh.open(role_config(bundle, "consumer-fcw")).close()  # the same file, unchanged, opens
    with pytest.raises(zenoh.ZError):
        zenoh.open(role_config(bundle, "consumer-fcw", **patch)).close()


def test_a_certificate_from_another_ca_is_refused(
    secured: tuple[dict[str, Path], int], tmp_path: Path
) -> None:
    bundle, port = secured
    keys = Keys.from_config(ZenohConfig(), VEHICLE)
    other = init_bundle(tmp_path / "other", keys, ["fcw"], f"tls/127.0.0.1:{port}")
    settings = json.loads(other["consumer-fcw"].read_text())
    settings["transport"]["link"]["tls"]["root_ca_certificate"] = str(
        bundle["consumer-fcw"].parent / "ca.pem"
    )  # trusts the real router, presents a certificate the router does not trust
    with pytest.raises(zenoh.ZError):
        zenoh.open(zenoh.Config.from_json5(json.dumps(settings))).close()


def test_listen_with_a_consumer_file_checks_the_state(
    secured: tuple[dict[str, Path], int], daemon: tuple[ZenohLink, SpeedInput]
) -> None:
    bundle, _ = secured
    result = subprocess.run(
        [sys.executable, "-m", "roadgaze", "listen", "--query-state", "--vehicle-id", VEHICLE,
         "--zenoh-config", str(bundle["consumer-fcw"]), "--timeout", "10"],
        capture_output=True, text=True, timeout=60, env=child_env(), check=False,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "state  car-1 status=running" in result.stdout


def test_without_access_control_a_spoofed_speed_in_range_is_taken(
    tmp_path: Path,
) -> None:
    """The open development bus: what the router's access control is for (docs/security.md).

    A speed within 0-400 km/h from anyone is believed; an absurd one is refused and makes the
    speed unknown (moving)."""
    port = free_port()
    config = ZenohConfig(vehicle_id=VEHICLE, connect=[f"tcp/127.0.0.1:{port}"])
    keys = Keys.from_config(config)
    speed = SpeedInput()
    with router(port) as anyone, ZenohLink(config, keys, speed=speed):

        def spoofed() -> bool:
            anyone.put(keys.speed, b'{"kmh": 0}')
            time.sleep(0.1)
            return speed.kmh() == 0.0

        assert wait_for(spoofed, timeout_s=10.0, every_s=0.1)
        anyone.put(keys.speed, b'{"kmh": 1e308}')
        time.sleep(0.2)
        assert speed.kmh() is None and speed.current()[1] == "invalid"


def test_roadgaze_speed_publishes_with_the_speed_providers_file(
    secured: tuple[dict[str, Path], int], daemon: tuple[ZenohLink, SpeedInput]
) -> None:
    bundle, _ = secured
    _, speed = daemon
    provider = subprocess.Popen(
        [sys.executable, "-m", "roadgaze", "speed", "--kmh", "42.5", "--duration", "20",
         "--vehicle-id", VEHICLE, "--zenoh-config", str(bundle["speed"])],
        stderr=subprocess.PIPE, text=True, env=child_env(),
    )  # fmt: skip
    try:
        assert wait_for(lambda: speed.kmh() == 42.5, timeout_s=15.0, every_s=0.1)
    finally:
        provider.terminate()
        _, err = provider.communicate(timeout=30)
    assert provider.returncode == 0, err
    assert "speeds published, the last 42.5 km/h" in err and "Traceback" not in err
