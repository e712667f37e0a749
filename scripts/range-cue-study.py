#!/usr/bin/env python3
"""Which range cue tells when Center-CE saturates: the study behind docs/pose.md's full-range cue.

    .venv/bin/python scripts/range-cue-study.py [DATASET_DIR] [--cache NPZ] [--workers N]

Runs the landmark stage over a labelled data set with a `subject` column (default: Pointing'04
dev subjects 1-10 beside the checkout), or reads the `--cache` an earlier run wrote, then prints:
1. each candidate cue's mean and spread per |yaw| bin and how well it separates 45 from 60, 60 from
   75 and 75 from 90 deg (area under the ROC curve);
2. the full-range blend (F1) with each cue in place of the matrix yaw, its two constants re-fitted
   leaving each subject out by the shipped rule (`roadgaze.evaluation.full_range_cv`);
3. the trade-off any such blend faces, fitted on all subjects (in-sample, so optimistic): for a
   bound on how far every bin within +-60 may rise above Center-CE, the least the worse +-75 bin
   lies above the cylinder's.
Every cue uses only what MediaPipe's FaceLandmarker returns: the landmarks (x, y and z) and the
facial transformation matrix. Progress goes to stderr, the tables to stdout.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from roadgaze.config import Config  # noqa: E402
from roadgaze.evaluation import (  # noqa: E402
    GroundTruth,
    ImageEstimate,
    estimate_images,
    load_ground_truth,
)
from roadgaze.evaluation.full_range_cv import cross_validate_full_range  # noqa: E402
from roadgaze.evaluation.stats import separation_auc  # noqa: E402
from roadgaze.landmarks.features import FACE_OVAL, remove_roll  # noqa: E402
from roadgaze.landmarks.model_store import resolve_model  # noqa: E402
from roadgaze.pose.fullrange import (  # noqa: E402
    FullRangeConstants,
    clipped_cylinder_deg,
    full_range_yaw_deg,
)
from roadgaze.pose.geometry import center_ce, cylindrical  # noqa: E402

DEFAULT_DATASET = REPO.parent / "shared" / "data" / "pointing04-dev"
CONTOUR_PAIRS = ((234, 454), (93, 323), (132, 361), (58, 288), (127, 356), (162, 389),
                 (172, 397), (136, 365))  # fmt: skip
"""Face-oval landmarks of the person's right side and their mirror images on the left."""
CUES = (
    ("matrix yaw", "deg"),
    ("contour line 234-454", "deg"),
    ("eye line 33-263", "deg"),
    ("contour lines, median of 8", "deg"),
    ("nose depth / H", ""),
    ("nose off the eye midpoint / H", ""),
    ("centre to the boundary ahead / H", ""),
    ("face width / H", ""),
    ("oval beyond the nose tip", "share"),
    ("cylinder - Center-CE", "deg"),
)


def _line_deg(x: np.ndarray, z: np.ndarray, right: int, left: int) -> float:
    """The angle of a landmark pair's line out of the image plane, from the mesh's own depth."""
    return math.degrees(math.atan2(float(z[left] - z[right]), float(x[left] - x[right])))


def cues_of(e: ImageEstimate) -> list[float]:
    """The candidate cues of one face, signed so that they grow with the turn either way."""
    assert e.landmarks_px is not None and e.roll_deg is not None
    assert e.x_left_px is not None and e.x_right_px is not None and e.x_center_px is not None
    up = remove_roll(e.landmarks_px, e.roll_deg)
    x, y = up[:, 0], up[:, 1]
    z = np.asarray(e.landmarks_px[:, 2], dtype=np.float64)
    left, right, centre = e.x_left_px, e.x_right_px, e.x_center_px
    side = 1.0 if centre >= 0.5 * (left + right) else -1.0
    height = math.hypot(x[152] - x[10], y[152] - y[10])
    lines = [_line_deg(x, z, a, b) for a, b in CONTOUR_PAIRS]
    oval = np.array(FACE_OVAL)
    return [
        side * (e.mediapipe_yaw_deg or math.nan),
        side * lines[0],
        side * _line_deg(x, z, 33, 263),
        side * float(np.median(lines)),
        (0.5 * (z[234] + z[454]) - z[1]) / height,
        side * (x[1] - 0.5 * (x[33] + x[263])) / height,
        (right - centre if side > 0 else centre - left) / height,
        (right - left) / height,
        float(np.mean(side * (x[oval] - x[1]) > 0)),
        side * (float(clipped_cylinder_deg(left, right, centre)) - center_ce(left, right, centre)),
    ]


def collect(dataset: Path, cache: Path | None, workers: int) -> dict[str, np.ndarray]:
    if cache is not None and cache.is_file():
        return dict(np.load(cache, allow_pickle=False))
    truths, _ = load_ground_truth(dataset)
    config = Config()
    jobs = [(dataset / t.file, t.file) for t in truths]
    estimates = list(
        estimate_images(
            jobs,
            config.landmarks,
            resolve_model(config.model),
            workers=workers,
            progress=True,
            config=config,
        )
    )
    nan = [math.nan] * 3
    data = {
        "yaw": np.array([t.yaw_deg for t in truths]),
        "subject": np.array([t.subject or "" for t in truths]),
        "face": np.array([e.face for e in estimates]),
        "xyz": np.array(
            [[e.x_left_px, e.x_right_px, e.x_center_px] if e.face else nan for e in estimates],
            dtype=np.float64,
        ),
        "cues": np.array([cues_of(e) if e.face else [math.nan] * len(CUES) for e in estimates]),
    }
    if cache is not None:
        np.savez(cache, **data)
    return data


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dataset", type=Path, nargs="?", default=DEFAULT_DATASET)
    parser.add_argument("--cache", type=Path, help="features saved here, and read when present")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    data = collect(args.dataset, args.cache, args.workers)
    yaw, face, cues = data["yaw"], data["face"], data["cues"]
    left, right, centre = data["xyz"].T
    magnitude = np.abs(yaw)
    print("1. cue per |yaw| bin (mean +- sd over faces found) and ROC AUC between bins")
    print(
        f"{'cue':<34} "
        + " ".join(f"{b:>12.0f}" for b in (45, 60, 75, 90))
        + "  45|60  60|75  75|90"
    )
    for column, (name, _) in enumerate(CUES):
        value = cues[:, column]
        cells = " ".join(
            f"{np.nanmean(value[magnitude == b]):>6.2f}+-{np.nanstd(value[magnitude == b]):<4.2f}"
            for b in (45, 60, 75, 90)
        )
        aucs = [
            separation_auc(value[magnitude == a], value[magnitude == b])
            for a, b in ((45, 60), (60, 75), (75, 90))
        ]
        aucs = [max(a, 1.0 - a) for a in aucs]  # a cue may fall with the turn
        print(f"{name:<34} {cells}  " + "  ".join(f"{a:.3f}" for a in aucs))

    truths = [
        GroundTruth(str(i), float(y), 0.0, str(s))
        for i, (y, s) in enumerate(zip(yaw, data["subject"], strict=True))
    ]
    print("\n2. the blend with each cue, constants re-fitted leaving each subject out")
    print(
        f"{'cue':<34} {'|yaw|<=60':>9} {'all':>6} {'-75':>6} {'+75':>6} {'-90':>6} {'+90':>6}"
        "  folds without constants"
    )
    for column in (0, 1, 2, 3):
        estimates = [
            ImageEstimate(
                str(i),
                bool(f),
                x_left_px=float(left[i]),
                x_right_px=float(right[i]),
                x_center_px=float(centre[i]),
                mediapipe_yaw_deg=float(cues[i, column]),
            )
            if f
            else ImageEstimate(str(i), False)
            for i, f in enumerate(face)
        ]
        result = cross_validate_full_range(truths, estimates)
        assert result is not None
        by_bin = {c: per["service_cv"].mae_deg for c, per in result.bins}
        print(
            f"{CUES[column][0]:<34} {result.ranges['abs_yaw_le_60']['service_cv'].mae_deg:>9.2f} "
            f"{result.ranges['all']['service_cv'].mae_deg:>6.2f} "
            + " ".join(f"{by_bin[b]:>6.2f}" for b in (-75.0, 75.0, -90.0, 90.0))
            + f"  {sum(f.constants is None for f in result.folds)}"
        )

    print(
        "\n3. in-sample trade-off: bound on every +-60 bin's rise above Center-CE -> least rise "
        "of the worse +-75 bin above the cylinder"
    )
    inner = np.asarray(center_ce(left, right, centre))
    paper_cylinder = np.asarray(cylindrical(left, right, centre))
    bins = np.unique(yaw)

    def bin_mae(estimate: np.ndarray) -> dict[float, float]:
        error = np.abs(estimate - yaw)
        return {b: float(np.nanmean(np.where(face, error, np.nan)[yaw == b])) for b in bins}

    center_bins, cylinder_bins = bin_mae(inner), bin_mae(paper_cylinder)
    grid = np.arange(10.0, 100.0 + 1e-9, 2.5)
    for column in (0, 1, 2, 3):
        best: dict[float, float] = {}
        for start in grid:
            for end in grid[grid >= start + 5.0]:
                constants = FullRangeConstants(start, end)
                cue = cues[:, column]
                blended = np.asarray(full_range_yaw_deg(left, right, centre, cue, constants))
                per = bin_mae(blended)
                rise_in = max(per[b] - center_bins[b] for b in bins if abs(b) <= 60)
                rise_out = max(per[b] - cylinder_bins[b] for b in bins if abs(b) == 75)
                for bound in (0.1, 0.5, 1.0, 2.0):
                    if rise_in <= bound:
                        best[bound] = min(best.get(bound, math.inf), rise_out)
        cells = [f"<= {b:g}: {best.get(b, math.nan):.2f}" for b in (0.1, 0.5, 1.0, 2.0)]
        print(f"{CUES[column][0]:<34} " + "  ".join(cells))
    clipped = np.asarray(clipped_cylinder_deg(left, right, centre))
    pick = np.where(np.abs(yaw) >= 75, clipped, inner)
    error = np.where(face, np.abs(pick - yaw), np.nan)
    print(
        f"\noracle (the label picks Center-CE within +-60, the cylinder beyond): all poses "
        f"{np.nanmean(error):.2f} deg"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
