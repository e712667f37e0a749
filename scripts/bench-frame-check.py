"""Per-frame cost of the failure checks (`roadgaze.monitor.failures.check_frame`).

    PYTHONPATH=src python scripts/bench-frame-check.py [--size 640x480] [--frames 3000]

Prints the wall-clock mean and median and the CPU time per frame in milliseconds on random BGR
frames (on a loaded machine the wall mean carries the time other processes took the core).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from roadgaze.monitor.failures import check_frame


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="640x480", help="WIDTHxHEIGHT")
    parser.add_argument("--frames", type=int, default=3000)
    args = parser.parse_args()
    width, height = (int(part) for part in args.size.split("x"))
    rng = np.random.default_rng(0)
    images = [rng.integers(0, 256, (height, width, 3), dtype=np.uint8) for _ in range(8)]
    previous = None
    times_ms = []
    cpu_start = time.process_time()
    for index in range(args.frames):
        start = time.perf_counter()
        _, previous = check_frame(images[index % len(images)], previous)
        times_ms.append((time.perf_counter() - start) * 1e3)
    cpu_ms = (time.process_time() - cpu_start) * 1e3 / args.frames
    print(
        f"check_frame {width}x{height}: wall mean {statistics.fmean(times_ms):.4f} ms, "
        f"median {statistics.median(times_ms):.4f} ms; CPU {cpu_ms:.4f} ms per frame "
        f"over {args.frames} frames"
    )


if __name__ == "__main__":
    main()
