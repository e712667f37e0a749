#!/usr/bin/env python3
"""Soak of the deployed processes: `roadgaze run` on a looped drive for an hour, bus up.

    .venv/bin/python scripts/soak.py VIDEO SECONDS [--restart-at S] [--outage S] [--csv F]

Writes VIDEO looped to SECONDS into a temporary file (the camera-like stand-in: `run` paces a
file at its own frame rate), then starts, as a user would, three processes on 127.0.0.1:
`roadgaze router`, `roadgaze listen --json` (the subscriber) and `roadgaze run` in client mode.
At --restart-at (default: half way) the router is stopped with SIGTERM and started again on the
same port after --outage seconds (default 10). --nice N runs the daemon at that niceness (a
vehicle computer gives the monitor priority; on a shared machine -10 keeps it paced). Every
10 s the daemon's resident memory (VmRSS) and CPU time are sampled (--csv keeps the samples).
At the end it prints the daemon's frames and alerts, the alerts the subscriber received and
missed, both exit codes, the memory baseline (after 60 s), end, peak and growth, and the CPU
share of one core.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2

ROADGAZE = str(Path(sys.executable).with_name("roadgaze"))
SAMPLE_S = 10.0
BASELINE_S = 60.0
VEHICLE = "soak"


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def looped(video: str, seconds: float, out: Path) -> float:
    """VIDEO's frames repeated into `out` until `seconds`; returns the frame rate."""
    capture = cv2.VideoCapture(video)
    fps = capture.get(cv2.CAP_PROP_FPS) or 15.0
    frames = []
    while True:
        ok, frame = capture.read()
        if not ok:
            break
        frames.append(frame)
    capture.release()
    if not frames:
        raise SystemExit(f"soak: no frames in {video}")
    height, width = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(out), cv2.VideoWriter.fourcc(*"mp4v"), fps, (width, height))
    for number in range(round(seconds * fps)):
        writer.write(frames[number % len(frames)])
    writer.release()
    return float(fps)


def sample(pid: int) -> tuple[float, float] | None:
    """(resident MiB, CPU seconds) of `pid`, None once it has gone."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    rss_kib = int(re.search(r"VmRSS:\s+(\d+)", status).group(1))  # type: ignore[union-attr]
    ticks = os.sysconf("SC_CLK_TCK")
    return rss_kib / 1024.0, (int(fields[11]) + int(fields[12])) / ticks


def router(port: int, log: Path) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [ROADGAZE, "router", "--listen", f"tcp/127.0.0.1:{port}"],
        stdout=subprocess.DEVNULL,
        stderr=log.open("ab"),
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("video")
    parser.add_argument("seconds", type=float)
    parser.add_argument("--restart-at", type=float, default=None)
    parser.add_argument("--outage", type=float, default=10.0)
    parser.add_argument("--csv", type=Path, default=None)
    parser.add_argument(
        "--nice", type=int, default=0, help="the daemon's niceness (negative: before other jobs)"
    )
    parser.add_argument("--keep", type=Path, default=None, help="keep the logs in this folder")
    args = parser.parse_args()
    restart_at = args.seconds / 2 if args.restart_at is None else args.restart_at

    work = Path(tempfile.mkdtemp(prefix="roadgaze-soak-")) if args.keep is None else args.keep
    work.mkdir(parents=True, exist_ok=True)
    drive = work / "looped.mp4"
    fps = looped(args.video, args.seconds, drive)
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    client = ["--vehicle-id", VEHICLE, "--zenoh-mode", "client", "--zenoh-connect", endpoint]

    hub = router(port, work / "router.err")
    time.sleep(3.0)
    listener = subprocess.Popen(
        [ROADGAZE, "listen", "--json", "--no-yaw", *client[:2], "--zenoh-connect", endpoint],
        stdout=(work / "listen.jsonl").open("wb"),
        stderr=(work / "listen.err").open("wb"),
    )
    daemon = subprocess.Popen(
        [ROADGAZE, "run", "--source", str(drive), *client],
        preexec_fn=(lambda: os.nice(args.nice)) if args.nice else None,
        stdout=subprocess.DEVNULL,
        stderr=(work / "run.err").open("wb"),
    )
    started = time.monotonic()
    samples: list[tuple[float, float, float]] = []
    restarted = False
    while daemon.poll() is None:
        now = time.monotonic() - started
        taken = sample(daemon.pid)
        if taken is not None:
            samples.append((now, *taken))
        if not restarted and now >= restart_at:
            hub.send_signal(signal.SIGTERM)
            hub.wait(timeout=30)
            time.sleep(args.outage)
            hub = router(port, work / "router.err")
            restarted = True
            print(f"soak: router restarted at {now:.0f} s after {args.outage:.0f} s down")
        time.sleep(SAMPLE_S)
    run_code = daemon.returncode
    wall_s = time.monotonic() - started
    time.sleep(5.0)
    listener.send_signal(signal.SIGTERM)
    listen_code = listener.wait(timeout=60)
    hub.send_signal(signal.SIGTERM)
    hub.wait(timeout=30)

    run_log = (work / "run.err").read_text(errors="replace")
    stop = re.search(r"after (\d+) frames, (\d+) alerts", run_log)
    frames, raised = (int(stop.group(1)), int(stop.group(2))) if stop else (0, -1)
    received = [
        json.loads(line)
        for line in (work / "listen.jsonl").read_text().splitlines()
        if line.startswith("{")
    ]
    alerts = {m["payload"]["seq"] for m in received if m.get("type") == "alert"}
    totals = [line for line in (work / "listen.err").read_text().splitlines() if "totals" in line]
    if args.csv is not None:
        args.csv.write_text(
            "t_s,rss_mib,cpu_s\n" + "".join(f"{t:.1f},{r:.1f},{c:.2f}\n" for t, r, c in samples)
        )

    settled = [s for s in samples if s[0] >= BASELINE_S]
    print(
        f"soak: {wall_s:.0f} s from start to exit, {frames} frames "
        f"of a {args.seconds:.0f} s drive at {fps:g} fps"
    )
    print(f"soak: run exit {run_code}; listen exit {listen_code}")
    print(
        f"soak: alerts raised {raised}, received {len(alerts)} distinct (seq), "
        + (totals[-1].split(": ", 1)[-1] if totals else "no totals line from listen")
    )
    if settled:
        base, end, peak = settled[0][1], settled[-1][1], max(s[1] for s in settled)
        cpu = (settled[-1][2] - settled[0][2]) / (settled[-1][0] - settled[0][0] or 1.0)
        print(
            f"soak: resident memory baseline {base:.1f} MiB (at {settled[0][0]:.0f} s), "
            f"end {end:.1f}, peak {peak:.1f}, growth {end - base:+.1f} MiB"
        )
        print(
            f"soak: CPU {100 * cpu:.1f} % of one core (mean after {BASELINE_S:.0f} s); "
            f"load average at the end {os.getloadavg()[0]:.1f}"
        )
    print(f"soak: logs in {work}")
    return 0 if run_code == 0 and raised == len(alerts) else 1


if __name__ == "__main__":
    sys.exit(main())
