"""deploy/roadgaze.service: `systemd-analyze verify` says nothing about it (it exits 0 even on bad
values, so its output is what counts), its hardening keeps the exposure score low, and the
supervision settings are the ones the daemon implements."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

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


def install_steps(unit_text: str) -> list[str]:
    """The command lines of the unit header's install steps, in order."""
    header = unit_text.split("# Install, as root, in this order:")[1].split("\n#\n")[0]
    return [line[4:] for line in header.splitlines() if line.startswith("#   ")]


def test_the_install_steps_create_what_the_unit_and_the_fetch_need() -> None:
    text = UNIT.read_text(encoding="utf-8")
    settings = unit_settings(text)
    steps = install_steps(text)
    index = {
        name: next(i for i, step in enumerate(steps) if needle in step)
        for name, needle in (
            ("clone", "git clone"),
            ("user", "useradd"),
            ("cache", "install -d -o roadgaze -g roadgaze -m 0750 /var/cache/roadgaze"),
            ("fetch", "roadgaze model fetch"),
            ("enable", "systemctl enable"),
        )
    }
    # The fetch runs as `roadgaze` before the service ever started, so before CacheDirectory=
    # made /var/cache/roadgaze: the folder is made for it, with the unit's owner and mode.
    assert index["user"] < index["cache"] < index["fetch"] < index["enable"]
    assert settings["CacheDirectory"] == ["roadgaze"] and settings["CacheDirectoryMode"] == ["0750"]
    assert "ROADGAZE_CACHE_DIR=/var/cache/roadgaze" in steps[index["fetch"]]
    # Documentation= names a file the steps put there: the clone's docs/deployment.md.
    (documentation,) = settings["Documentation"]
    clone_dir = steps[index["clone"]].split("#")[0].split()[-1]
    assert documentation.startswith(f"file://{clone_dir}/")
    assert (REPO / documentation.removeprefix(f"file://{clone_dir}/")).is_file()


def store_conf(tmp_path: Path, **env: str) -> str:
    """What `roadgaze_podman_store` exports, for a given environment ('' when nothing)."""
    script = f'source "{REPO}/docker/podman-store.sh"; roadgaze_podman_store; '
    script += 'printf %s "${CONTAINERS_STORAGE_CONF:-}"'
    clean = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "ROADGAZE_STORE": str(tmp_path)}
    result = subprocess.run(
        ["bash", "-c", script], env=clean | env, capture_output=True, text=True, check=True
    )
    return result.stdout


def test_the_container_scripts_use_a_podman_store_of_their_own(tmp_path: Path) -> None:
    """A default store used before with another driver refuses --storage-driver vfs, so the
    scripts name a private store (driver, graphroot, runroot) instead of passing the flag."""
    conf = store_conf(tmp_path)
    assert conf == str(tmp_path / "storage.conf")
    text = Path(conf).read_text()
    assert 'driver = "vfs"' in text and f'graphroot = "{tmp_path}/storage-vfs"' in text
    assert "runroot = " in text
    assert store_conf(tmp_path, STORAGE_DRIVER="") == ""  # podman's default store
    assert store_conf(tmp_path, CONTAINERS_STORAGE_CONF="/etc/mine.conf") == "/etc/mine.conf"
    for script in ("smoke.sh", "offline-base.sh"):
        body = (REPO / "docker" / script).read_text()
        assert "roadgaze_podman_store" in body
        assert "+=(--storage-driver" not in body
    # The build stage's image is labelled, and smoke.sh removes what carries the label.
    assert "LABEL org.roadgaze.stage=build" in (REPO / "docker" / "Dockerfile").read_text()
    assert (
        "prune -f --filter label=org.roadgaze.stage=build"
        in (REPO / "docker" / "smoke.sh").read_text()
    )
