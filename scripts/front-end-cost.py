#!/usr/bin/env python3
"""CPU time of the front end for cabin images per 640x480 frame (docs/conditions.md).

    .venv/bin/python scripts/front-end-cost.py [--frames N]

Frames: a good colour frame (the decision only), and a dark colour frame, a flat grey frame
(V4L2 GREY) and a noisy IR-like grey frame (the decision and the enhancement), each made from
skimage's astronaut placed on a 640x480 canvas with the condition suite's transforms; then the
strong version a further look makes of the two noisy ones (N / 10 frames a round). Prints the
process CPU time per frame (median of 5 rounds of N frames), so other processes on the machine
move it less than wall time.
"""

from __future__ import annotations

import argparse
import statistics
import time

import cv2
import numpy as np
from skimage import data as skimage_data

from roadgaze.evaluation.conditions import dark_cabin, ir_grey
from roadgaze.landmarks.front_end import assess, enhance


def canvas() -> np.ndarray:
    frame = np.full((480, 640, 3), 90, np.uint8)
    face = cv2.cvtColor(skimage_data.astronaut(), cv2.COLOR_RGB2BGR)
    frame[:, 80:560] = cv2.resize(face, (480, 480), interpolation=cv2.INTER_AREA)
    return frame


def cost_ms(frame: np.ndarray, frames: int, strong: bool = False) -> tuple[float, bool]:
    """Median CPU ms per frame of the front end's work on `frame` (with `strong`, of the strong
    version a further look makes), and whether it enhanced."""
    needs = assess(frame).needs_curve
    rounds = []
    for _ in range(5):
        start = time.process_time()
        for _ in range(frames):
            if assess(frame).needs_curve:
                enhance(frame, strong=strong)
        rounds.append((time.process_time() - start) / frames * 1e3)
    return statistics.median(rounds), needs


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=500, help="frames per round (default 500)")
    args = parser.parse_args()
    cv2.setNumThreads(1)
    good = canvas()
    rng = np.random.default_rng(0)
    cases = {
        "good colour frame": good,
        "dark colour frame": dark_cabin(good, rng),
        "flat grey frame (no noise)": ir_grey(good, rng, noise_std=0.0),
        "IR-like grey frame (noise 6)": ir_grey(good, rng),
    }
    print(f"front end, CPU ms per 640x480 frame (median of 5 x {args.frames} frames):")
    for name, frame in cases.items():
        milliseconds, enhanced = cost_ms(frame, args.frames)
        what = "decision + enhancement" if enhanced else "decision only"
        print(f"  {name:30s} {milliseconds:.3f} ms ({what})")
    print("a further look's strong version (a noisy hard frame without a face at first):")
    for name in ("dark colour frame", "IR-like grey frame (noise 6)"):
        milliseconds, _ = cost_ms(cases[name], max(1, args.frames // 10), strong=True)
        print(f"  {name:30s} {milliseconds:.3f} ms (decision + strong enhancement)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
