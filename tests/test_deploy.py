"""deploy/roadgaze.service: `systemd-analyze verify` says nothing about it (it exits 0 even on bad
values, so its output is what counts), its hardening keeps the exposure score low, and the
supervision settings are the ones the daemon implements."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest

from repo_paths import REPO

UNIT = REPO / "deploy" / "roadgaze.service"
INSTALLED_BINARY = "/opt/roadgaze/venv/bin/roadgaze"

needs_systemd_analyze = pytest.mark.skipif(
    shutil.which("systemd-analyze") is None, reason="systemd-analyze is not installed"
)


def unit_settings(text: str) -> dict[str, list[str]]:
    """`Key=value` lines of a unit (every value of a repeated key), comments skipped."""
    settings: dict[str, list[str]] = {}
    for line in text.splitlines():
        if line and not line.startswith(("#", ";", "[")) and "=" in line:
            key, value = line.split("=", 1)
            settings.setdefault(key.strip(), []).append(value.strip())
    return settings


def verify(unit_text: str, folder: Path) -> subprocess.CompletedProcess[str]:
    """`systemd-analyze verify` on the unit, its ExecStart binary replaced by an executable stub
    in `folder` (the real one is only on an installed machine); every other line is as written."""
    stub = folder / "roadgaze"
    stub.write_text("#!/bin/sh\n", encoding="utf-8")
    stub.chmod(0o755)
    assert INSTALLED_BINARY in unit_text
    path = folder / "roadgaze.service"
    path.write_text(unit_text.replace(INSTALLED_BINARY, str(stub)), encoding="utf-8")
    return subprocess.run(
        ["systemd-analyze", "verify", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )


@needs_systemd_analyze
def test_systemd_analyze_verify_says_nothing_about_the_unit(tmp_path: Path) -> None:
    result = verify(UNIT.read_text(encoding="utf-8"), tmp_path)
    assert (result.returncode, result.stdout + result.stderr) == (0, "")


@needs_systemd_analyze
def test_the_verify_check_catches_a_bad_value(tmp_path: Path) -> None:
    """The control: a typo exits 0 too, but is reported; the test above would fail on it."""
    broken = UNIT.read_text(encoding="utf-8").replace("Type=notify", "Type=notfy")
    result = verify(broken, tmp_path)
    assert "Failed to parse service type" in result.stdout + result.stderr


@needs_systemd_analyze
def test_the_hardening_keeps_the_exposure_score_at_most_2(tmp_path: Path) -> None:
    shutil.copy(UNIT, tmp_path / "roadgaze.service")
    result = subprocess.run(
        ["systemd-analyze", "security", "--offline=true", "roadgaze.service"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    if "--offline" in result.stderr:
        pytest.skip(f"this systemd-analyze has no --offline: {result.stderr.strip()}")
    match = re.search(
        r"Overall exposure level for roadgaze\.service: ([0-9.]+) (\w+)", result.stdout
    )
    assert match is not None, result.stdout[-2000:] + result.stderr
    print(f"systemd-analyze security: {match.group(1)} {match.group(2)}")
    assert float(match.group(1)) <= 2.0 and match.group(2) == "OK"


def test_the_unit_asks_for_what_the_daemon_implements() -> None:
    settings = unit_settings(UNIT.read_text(encoding="utf-8"))
    assert settings["Type"] == ["notify"] and settings["NotifyAccess"] == ["main"]
    assert settings["ExecStart"][0].startswith(f"{INSTALLED_BINARY} run --source ")
    assert settings["KillSignal"] == ["SIGTERM"]
    assert settings["WatchdogSec"] == ["20s"] and settings["TimeoutStartSec"] == ["90s"]
    assert settings["RestartPreventExitStatus"] == ["2"]  # configuration errors: no restart loop
    for hardening in ("ProtectSystem", "PrivateTmp", "NoNewPrivileges", "DevicePolicy"):
        assert hardening in settings
    assert settings["DeviceAllow"] == ["/dev/video0 rw"]


# --- docker/compose.yaml on the files of `roadgaze security init` ------------------------------

COMPOSE = REPO / "docker" / "compose.yaml"
MOUNT_ROOT = Path("/etc/roadgaze/zenoh")


def _zenoh_files(service: dict[str, Any]) -> list[str]:
    """The Zenoh files a service is told to use: --zenoh-config and ROADGAZE__ZENOH__CONFIG_FILE."""
    command = service.get("command", [])
    files = [command[i + 1] for i, arg in enumerate(command) if arg == "--zenoh-config"]
    config_file = service.get("environment", {}).get("ROADGAZE__ZENOH__CONFIG_FILE")
    return files + ([config_file] if config_file else [])


def _paths_in(value: Any) -> list[str]:
    """Every string under MOUNT_ROOT in a JSON document (certificates, keys, CA)."""
    if isinstance(value, dict):
        return [path for item in value.values() for path in _paths_in(item)]
    if isinstance(value, list):
        return [path for item in value for path in _paths_in(item)]
    return [value] if isinstance(value, str) and value.startswith(f"{MOUNT_ROOT}/") else []


def test_compose_runs_roadgaze_router_and_every_role_on_its_mounted_bundle_files(
    tmp_path: Path,
) -> None:
    """Made as the compose header says, the bundle's files are all where each service looks:
    every Zenoh file a service names, and every certificate and key those name, is inside a
    folder mounted into that service; the router listens where its port is published, and no
    environment variable overrides the files' sessions."""
    yaml = pytest.importorskip("yaml", reason="PyYAML is needed to read the compose file")
    from roadgaze.config import ZenohConfig
    from roadgaze.security import init_bundle
    from roadgaze.transport import Keys

    header = COMPOSE.read_text(encoding="utf-8")
    words = " ".join(header.replace("#", " ").replace("\\", " ").split())
    assert (
        "security init /out/bundle --vehicle-id car-0 --consumer listener --consumer health "
        "--endpoint tls/router:7447 --listen tls/0.0.0.0:7447 --path-root /etc/roadgaze/zenoh"
    ) in words
    bundle = tmp_path / "zenoh"
    init_bundle(
        bundle,
        Keys.from_config(ZenohConfig(), "car-0"),
        ["listener", "health"],
        endpoint="tls/router:7447",
        listen="tls/0.0.0.0:7447",
        path_root=MOUNT_ROOT,
    )
    services = yaml.safe_load(header)["services"]
    assert services["router"]["command"] == [
        "router", "--zenoh-config", f"{MOUNT_ROOT}/router/zenoh.json5"
    ]  # fmt: skip
    assert services["router"]["ports"] == ["127.0.0.1:7447:7447"]
    checked = 0
    for name, service in services.items():
        environment = service.get("environment", {})
        assert not {"ROADGAZE__ZENOH__CONNECT", "ROADGAZE__ZENOH__MODE"} & set(environment), name
        mounts = {}
        for volume in service.get("volumes", []):
            host, container = volume.split(":")[:2]
            if host.startswith("./zenoh/"):
                mounts[Path(container)] = bundle / host.removeprefix("./zenoh/")
        files = _zenoh_files(service)
        assert files, f"{name} names no Zenoh file"
        for file in files:
            settings = json.loads(_on_host(Path(file), mounts, name).read_text(encoding="utf-8"))
            for path in _paths_in(settings):
                assert _on_host(Path(path), mounts, name).is_file(), (name, path)
                checked += 1
    assert checked >= 4 * 3  # router, daemon, listener and health: CA, certificate and key each
    router = json.loads((bundle / "router" / "zenoh.json5").read_text(encoding="utf-8"))
    assert router["listen"]["endpoints"] == ["tls/0.0.0.0:7447"]
    assert router["access_control"]["enabled"] is True


def _on_host(path: Path, mounts: dict[Path, Path], service: str) -> Path:
    """Where a path inside a service's container is on the host (via its mounts)."""
    for inside, outside in mounts.items():
        if path.is_relative_to(inside):
            return outside / path.relative_to(inside)
    raise AssertionError(f"{service}: {path} is in no mounted folder ({sorted(map(str, mounts))})")
