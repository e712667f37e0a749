#!/usr/bin/env python3
"""Resident memory of the live path: a video replayed at its own frame rate, publishing on Zenoh.

    .venv/bin/python scripts/paced-soak.py VIDEO SECONDS

Loops VIDEO for SECONDS through the run `roadgaze run` builds (`build_run`: health, publisher, a
peer listening on a free 127.0.0.1 port, no subscriber needed) paced at the video's rate, the
one-thread path a camera or `roadgaze run --source FILE` takes, and prints the resident memory
baseline (after 30 s), end, peak and growth. `roadgaze bench --loop-seconds S --memory` measures
the flat-out path.
"""

from __future__ import annotations

import sys

from roadgaze.benchmark.probes import MemoryProbe
from roadgaze.capture import LoopingSource, VideoFileSource
from roadgaze.config import Config
from roadgaze.demo import demo_config, free_local_port
from roadgaze.errors import RoadgazeError
from roadgaze.pipeline import RunOptions, RunSummary, build_run


def soak(video: str, seconds: float, config: Config, memory: MemoryProbe) -> RunSummary:
    source = LoopingSource(lambda: VideoFileSource(video), duration_s=seconds)
    options = RunOptions("paced-soak", command="run", publish=True)
    with build_run(config, options, source=source, sinks=(memory,)) as run:
        summary = run.run(realtime=True)
    memory.close()
    return summary


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    video, seconds = sys.argv[1], float(sys.argv[2])
    config = demo_config(Config(), free_local_port())
    memory = MemoryProbe(settle_s=30.0)
    try:
        summary = soak(video, seconds, config, memory)
    except RoadgazeError as exc:
        print(f"paced-soak: {exc}", file=sys.stderr)
        return 2

    baseline = memory.baseline_mb
    growth = memory.growth_mb
    print(
        f"paced soak: {summary.frames} frames in {summary.wall_s:.0f} s; resident memory "
        + ("no baseline (under 30 s)" if baseline is None else f"baseline {baseline:.1f} MiB")
        + f", end {memory.last_mb:.1f} MiB, peak {memory.peak_mb:.1f} MiB"
        + ("" if growth is None else f", growth {growth:+.2f} MiB")
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
