"""Frame-loop slowdown of the daemon under bus floods, for one or more source trees.

    python scripts/bus_flood_bench.py --tree before=/tmp/base/src --tree after=src \
        [--rounds 3] [--cycles 5] [--work mediapipe|numpy]

For every round, tree and flood (10 MB puts on the speed key as fast as a client can; 2,000
state queries a second; the same two on another vehicle's keys, which the daemon does not
declare: what the router and the flooder alone cost on a shared machine) it starts, each in its
own process: a Python router on a free loopback port, the daemon's bus outputs and frame loop
from that tree (`build_run` as `roadgaze run` builds it, or `bus_outputs` + `Pipeline` in a tree
from before it; real MediaPipe on a synthetic clip by default), and
the flooder. The flooder is switched on and off (SIGCONT/SIGSTOP) every `--period` seconds for
`--cycles` cycles, so each flooded window has an unflooded neighbour in the same process: the
other load on a shared machine drifts more slowly than that. The daemon records the wall time
between consecutive frames; the slowdown of a run is median(interval, flood on) /
median(interval, flood off) - 1 (0.4 s after each switch left out); the daemon process's CPU
time per wall second (all its threads, Zenoh's included) is reported beside it, the figure the
shared machine disturbs least. A client also asks for the state twice a second (a legitimate
health check): answered/asked per window state is reported. Prints one JSON line per run and a
summary table.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve()
REPO = HERE.parents[1]
VEHICLE = "bench"
FLOODS = (
    "speed-10MB",
    "speed-10MB-elsewhere",
    "speed-10MB+router-limits",
    "queries-2000/s",
    "queries-elsewhere",
    "queries-2000/s+router-limits",
)
"""'+router-limits': the router has the size and rate limits `roadgaze security init` writes."""
SETTLE_S = 0.4
"""Left out after each switch of the flood: queued data drains, the flooder restarts."""

ROUTER = """
import json, sys, time, zenoh
conf = {"mode": "router", "listen": {"endpoints": [sys.argv[1]]},
        "scouting": {"multicast": {"enabled": False}}}
conf.update(json.loads(sys.argv[2]))
session = zenoh.open(zenoh.Config.from_json5(json.dumps(conf)))
print("ready", flush=True)
while True:
    time.sleep(3600)
"""

FLOODER = """
import json, signal, sys, time, zenoh
endpoint, mode = sys.argv[1], sys.argv[2]
vehicle = "other" if mode.endswith("elsewhere") else "bench"
conf = {"mode": "client", "connect": {"endpoints": [endpoint]},
        "scouting": {"multicast": {"enabled": False}}}
session = zenoh.open(zenoh.Config.from_json5(json.dumps(conf)))
running = True
def stop(*_):
    global running
    running = False
signal.signal(signal.SIGTERM, stop)
payload = b'{"kmh": 50, "pad": "' + b"a" * (10_000_000 - 30) + b'"}'
sent, period, next_t = 0, 1 / 2000, time.perf_counter()
print("started", flush=True)
while running:
    if mode.startswith("speed"):
        session.put(f"vehicle/{vehicle}/speed", payload)
    else:
        session.get(f"vehicle/{vehicle}/dms/state", lambda reply: None, timeout=1.0,
                    consolidation=zenoh.ConsolidationMode.NONE)
        next_t += period
        delay = next_t - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
        elif delay < -1.0:
            next_t = time.perf_counter()
    sent += 1
print("sent", sent, flush=True)
"""


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def run_daemon(args: argparse.Namespace) -> int:
    """Child: the daemon's bus outputs and frame loop from the tree on sys.path."""
    import numpy as np

    from roadgaze.capture import LoopingSource, VideoFileSource
    from roadgaze.config import Config
    from roadgaze.pipeline import create_detector
    from roadgaze.types import Detection

    config = Config.model_validate(
        {"zenoh": {"vehicle_id": VEHICLE, "connect": [f"tcp/127.0.0.1:{args.port}"]}}
    )

    class NumpyWork:
        """About 10 ms of single-threaded numpy per frame (the GIL is released in BLAS)."""

        def __init__(self) -> None:
            self.matrix = np.random.default_rng(0).standard_normal((260, 260))

        def detect(self, image: Any, t_s: float | None = None) -> Detection:
            product = self.matrix
            for _ in range(6):
                product = np.tanh(product @ self.matrix / 260.0)
            return Detection(faces=(), driver_index=None)

        def close(self) -> None:
            return None

    class FrameTimes:
        def __init__(self) -> None:
            self.stamps: list[tuple[float, float]] = []

        def on_record(self, record: Any, frame: Any) -> None:
            self.stamps.append((time.monotonic(), time.process_time()))

        def on_alert(self, alert: Any) -> None:
            return None

        def close(self) -> None:
            return None

    detector = NumpyWork() if args.work == "numpy" else create_detector(config)
    times = FrameTimes()
    stop = threading.Event()
    threading.Thread(target=lambda: (sys.stdin.readline(), stop.set()), daemon=True).start()
    source = LoopingSource(lambda: VideoFileSource(Path(args.clip)), duration_s=600.0)
    try:
        from roadgaze.pipeline import RunOptions, build_run
    except ImportError:  # a tree from before the one builder: its daemon's own wiring
        state = old_tree_loop(config, detector, source, times, stop)
    else:
        options = RunOptions("bench", command="run", publish=True)
        with build_run(config, options, source=source, detector=detector, sinks=(times,)) as run:
            print("ready", flush=True)
            run.run(stop=stop)
            state = run.health.state_message().transport.model_dump()
    counters = {k: v for k, v in state.items() if isinstance(v, int) and not isinstance(v, bool)}
    print(json.dumps({"stamps": times.stamps, "transport": counters}), flush=True)
    return 0


def old_tree_loop(config: Any, detector: Any, source: Any, times: Any, stop: Any) -> Any:
    """The loop as a tree without `roadgaze.pipeline.build_run` wired it (`roadgaze.daemon`)."""
    from roadgaze.daemon import bus_outputs
    from roadgaze.pipeline import Pipeline

    with bus_outputs(config, "bench", publish=True) as bus:
        pipeline = Pipeline.from_config(config, detector, speed=bus.speed)
        print("ready", flush=True)
        pipeline.run(source, [*bus.sinks, times], stop=stop)
        state = bus.health.state_message().transport.model_dump()
    detector.close()
    return state


def spawn(code_or_args: list[str], env: dict[str, str] | None = None) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, *code_or_args],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        env=env,
    )


def wait_line(process: subprocess.Popen[str], prefix: str, timeout_s: float = 60.0) -> str:
    assert process.stdout is not None
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if not line and process.poll() is not None:
            break
        if line.startswith(prefix):
            return line
    raise RuntimeError(f"no '{prefix}' line from {process.args}")


def _health_checks(endpoint: str, until: threading.Event, asked: list[tuple[float, bool]]) -> None:
    import zenoh

    conf = {"mode": "client", "connect": {"endpoints": [endpoint]},
            "scouting": {"multicast": {"enabled": False}}}  # fmt: skip
    with zenoh.open(zenoh.Config.from_json5(json.dumps(conf))) as session:
        while not until.wait(0.5):
            at = time.monotonic()
            replies = session.get(f"vehicle/{VEHICLE}/dms/state", timeout=0.5)
            asked.append((at, any(reply.ok is not None for reply in replies)))


def one_run(tree: str, flood: str, args: argparse.Namespace, clip: Path) -> dict[str, Any]:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    env = dict(os.environ, PYTHONPATH=tree, GLOG_minloglevel="2")
    limits: dict[str, Any] = {}
    if flood.endswith("+router-limits"):
        from roadgaze.config import ZenohConfig
        from roadgaze.security import downsampling, low_pass_filter
        from roadgaze.transport import Keys

        keys = Keys.from_config(ZenohConfig(), VEHICLE)
        limits = {"low_pass_filter": low_pass_filter(keys), "downsampling": downsampling(keys)}
        flood = flood.removesuffix("+router-limits")
    router = spawn(["-c", ROUTER, endpoint, json.dumps(limits)])
    processes = [router]
    windows: list[tuple[float, float, bool]] = []
    asked: list[tuple[float, bool]] = []
    try:
        wait_line(router, "ready")
        daemon = spawn(
            [str(HERE), "--daemon", "--port", str(port), "--clip", str(clip), "--work", args.work],
            env=env,
        )
        processes.append(daemon)
        wait_line(daemon, "ready", timeout_s=120.0)
        flooder = spawn(["-c", FLOODER, endpoint, flood])
        processes.append(flooder)
        wait_line(flooder, "started")
        flooder.send_signal(signal.SIGSTOP)
        done = threading.Event()
        checker = threading.Thread(target=_health_checks, args=(endpoint, done, asked))
        checker.start()
        time.sleep(args.warmup)
        for _ in range(args.cycles):
            for on in (True, False):
                flooder.send_signal(signal.SIGCONT if on else signal.SIGSTOP)
                start = time.monotonic()
                time.sleep(args.period)
                windows.append((start, time.monotonic(), on))
        done.set()
        checker.join(timeout=10)
        assert daemon.stdin is not None
        daemon.stdin.write("stop\n")
        daemon.stdin.flush()
        result = json.loads(wait_line(daemon, "{", timeout_s=120.0))
    finally:
        for process in reversed(processes):
            if process.poll() is None:
                process.send_signal(signal.SIGCONT)
                process.kill()
            process.wait(timeout=30)
    stamps = result.pop("stamps")
    intervals: dict[bool, list[float]] = {True: [], False: []}
    cpu_s: dict[bool, float] = {True: 0.0, False: 0.0}
    wall_s: dict[bool, float] = {True: 0.0, False: 0.0}
    health: dict[bool, list[bool]] = {True: [], False: []}
    for begin, end, on in windows:
        for (wall_a, cpu_a), (wall_b, cpu_b) in itertools.pairwise(stamps):
            if begin + SETTLE_S <= wall_a and wall_b <= end:
                intervals[on].append((wall_b - wall_a) * 1e3)
                cpu_s[on] += cpu_b - cpu_a
                wall_s[on] += wall_b - wall_a
        health[on] += [ok for at, ok in asked if begin + SETTLE_S <= at <= end]
    median_on = statistics.median(intervals[True]) if intervals[True] else None
    median_off = statistics.median(intervals[False]) if intervals[False] else None
    return result | {
        "median_ms_flood_off": median_off,
        "median_ms_flood_on": median_on,
        "frames": {"off": len(intervals[False]), "on": len(intervals[True])},
        "daemon_cpu_cores": {
            "off": round(cpu_s[False] / wall_s[False], 3) if wall_s[False] else None,
            "on": round(cpu_s[True] / wall_s[True], 3) if wall_s[True] else None,
        },
        "slowdown": None if not (median_on and median_off) else median_on / median_off - 1,
        "health_answered": {
            state: f"{sum(health[on])}/{len(health[on])}"
            for state, on in (("off", False), ("on", True))
        },
    }


def make_clip(folder: Path) -> Path:
    clip = folder / "drive.mkv"
    subprocess.run(
        [sys.executable, "-m", "roadgaze", "synth", "--timeline", "0:2,40:2,0:2", "--out",
         str(clip), "--size", "640x480"],
        check=True, capture_output=True, env=dict(os.environ, PYTHONPATH=str(REPO / "src")),
    )  # fmt: skip
    return clip


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--tree", action="append", default=[], metavar="NAME=SRC")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--cycles", type=int, default=5, help="flood on/off cycles per run")
    parser.add_argument("--period", type=float, default=2.0, help="seconds on, then off")
    parser.add_argument("--warmup", type=float, default=4.0)
    parser.add_argument("--work", choices=["mediapipe", "numpy"], default="mediapipe")
    parser.add_argument("--flood", action="append", choices=FLOODS, help="default: all")
    parser.add_argument("--daemon", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--port", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--clip", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.daemon:
        return run_daemon(args)
    trees = dict(item.split("=", 1) for item in args.tree) or {"this": str(REPO / "src")}
    table: dict[tuple[str, str], list[float]] = {}
    cpu: dict[tuple[str, str], list[tuple[float, float, str]]] = {}
    with tempfile.TemporaryDirectory() as folder:
        clip = make_clip(Path(folder))
        for round_index in range(args.rounds):
            for flood in args.flood or FLOODS:
                for name, tree in trees.items():
                    result = one_run(str(Path(tree).resolve()), flood, args, clip)
                    result |= {"round": round_index, "tree": name, "flood": flood}
                    print(json.dumps(result), flush=True)
                    if result["slowdown"] is not None:
                        table.setdefault((name, flood), []).append(result["slowdown"])
                        cores = result["daemon_cpu_cores"]
                        cpu.setdefault((name, flood), []).append(
                            (
                                cores["off"] or 0.0,
                                cores["on"] or 0.0,
                                result["health_answered"]["on"],
                            )
                        )
    print("\ntree     flood                         frame-loop slowdown per run (on vs off); "
          "median; daemon CPU cores off -> on; health checks answered while flooded")  # fmt: skip
    for (name, flood), values in sorted(table.items()):
        shown = ", ".join(f"{100 * value:+.0f} %" for value in values)
        runs = cpu[(name, flood)]
        cores = ", ".join(f"{off:.2f}->{on:.2f}" for off, on, _ in runs)
        answered = " ".join(health for _, _, health in runs)
        print(f"{name:<8} {flood:<29} {shown}; {100 * statistics.median(values):+.0f} %; "
              f"{cores}; {answered}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
