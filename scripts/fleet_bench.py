"""Fleet replay: make synthetic drives, and measure `roadgaze batch` with 1 and 2 workers.

    python scripts/fleet_bench.py make DIR [--drives 20] [--seconds 12] [--size 640x480]
                                           [--drivers 5] [--fps 15] [--seed 1] [--bad]
    python scripts/fleet_bench.py throughput VIDEOS [--workers 1 2] [--repeats 2]

`make` renders drives of a real face (scikit-image's astronaut) glancing off the road, under
DIR/videos/<vehicle>/<drive>.mp4, and writes DIR/manifest.csv (drive, driver and vehicle ids,
start times). Each driver has a habit: how often and how long they look away. `--bad` adds a
corrupt file, a truncated copy of a drive and a missing path to the manifest.

`throughput` runs `roadgaze batch VIDEOS --workers N --json` for each N in turn, `--repeats`
times, each into a fresh output folder, interleaved so that other load on the machine falls on
both alike; prints the frames/s of each run, the CPU time it used (all processes; frames per
CPU-second shows what parallel work costs besides the cores it gets), the 2-over-1 ratio of each
repeat, and the time to create one VIDEO-mode landmarker (the per-file start-up besides opening
the video).
"""

from __future__ import annotations

import argparse
import csv
import json
import random
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import UTC, datetime, timedelta
from pathlib import Path

HABITS = (0.15, 0.3, 0.45, 0.6, 0.8)
"""Per driver: the share of glances that are long (2.5-6 s) rather than short (0.6-1.8 s)."""


def timeline(rng: random.Random, seconds: float, habit: float) -> str:
    """Road segments and glances off the road, about `seconds` long."""
    parts: list[str] = []
    total = 0.0
    while total < seconds:
        road = rng.uniform(1.5, 4.0)
        parts.append(f"{rng.uniform(-4, 4):.1f}:{road:.2f}")
        total += road
        if total >= seconds:
            break
        glance = rng.uniform(2.5, 6.0) if rng.random() < habit else rng.uniform(0.6, 1.8)
        yaw = rng.choice((-1, 1)) * rng.uniform(30.0, 70.0)
        parts.append(f"{yaw:.1f}:{glance:.2f}")
        total += glance
    return ",".join(parts)


def make(args: argparse.Namespace) -> int:
    from roadgaze.synth import FaceRenderer, load_photo, render_clip

    width, height = (int(v) for v in args.size.split("x"))
    renderer = FaceRenderer(load_photo(), (width, height))
    rng = random.Random(args.seed)
    out: Path = args.dir
    start = datetime(2024, 5, 6, 7, 0, tzinfo=UTC)
    rows = []
    for index in range(args.drives):
        driver = index % args.drivers
        vehicle = f"van-{driver % 3 + 1}"
        drive_id = f"drive-{index + 1:03d}"
        path = out / "videos" / vehicle / f"{drive_id}.mp4"
        path.parent.mkdir(parents=True, exist_ok=True)
        began = time.perf_counter()
        line = timeline(rng, args.seconds, HABITS[driver % len(HABITS)])
        render_clip(line, path, fps=args.fps, renderer=renderer)
        print(f"{path} ({time.perf_counter() - began:.1f} s): {line}", file=sys.stderr)
        when = start + timedelta(days=index // args.drivers, hours=driver)
        rows.append((path, drive_id, f"driver-{driver + 1}", vehicle, when.isoformat()))
    if args.bad:
        bad = out / "videos" / "bad"
        bad.mkdir(parents=True, exist_ok=True)
        (bad / "corrupt.mp4").write_bytes(b"\x00not a video\x00" * 512)
        data = rows[0][0].read_bytes()
        (bad / "truncated.mp4").write_bytes(data[: len(data) // 2])
        rows.append((bad / "corrupt.mp4", "corrupt", "driver-1", "van-1", start.isoformat()))
        rows.append((bad / "truncated.mp4", "truncated", "driver-1", "van-1", start.isoformat()))
        rows.append((bad / "missing.mp4", "missing", "driver-2", "van-2", start.isoformat()))
    with (out / "manifest.csv").open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(("path", "drive_id", "driver_id", "vehicle_id", "start_time"))
        for path, *rest in rows:
            writer.writerow((path.relative_to(out).as_posix(), *rest))
    print(f"wrote {len(rows)} drives and {out / 'manifest.csv'}", file=sys.stderr)
    return 0


def landmarker_start_s(repeats: int = 5) -> list[float]:
    """Seconds to create (and close) one VIDEO-mode landmarker, `repeats` times."""
    from roadgaze.config import Config
    from roadgaze.landmarks import MediaPipeLandmarker

    config = Config()
    MediaPipeLandmarker.from_config(config, video=True).close()  # imports, model resolved
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        MediaPipeLandmarker.from_config(config, video=True).close()
        times.append(time.perf_counter() - began)
    return times


def throughput(args: argparse.Namespace) -> int:
    runs: list[dict[str, object]] = []
    with tempfile.TemporaryDirectory(prefix="fleet-bench-") as scratch:
        for repeat in range(args.repeats):
            for workers in args.workers:
                out = Path(scratch) / f"out-{repeat}-{workers}"
                command = [sys.executable, "-m", "roadgaze", "batch", str(args.videos)]
                command += ["--out", str(out), "--workers", str(workers), "--json"]
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                result = subprocess.run(
                    [*command, "--no-progress"], capture_output=True, text=True, check=False
                )
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpu_s = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
                if result.returncode not in (0, 3):
                    print(result.stderr, file=sys.stderr)
                    return result.returncode
                figures = json.loads(result.stdout)
                figures["repeat"] = repeat + 1
                figures["cpu_s"] = round(cpu_s, 2)
                runs.append(figures)
                print(
                    f"repeat {repeat + 1}, {workers} worker(s): {figures['frames']} frames in "
                    f"{figures['wall_s']:.1f} s = {figures['frames_per_s']:.1f} frames/s "
                    f"(pool start {figures['engine_startup_s']:.1f} s, per-drive start-up "
                    f"median {figures['drive_startup_median_s']} s; {cpu_s:.1f} CPU-s in all, "
                    f"{figures['frames'] / cpu_s:.1f} frames per CPU-second)",
                    flush=True,
                )
    by_key = {(r["repeat"], r["workers"]): r["frames_per_s"] for r in runs}
    low, high = min(args.workers), max(args.workers)
    for repeat in range(1, args.repeats + 1):
        ratio = float(by_key[(repeat, high)]) / float(by_key[(repeat, low)])  # type: ignore[arg-type]
        print(f"repeat {repeat}: {high} workers / {low} worker = x{ratio:.2f}")
    starts = landmarker_start_s()
    print(
        f"landmarker creation (VIDEO mode): median {statistics.median(starts) * 1000:.0f} ms, "
        f"max {max(starts) * 1000:.0f} ms over {len(starts)}"
    )
    if args.json:
        print(json.dumps({"runs": runs, "landmarker_start_s": starts}))
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    maker = commands.add_parser("make", help="render synthetic drives and a manifest")
    maker.add_argument("dir", type=Path)
    maker.add_argument("--drives", type=int, default=20)
    maker.add_argument("--seconds", type=float, default=12.0)
    maker.add_argument("--size", default="640x480")
    maker.add_argument("--drivers", type=int, default=5)
    maker.add_argument("--fps", type=float, default=15.0)
    maker.add_argument("--seed", type=int, default=1)
    maker.add_argument("--bad", action="store_true", help="add a corrupt, a truncated, a missing")
    maker.set_defaults(run=make)
    bench = commands.add_parser("throughput", help="roadgaze batch with 1 and 2 workers")
    bench.add_argument("videos", type=Path, help="folder of videos or manifest")
    bench.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    bench.add_argument("--repeats", type=int, default=2)
    bench.add_argument("--json", action="store_true", help="also print every figure as JSON")
    bench.set_defaults(run=throughput)
    args = parser.parse_args()
    return int(args.run(args))


if __name__ == "__main__":
    sys.exit(main())
