"""The whole loop on one clip with both landmark engines, record by record.

    PYTHONPATH=src python scripts/compare-engines.py CLIP [--baseline]

Runs the pipeline (`build_run`, the configured settings but `landmarks.engine`) over
CLIP once with `litert` and once with `mediapipe` and prints, over the frames where both found
the driver, the median, p99 and largest absolute difference of the raw and smoothed yaw and
pitch, MediaPipe's matrix yaw and pitch, the eye direction and openness, the driver's landmarks
(pixels), and whether the alerts came at the same times. `--baseline` compares MediaPipe with
MediaPipe on the same clip with the lowest bit of 1 % of the pixels flipped (an invisible change):
the run-to-run spread of MediaPipe's tracked, smoothed stream, against which the engines'
differences are read (docs/landmarks.md).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from roadgaze.capture import open_source
from roadgaze.config import Config
from roadgaze.pipeline import RunOptions, build_run
from roadgaze.types import ClosesOnExit, Frame, FrameRecord

FIELDS: dict[str, Callable[[FrameRecord], Any]] = {
    "yaw_raw_deg": lambda r: r.sample.yaw_raw_deg,
    "yaw_deg": lambda r: r.sample.yaw_deg,
    "pitch_raw_deg": lambda r: r.sample.pitch_raw_deg,
    "pitch_deg": lambda r: r.sample.pitch_deg,
    "matrix_yaw_deg": lambda r: r.sample.features and r.sample.features.mediapipe_yaw_deg,
    "matrix_pitch_deg": lambda r: r.sample.features and r.sample.features.mediapipe_pitch_deg,
    "eye_yaw_deg": lambda r: r.sample.eyes and r.sample.eyes.yaw_deg,
    "eye_pitch_deg": lambda r: r.sample.eyes and r.sample.eyes.pitch_deg,
    "eye_openness": lambda r: r.sample.eyes and r.sample.eyes.openness,
}


class FlippedBits(ClosesOnExit):
    """A source whose frames have the lowest bit of a random 1 % of their pixels flipped."""

    def __init__(self, source: Any) -> None:
        self._source = source

    def __iter__(self) -> Iterator[Frame]:
        rng = np.random.default_rng(1)
        for frame in self._source:
            image = frame.image.copy()
            image[rng.random(image.shape[:2]) < 0.01] ^= 1
            yield dataclasses.replace(frame, image=image)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._source, name)

    def close(self) -> None:
        self._source.close()


def run(clip: str, engine: str, perturb: bool) -> list[FrameRecord]:
    base = Config()
    landmarks = base.landmarks.model_copy(update={"engine": engine})
    config = base.model_copy(update={"landmarks": landmarks})
    source = open_source(clip, config)
    options = RunOptions(clip, command="compare-engines", quiet=True)
    frames = FlippedBits(source) if perturb else source
    with build_run(config, options, source=frames) as built:
        return [processed.record for processed in built.frames()]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("clip")
    parser.add_argument("--baseline", action="store_true")
    args = parser.parse_args()
    if args.baseline:
        first, second = run(args.clip, "mediapipe", False), run(args.clip, "mediapipe", True)
        print(f"{args.clip}: MediaPipe against MediaPipe with 1 % of the lowest bits flipped")
    else:
        first, second = run(args.clip, "mediapipe", False), run(args.clip, "litert", False)
        print(f"{args.clip}: LiteRT engine against MediaPipe")
    faces = (sum(r.sample.face for r in first), sum(r.sample.face for r in second))
    print(f"frames {len(first)} / {len(second)}, driver found {faces[0]} / {faces[1]}")
    for name, field in FIELDS.items():
        a = np.array([np.nan if field(r) is None else field(r) for r in first], float)
        b = np.array([np.nan if field(r) is None else field(r) for r in second], float)
        both = ~np.isnan(a) & ~np.isnan(b)
        if both.any():
            d = np.abs(a - b)[both]
            print(
                f"  {name:<17} n {d.size:4d}  median {np.median(d):.4f}  "
                f"p99 {np.percentile(d, 99):.4f}  max {d.max():.4f}"
            )
    pairs = [
        (ra.sample.features.landmarks_px, rb.sample.features.landmarks_px)
        for ra, rb in zip(first, second, strict=False)
        if ra.sample.features is not None and rb.sample.features is not None
    ]
    if pairs:
        px = np.concatenate([np.abs(a[:, :2] - b[:, :2]).max(axis=1) for a, b in pairs])
        print(
            f"  landmarks_px      median {np.median(px):.4f}  p99 {np.percentile(px, 99):.4f}"
            f"  max {px.max():.4f}"
        )

    def alerts(records: list[FrameRecord]) -> list[tuple[float, str]]:
        return [(round(r.sample.t_s, 3), str(a.kind)) for r in records for a in r.alerts]

    same = alerts(first) == alerts(second)
    print(f"  alerts at the same times: {same} ({len(alerts(first))} alerts)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
