#!/usr/bin/env python3
"""Why the head yaw reads short under a long beard: the study behind docs/pose.md's "Facial hair".

    .venv/bin/python scripts/beard-yaw-study.py [DATASET_DIR] [--workers N]

1. Renders the conformance face (320x320, the eyes at rest) at yaw -45..45 (5 deg steps) and
   pitch -10 / 0 / +12, plain, under `stubble` and under `beard`, and runs the still landmarker
   on each. For each landmark choice (`LandmarkChoice`: the boundary band and the centre) it
   prints Center-CE's MAE against Center-CE of the rendered mesh itself (exact landmarks), its
   mean error over yaw -40..-25 (the side where the beard hurts), and the mean |beard - plain|.
2. Splits the beard's change at each pose into the centre's part and the boundaries' part
   (Center-CE with the beard's centre and the plain boundaries, and the other way round).
3. Scores the same choices on Pointing'04 (default: dev subjects 1-10 beside the checkout),
   |yaw| <= 60, all subjects together (`roadgaze.evaluation.compare_landmark_choices`).
Progress goes to stderr, the tables to stdout.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from roadgaze.config import Config  # noqa: E402
from roadgaze.evaluation import (  # noqa: E402
    compare_landmark_choices,
    estimate_images,
    load_ground_truth,
)
from roadgaze.evaluation.images import still_detector  # noqa: E402
from roadgaze.landmarks.features import (  # noqa: E402
    DEFAULT_CHOICE,
    NOSE_TIP,
    LandmarkChoice,
    boundaries_and_center,
    remove_roll,
    roll_from_eyes_deg,
)
from roadgaze.landmarks.model_store import resolve_model  # noqa: E402
from roadgaze.pose.geometry import center_ce  # noqa: E402
from roadgaze.synth import EyeRenderer, load_photo  # noqa: E402
from roadgaze.synth.eyes import EyeState  # noqa: E402
from roadgaze.synth.outfit import Outfit  # noqa: E402

SIZE = (320, 320)
YAWS_DEG = tuple(float(y) for y in range(-45, 46, 5))
PITCHES_DEG = (-10.0, 0.0, 12.0)
CONDITIONS = ("none", "stubble", "beard")
CHOICES = (
    DEFAULT_CHOICE,
    LandmarkChoice("band [0.2, 0.5] / nose 1+4", (NOSE_TIP, 4), None, (0.2, 0.5)),
    LandmarkChoice("band [0.1, 0.3] / nose 1+4", (NOSE_TIP, 4), None, (0.1, 0.3)),
    LandmarkChoice("band [0, 0.3] / nose 1+4", (NOSE_TIP, 4), None, (0.0, 0.3)),
    LandmarkChoice("band [0, 0.2] / nose 1+4", (NOSE_TIP, 4), None, (0.0, 0.2)),
    LandmarkChoice("band [-0.2, 0.2] (eye height) / nose 1+4", (NOSE_TIP, 4), None, (-0.2, 0.2)),
    LandmarkChoice("band [0.1, 0.5] / ridge 4", (4,), None, (0.1, 0.5)),
    LandmarkChoice("band [0.1, 0.5] / ridge 4+5", (4, 5), None, (0.1, 0.5)),
    LandmarkChoice("band [0.1, 0.5] / ridge 5", (5,), None, (0.1, 0.5)),
)
Points = np.ndarray


def features(points: Points, choice: LandmarkChoice) -> tuple[float, float, float]:
    """x_left, x_right, x_center of (478, 2|3) landmarks, roll removed, under `choice`."""
    upright = remove_roll(points[:, :2], roll_from_eyes_deg(points[:, :2]))
    return boundaries_and_center(upright, choice)


def render_stills() -> tuple[dict[tuple[str, float, float], Points | None], dict]:
    """Landmarks found per (condition, yaw, pitch), and the rendered mesh per (yaw, pitch)."""
    config = Config()
    renderer = EyeRenderer(load_photo(), SIZE, config=config, eyeball_at_rest=True)
    detector = still_detector(config.landmarks, resolve_model(config.model))
    found: dict[tuple[str, float, float], Points | None] = {}
    try:
        for condition in CONDITIONS:
            outfit = Outfit(renderer, [] if condition == "none" else [condition])
            for pitch in PITCHES_DEG:
                for yaw in YAWS_DEG:
                    driver = detector.detect(outfit.render(yaw, pitch, EyeState())).driver
                    found[(condition, yaw, pitch)] = None if driver is None else driver.landmarks_px
            print(f"rendered and measured: {condition}", file=sys.stderr)
    finally:
        detector.close()
    mesh = {(y, p): renderer.turned_points(y, p) for p in PITCHES_DEG for y in YAWS_DEG}
    return found, mesh


def synthetic_table(found: dict, mesh: dict) -> None:
    print("| landmark choice | condition | MAE vs mesh | mean error, yaw -40..-25 | |vs plain| |")
    print("|---|---|---|---|---|")
    for choice in CHOICES:
        plain: dict[tuple[float, float], float] = {}
        for condition in CONDITIONS:
            errors, short, moved = [], [], []
            for pitch in PITCHES_DEG:
                for yaw in YAWS_DEG:
                    points = found[(condition, yaw, pitch)]
                    if points is None:
                        continue
                    estimate = center_ce(*features(points, choice))
                    exact = center_ce(*features(mesh[(yaw, pitch)], choice))
                    if not (np.isfinite(estimate) and np.isfinite(exact)):
                        continue
                    errors.append(abs(estimate - exact))
                    if -40 <= yaw <= -25:
                        short.append(estimate - exact)
                    if condition == "none":
                        plain[(yaw, pitch)] = estimate
                    elif (yaw, pitch) in plain:
                        moved.append(abs(estimate - plain[(yaw, pitch)]))
            change = f"{np.mean(moved):.2f}" if moved else "-"
            print(
                f"| {choice.name} | {condition} | {np.mean(errors):.2f} | "
                f"{np.mean(short):+.2f} | {change} |"
            )


def split_table(found: dict, mesh: dict) -> None:
    print("\n| pitch | yaw | mesh | plain | beard | beard's centre only | beard's boundaries |")
    print("|---|---|---|---|---|---|---|")
    for pitch in PITCHES_DEG:
        for yaw in (-45.0, -40.0, -35.0, -30.0, -25.0, 30.0, 40.0):
            plain, beard = found[("none", yaw, pitch)], found[("beard", yaw, pitch)]
            if plain is None or beard is None:
                continue
            left, right, centre = features(plain, DEFAULT_CHOICE)
            b_left, b_right, b_centre = features(beard, DEFAULT_CHOICE)
            cells = (
                center_ce(*features(mesh[(yaw, pitch)], DEFAULT_CHOICE)),
                center_ce(left, right, centre),
                center_ce(b_left, b_right, b_centre),
                center_ce(left, right, b_centre),
                center_ce(b_left, b_right, centre),
            )
            print(f"| {pitch:+.0f} | {yaw:+.0f} | " + " | ".join(f"{c:.1f}" for c in cells) + " |")


def pointing04_table(dataset: Path, workers: int) -> None:
    config = Config()
    truths, _ = load_ground_truth(dataset)
    jobs = [(dataset / truth.file, truth.file) for truth in truths]
    estimates = list(
        estimate_images(
            jobs, config.landmarks, resolve_model(config.model), workers=workers, config=config
        )
    )
    print("\n| landmark choice | Pointing'04 Center-CE MAE, \\|yaw\\| <= 60 | valid % |")
    print("|---|---|---|")
    for choice, stats in compare_landmark_choices(truths, estimates, CHOICES):
        ce = stats["center_ce"]
        print(f"| {choice.name} | {ce.mae_deg:.2f} | {100 * ce.n_valid / ce.n_images:.1f} |")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "dataset", nargs="?", type=Path, default=REPO.parent / "shared/data/pointing04-dev"
    )
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    logging.disable(logging.WARNING)
    found, mesh = render_stills()
    synthetic_table(found, mesh)
    split_table(found, mesh)
    if (args.dataset / "ground_truth.csv").is_file():
        pointing04_table(args.dataset, args.workers)
    else:
        print(f"no {args.dataset / 'ground_truth.csv'}: Pointing'04 skipped", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
