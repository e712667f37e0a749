"""docker/compose.yaml runs on the files `roadgaze security init` writes (issue 10, Deliver 2).

The bundle is made with the exact command the compose file's header documents; then every Zenoh
file a service is given (`--zenoh-config`, `ROADGAZE__ZENOH__CONFIG_FILE`, zenohd's `-c`) must be
a generated file inside a folder that service mounts, and so must every certificate and key that
file names; the router is `roadgaze router` on the router file (issue 15). No Docker needed: the
paths are checked as the containers would see them.
"""

from __future__ import annotations

import json
import shlex
from pathlib import Path
from typing import Any

import pytest
import yaml

from repo_paths import REPO
from roadgaze.cli import main

pytestmark = pytest.mark.usefixtures("restore_logging")

COMPOSE = REPO / "docker" / "compose.yaml"


def documented_init_command() -> list[str]:
    """The `roadgaze security init ...` command of the compose file's header comment."""
    lines = [line.lstrip("#").strip() for line in COMPOSE.read_text().splitlines()]
    start = next(i for i, line in enumerate(lines) if line.startswith("roadgaze security init"))
    words: list[str] = []
    for line in lines[start:]:
        words += shlex.split(line.rstrip("\\"))
        if not line.endswith("\\"):
            return words[1:]  # without the program name
    raise AssertionError("the init command in docker/compose.yaml does not end")


def mounts(service: dict[str, Any], docker: Path) -> dict[str, Path]:
    """Container folder -> host folder of a service's volumes (`docker`: the compose folder)."""
    result = {}
    for volume in service.get("volumes", []):
        host, container, *_ = volume.split(":")
        result[container] = docker / host
    return result


def on_host(container_path: str, service: dict[str, Any], docker: Path) -> Path:
    """Where a file a service reads in its container lies on the host; AssertionError if the
    service mounts no folder holding it."""
    for container, host in mounts(service, docker).items():
        if container_path.startswith(container + "/"):
            return host / container_path[len(container) + 1 :]
    raise AssertionError(f"{container_path} is in no folder the service mounts: {service}")


def pem_paths(settings: dict[str, Any]) -> list[str]:
    tls = settings["transport"]["link"]["tls"]
    return [value for key, value in tls.items() if key.endswith(("certificate", "private_key"))]


def zenoh_files(service: dict[str, Any]) -> list[str]:
    command = service.get("command", [])
    files = [command[i + 1] for i, word in enumerate(command) if word == "--zenoh-config"]
    if command[:1] == ["-c"]:
        files.append(command[1])
    environment = service.get("environment", {})
    if "ROADGAZE__ZENOH__CONFIG_FILE" in environment and "healthcheck" not in service:
        files.append(environment["ROADGAZE__ZENOH__CONFIG_FILE"])  # the image's health check
    return files


def test_compose_services_use_the_generated_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    command = documented_init_command()
    assert command[:2] == ["security", "init"]
    assert command[2] == "docker/zenoh"  # the folder the volumes name
    docker = tmp_path / "docker"  # the generated files as a checkout would hold them
    monkeypatch.chdir(tmp_path)
    assert main(command) == 0
    generated = docker / "zenoh"

    services = yaml.safe_load(COMPOSE.read_text())["services"]
    used: dict[str, str] = {}
    for name, service in services.items():
        for container_path in zenoh_files(service):
            host_file = on_host(container_path, service, docker)
            assert host_file.is_file(), f"{name}: {container_path} was not generated"
            settings = json.loads(host_file.read_text())
            for pem in pem_paths(settings):
                assert on_host(pem, service, docker).is_file(), f"{name}: {pem} missing"
            used[f"{name}:{container_path}"] = settings["mode"]

    assert used == {
        "router:/etc/roadgaze/zenoh/router/zenoh.json5": "router",
        "roadgaze:/etc/roadgaze/zenoh/daemon/zenoh.json5": "peer",
        "roadgaze:/etc/roadgaze/zenoh/consumer-health/zenoh.json5": "client",
        "listener:/etc/roadgaze/zenoh/consumer-listener/zenoh.json5": "client",
    }
    assert services["router"]["command"][:2] == ["router", "--zenoh-config"]  # roadgaze router
    assert services["router"]["ports"] == ["127.0.0.1:7447:7447"]  # the host: loopback only
    for name, service in services.items():  # the Zenoh files set the sessions
        overrides = {"ROADGAZE__ZENOH__CONNECT", "ROADGAZE__ZENOH__MODE"}
        assert not overrides & set(service.get("environment", {})), name
    router = json.loads((generated / "router" / "zenoh.json5").read_text())
    daemon = json.loads((generated / "daemon" / "zenoh.json5").read_text())
    assert router["listen"]["endpoints"] == ["tls/0.0.0.0:7447"]
    assert daemon["connect"]["endpoints"] == ["tls/router:7447"]
    assert router["transport"]["link"]["tls"]["enable_mtls"] is True
    assert "access_control" in router and router["access_control"]["enabled"] is True
