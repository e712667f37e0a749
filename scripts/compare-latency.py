#!/usr/bin/env python3
"""Compare the paced capture-to-delivery latency of source trees on one clip, interleaved.

    .venv/bin/python scripts/compare-latency.py VIDEO --trees OLD/src NEW/src [--rounds 3]
                                                [--loop-seconds 30]

Each round runs `roadgaze bench VIDEO --json --no-raw --latency --loop-seconds S` once per tree,
in turn, with the tree first on PYTHONPATH (both trees need `bench --latency`). Every run is
printed as it ends (a shared machine's load moves single runs): the landmark stage's p50/p99,
capture-to-delivery p50/p99, the part after the landmark stage at the median, the margin to the
target (landmark p99 + 2 ms; negative = met) and Zenoh's delivery p50. Progress on stderr, the
table on stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path


def one_run(video: str, tree: str, loop_seconds: float) -> dict[str, float]:
    command = [sys.executable, "-m", "roadgaze", "bench", video, "--json", "--no-raw"]
    command += ["--latency", "--loop-seconds", str(loop_seconds)]
    environment = {**os.environ, "PYTHONPATH": str(Path(tree).resolve())}
    done = subprocess.run(
        command, env=environment, capture_output=True, text=True, check=False, timeout=900
    )
    if done.returncode != 0:
        raise SystemExit(f"bench failed in {tree}: {done.stderr.strip().splitlines()[-1:]}")
    latency: dict[str, float] = json.loads(done.stdout)["latency"]
    return latency


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("video")
    parser.add_argument("--trees", nargs="+", required=True, help="src folders to compare")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--loop-seconds", type=float, default=30.0)
    args = parser.parse_args()
    print(
        "tree | landmarks p50 / p99 | e2e p50 / p99 | after landmarks p50 | p99 - target | "
        "delivery p50 (ms)"
    )
    for round_index in range(args.rounds):
        for tree in args.trees:
            print(f"round {round_index + 1}: {tree}", file=sys.stderr, flush=True)
            run = one_run(args.video, tree, args.loop_seconds)
            print(
                f"{tree} | {run['landmarks_p50_ms']:.2f} / {run['landmarks_p99_ms']:.2f} | "
                f"{run['p50_ms']:.2f} / {run['p99_ms']:.2f} | "
                f"{run['p50_ms'] - run['landmarks_p50_ms']:.2f} | "
                f"{run['p99_ms'] - run['target_p99_ms']:+.2f} | {run['delivery_p50_ms']:.2f}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
