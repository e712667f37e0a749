"""`roadgaze bench VIDEO --phone`: the CPU per frame with phone detection off and on.

`--repeat` rounds of two pipeline passes over the same frames, interleaved (off, then on), each
with a fresh detector; the figure is the process CPU time per frame after the warm-up (every
thread of the loop), medians over the rounds, and the added share. The load average is printed
with them: on a shared machine the figures move with it.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
from collections.abc import Callable
from typing import Any

from roadgaze.config import Config

PHONE_BUDGET = 0.25
"""The added CPU per frame phone detection may cost by default, as a share of the frame's."""


def phone_cost(args: argparse.Namespace, config: Config, pipeline_pass: Callable[..., Any]) -> int:
    """Print the comparison (JSON with `--json`); exit code 0."""
    from roadgaze.pipeline import StageTimings

    def one(enabled: bool) -> float | None:
        hands = config.hands.model_copy(update={"enabled": enabled})
        timings = StageTimings(skip_first=args.warmup)
        result = pipeline_pass(args, config.model_copy(update={"hands": hands}), [], timings)
        cpu: float | None = result.cpu_ms_per_frame
        return cpu

    off: list[float] = []
    on: list[float] = []
    loads: list[float] = []
    for _ in range(args.repeat):
        for enabled, into in ((False, off), (True, on)):
            value = one(enabled)
            if value is not None:
                into.append(value)
        loads.append(os.getloadavg()[0])
    off_ms = statistics.median(off) if off else None
    on_ms = statistics.median(on) if on else None
    added = None if not off_ms or on_ms is None else (on_ms - off_ms) / off_ms
    result = {
        "source": args.source,
        "hands": config.hands.model_dump(mode="json"),
        "rounds": args.repeat,
        "cpu_ms_per_frame_off": off,
        "cpu_ms_per_frame_on": on,
        "median_off_ms": off_ms,
        "median_on_ms": on_ms,
        "added": added,
        "budget": PHONE_BUDGET,
        "load_average": loads,
    }
    if args.json:
        print(json.dumps(result))
        return 0
    hands = config.hands
    print(
        f"phone detection on {args.source}: {hands.models} hand models, hands every "
        f"{hands.interval_s:g} s, palm detector every {hands.detect_interval_s:g} s at most, "
        f"upper body {'with them' if hands.body else 'off'}"
    )
    print(f"  CPU per frame, off: {_ms(off_ms)} (rounds: {', '.join(_ms(v) for v in off)})")
    print(f"  CPU per frame, on:  {_ms(on_ms)} (rounds: {', '.join(_ms(v) for v in on)})")
    if added is not None:
        verdict = "within" if added <= PHONE_BUDGET else "over"
        print(f"  added: {added:+.1%} ({verdict} the {PHONE_BUDGET:.0%} budget)")
    print(f"  load average (1 min) after each round: {', '.join(f'{v:.1f}' for v in loads)}")
    return 0


def _ms(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.2f} ms"
