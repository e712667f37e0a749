"""The Ray engine as a user runs it: `roadgaze batch --engine ray` in a fresh process, with no
Ray running (it starts a local instance and stops it) and with `--ray-address` to a head started
by `ray start --head`. The test process itself never initialises Ray, so a start that only works
where Ray is already initialised (or only on the main thread) fails here."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest

from repo_paths import child_env
from roadgaze.fleet import output_paths
from zenoh_helpers import free_port, wait_for

pytest.importorskip("ray", reason="Ray is the optional extra roadgaze[ray]")

pytestmark = pytest.mark.slow

TIMING = {"processing_fps", "startup_s", "wall_s"}
CLI_TIMEOUT_S = 600.0


def _batch(
    folder: Path, out: Path, *extra: str, ray_tmp: Path | None = None
) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in child_env().items() if k != "RAY_ADDRESS"}
    if ray_tmp is not None:
        env["RAY_TMPDIR"] = str(ray_tmp)
    return subprocess.run(
        [
            *(sys.executable, "-m", "roadgaze", "batch", str(folder), "--out", str(out)),
            *("--engine", "ray", "--no-progress", *extra),
        ],
        capture_output=True,
        text=True,
        timeout=CLI_TIMEOUT_S,
        env=env,
    )


def _assert_same_as_local(out: Path, local_batch: Any) -> None:
    for drive_id in local_batch.input.videos:
        for ray_path, local_path in zip(
            output_paths(out, drive_id), output_paths(local_batch.out_dir, drive_id), strict=True
        ):
            ray_table, local_table = pq.read_table(ray_path), pq.read_table(local_path)
            assert ray_table.num_rows > 0 or "alerts" in str(ray_path)
            assert ray_table.equals(local_table), drive_id
    ray_rows = pq.read_table(out / "summary.parquet").to_pylist()
    local_rows = pq.read_table(local_batch.out_dir / "summary.parquet").to_pylist()
    assert [{k: v for k, v in row.items() if k not in TIMING} for row in ray_rows] == [
        {k: v for k, v in row.items() if k not in TIMING} for row in local_rows
    ]
    assert {r["drive_id"]: r["status"] for r in ray_rows}["corrupt"] == "failed"


def _processes_naming(text: str) -> list[str]:
    """Command lines of the running processes that contain `text`."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode()
            except OSError:
                continue
            if text in cmdline:
                found.append(cmdline[:120])
    return found


def test_a_fresh_process_with_no_ray_running_starts_one_and_equals_the_local_engine(
    local_batch: Any, tmp_path: Path, ray_tmp: Path
) -> None:
    """The case that broke in 0.2: `ray.init` on a helper thread started a local instance
    that the kernel killed when the thread ended (parent-death signal of that thread)."""
    out = tmp_path / "ray-out"
    done = _batch(local_batch.input.folder, out, ray_tmp=ray_tmp)
    assert done.returncode == 3, done.stderr[-2000:]  # the corrupt and empty drives fail
    assert "on ray with" in done.stderr
    _assert_same_as_local(out, local_batch)
    # Ray's own processes end shortly after the driver's shutdown: the instance it started is
    # gone (waited for up to a bound far beyond their usual second or two).
    assert wait_for(lambda: _processes_naming(str(ray_tmp)) == [], timeout_s=60.0), (
        _processes_naming(str(ray_tmp))
    )


@pytest.fixture
def ray_tmp() -> Iterator[Path]:
    """A Ray temporary folder of this test's own (never the shared /tmp/ray); short, because
    Ray's unix sockets live under it (108 bytes at most)."""
    folder = Path(tempfile.mkdtemp(prefix="rg-ray-", dir="/tmp"))
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture
def ray_head(tmp_path: Path, ray_tmp: Path) -> Iterator[str]:
    """A real Ray head started with `ray start --head --block` in a process group of its own
    (stopped by signalling that group, never `ray stop`, which would stop every Ray here), in a
    temporary folder of its own and on ports chosen by the OS (not Ray's fixed defaults)."""
    port, agent_port = free_port(), free_port()
    ray_cli = Path(sys.executable).with_name("ray")
    head = subprocess.Popen(
        [
            *(str(ray_cli), "start", "--head", "--block", f"--port={port}", "--num-cpus=1"),
            *("--include-dashboard=false", "--disable-usage-stats", f"--temp-dir={ray_tmp}"),
            f"--dashboard-agent-listen-port={agent_port}",
        ],
        stdout=(tmp_path / "ray-head.log").open("w"),
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    try:

        def listening() -> bool:
            assert head.poll() is None, (tmp_path / "ray-head.log").read_text()[-2000:]
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=1.0):
                    return True
            except OSError:
                return False

        if not wait_for(listening, timeout_s=180.0, every_s=0.2):
            pytest.fail("ray start --head did not listen within 180 s")
        yield f"127.0.0.1:{port}"
    finally:
        with contextlib.suppress(ProcessLookupError):  # gone already: its log says why
            os.killpg(head.pid, signal.SIGTERM)
        try:  # `ray start --block` took the whole 30 s it was once given: a head of our own,
            head.wait(timeout=5)  # in a folder of its own, is killed after 5
        except subprocess.TimeoutExpired:
            os.killpg(head.pid, signal.SIGKILL)
            head.wait()


def test_a_running_head_at_an_address_is_used_and_left_running(
    local_batch: Any, tmp_path: Path, ray_head: str, ray_tmp: Path
) -> None:
    out = tmp_path / "ray-out"
    args = ("--ray-address", ray_head, "--ray-timeout", "120")
    done = _batch(local_batch.input.folder, out, *args, ray_tmp=ray_tmp)
    assert done.returncode == 3, done.stderr[-2000:]
    _assert_same_as_local(out, local_batch)
    host, port = ray_head.split(":")
    with socket.create_connection((host, int(port)), timeout=5.0):
        pass  # the head the user started is still there
