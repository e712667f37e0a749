"""Issue 24's items 6-9: each ends in one clear line and the documented exit code.

A bad `--zenoh-config` (JSON5 syntax, a folder), bad `security init` endpoints, a damaged model
file, a Ray address with nothing there (bounded wait), and two stop signals at any spacing
(a slow finaliser in the way, as MediaPipe's `FaceLandmarker.__del__` is).
"""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from repo_paths import child_env
from roadgaze.cli import main
from roadgaze.fleet.ray_connect import ray_head_endpoint
from zenoh_helpers import LineReader, endpoint, free_port, stop_process

FAKE_DAEMON = Path(__file__).resolve().parents[1] / "fake_daemon.py"


def error_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if "error" in line or "Traceback" in line]


@pytest.mark.parametrize(
    ("content", "says"),
    [
        ('{\n  mode: "peer",\n  connect: { endpoints: ["tcp/127.0.0.1:7447" }\n}\n', "line 3, "),
        (None, "is a folder; pass its zenoh.json5 file"),
    ],
    ids=["json5-syntax", "folder"],
)
def test_a_bad_zenoh_config_is_one_line_naming_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: str | None, says: str
) -> None:
    target = tmp_path / "zenoh.json5"
    if content is None:
        target.mkdir()
    else:
        target.write_text(content)
    for command in (["run", "--source", "/dev/video9"], ["listen", "--timeout", "1"]):
        assert main([*command, "--zenoh-config", str(target)]) == 2
        lines = error_lines(capsys.readouterr().err)
        assert len(lines) == 1 and str(target) in lines[0] and says in lines[0], lines


@pytest.mark.parametrize(
    ("option", "value", "says"),
    [
        ("--endpoint", "tls/127.0.0.1:99999", "port must be 1-65535"),
        ("--listen", "tls/[::1", "IPv6 address in brackets"),
        ("--endpoint", "tls/::1:7447", "IPv6 address in brackets"),
        ("--endpoint", "tls/bad host:7447", "not a host name"),
    ],
)
def test_security_init_refuses_endpoints_a_router_cannot_use(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], option: str, value: str, says: str
) -> None:
    out = tmp_path / "bundle"
    assert main(["security", "init", str(out), "--vehicle-id", "car-1", option, value]) == 2
    lines = error_lines(capsys.readouterr().err)
    assert len(lines) == 1 and says in lines[0] and option in lines[0]
    assert not out.exists()


def test_model_verify_on_a_damaged_file_exits_1(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    damaged = tmp_path / "face_landmarker.task"
    damaged.write_bytes(b"\0" * 1000)
    monkeypatch.setenv("ROADGAZE_MODEL_PATH", str(damaged))
    monkeypatch.setenv("ROADGAZE_CACHE_DIR", str(tmp_path / "cache"))
    assert main(["model", "verify"]) == 1
    assert f"explicit: {damaged}: size 1000 bytes" in capsys.readouterr().out


def test_batch_on_a_ray_address_with_nothing_there_fails_in_bounded_time(
    tmp_path: Path,
) -> None:
    """Ray's own connect retries for minutes (measured past 240 s): the head is probed first.
    The real command in a fresh process, with Ray installed and nothing at the address."""
    pytest.importorskip("ray", reason="Ray is the optional extra roadgaze[ray]")
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "drive.mkv").write_bytes(b"not a video")
    address = f"ray://127.0.0.1:{free_port()}"
    started = time.monotonic()
    done = subprocess.run(
        [
            *(sys.executable, "-m", "roadgaze", "batch", str(tmp_path / "in")),
            *("--out", str(tmp_path / "out"), "--engine", "ray", "--ray-address", address),
            *("--ray-timeout", "1", "--no-progress"),
        ],
        env=child_env(),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2, done.stderr[-2000:]
    assert f"no Ray cluster at {address}: nothing accepted" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert time.monotonic() - started < 60.0  # Ray's import included; its retries are minutes


def test_ray_head_endpoints() -> None:
    assert ray_head_endpoint("10.0.0.5:6379") == ("10.0.0.5", 6379)
    assert ray_head_endpoint("auto") is None


@pytest.mark.parametrize("spacing_s", [0.05, 0.6])
def test_a_second_signal_exits_1_without_a_traceback_at_any_spacing(spacing_s: float) -> None:
    process = subprocess.Popen(
        [sys.executable, str(FAKE_DAEMON), "--slow-del", "1.5", "--vehicle-id", "sig",
         "--zenoh-connect", endpoint(free_port()), "--set", "zenoh.delivery_wait_s=0"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
    )  # fmt: skip
    try:
        reader = LineReader(process, process.stderr)
        reader.until("roadgaze run: source", 60.0)
        time.sleep(0.3)
        process.send_signal(signal.SIGINT)
        time.sleep(spacing_s)
        process.send_signal(signal.SIGINT)
        code = process.wait(timeout=30)
        lines = reader.until("second SIGINT", 10.0)
        lines += reader.rest()
    finally:
        stop_process(process)
    stderr = "\n".join(lines)
    assert code == 1, stderr[-2000:]
    assert "second SIGINT: exiting without waiting (exit status 1)" in stderr
    assert "Traceback" not in stderr and "Exception ignored" not in stderr
