#!/usr/bin/env python3
"""Draw docs/images/noise-conditions.png: every condition a conformance scenario can render, on
the same face, as the scenarios render it (`roadgaze.conformance.clips`, sensor noise included).

    .venv/bin/python scripts/noise-contact-sheet.py [--out FILE]

Each tile is the face looking at the road (the camera in front) but for `talking` (mid-syllable)
and the two hands (a camera in front, one on the steering column); the second row turns the head
30 deg to the side and 20 deg down, to show the worn things following it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from roadgaze.conformance.clips import ScenarioRenderer
from roadgaze.conformance.model import Scenario, Segment
from roadgaze.synth import EyeRenderer, load_photo

OUT = Path(__file__).resolve().parents[1] / "docs" / "images" / "noise-conditions.png"
TILES = (
    ("day", (), "front"),
    ("night", ("night",), "front"),
    ("clear sunglasses", ("clear_sunglasses",), "front"),
    ("dark sunglasses", ("dark_sunglasses",), "front"),
    ("stubble", ("stubble",), "front"),
    ("beard", ("beard",), "front"),
    ("mask", ("mask",), "front"),
    ("talking", ("talking",), "front"),
    ("cap", ("cap",), "front"),
    ("hat", ("hat",), "front"),
    ("fringe", ("fringe",), "front"),
    ("eyelash makeup", ("eyelash_makeup",), "front"),
    ("hand, camera in front", ("hand_at_12",), "front"),
    ("hand, steering column", ("hand_at_12",), "steering_column"),
)
TILE = (112, 128)
"""Width, height of a tile's picture (the face and what is worn, from a 320 x 320 frame)."""


def tile(
    renderer: ScenarioRenderer, conditions: tuple[str, ...], mounting: str, pose: Segment
) -> np.ndarray:
    import cv2

    scenario = Scenario("sheet", "", (pose,), None, (), mounting, conditions)
    frames = list(renderer.frames(scenario))
    frame = frames[len(frames) // 2]
    if "talking" in conditions:  # the widest-open frame of the drive
        still = list(renderer.frames(Scenario("sheet", "", (pose,), None, (), mounting)))
        moved = [
            np.abs(f.astype(int) - s.astype(int))[170:230].mean()
            for f, s in zip(frames, still, strict=True)
        ]
        frame = frames[int(np.argmax(moved))]
    crop = frame[28:268, 55:265]
    return np.asarray(cv2.resize(crop, TILE, interpolation=cv2.INTER_AREA))


def main() -> int:
    import cv2

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    renderer = ScenarioRenderer(EyeRenderer(load_photo(), (320, 320), eyeball_at_rest=True), 15.0)
    columns = []
    for name, conditions, mounting in TILES:
        ahead = tile(renderer, conditions, mounting, Segment(2.0))
        turned = tile(renderer, conditions, mounting, Segment(2.0, -30.0, -20.0))
        label = np.full((18, TILE[0], 3), 255, dtype=np.uint8)
        cv2.putText(label, name, (3, 13), cv2.FONT_HERSHEY_SIMPLEX, 0.34, (0, 0, 0), 1, cv2.LINE_AA)
        columns.append(np.vstack([label, ahead, turned]))
    half = (len(columns) + 1) // 2
    sheet = np.vstack([np.hstack(columns[:half]), np.hstack(columns[half:])])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    from PIL import Image  # matplotlib's dependency: a palette keeps the page light

    rgb = Image.fromarray(np.ascontiguousarray(sheet[..., ::-1]))
    rgb.quantize(colors=256, method=Image.Quantize.MAXCOVERAGE).save(args.out, optimize=True)
    print(f"wrote {args.out} ({args.out.stat().st_size // 1024} kB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
