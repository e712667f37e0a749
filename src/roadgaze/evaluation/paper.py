"""The paper's synthetic experiments: Tables III and IV, Figs. 4 and 5.

Experiment 1 feeds the exact forward model (eqs. 53-55) to every yaw model. Experiment 2 draws
the top view of the rotated head ellipse and its centre line into a 640x480 image with OpenCV,
as the paper does, and measures the boundaries (bounding box of the drawn ellipse) and the
centre (where the centre line leaves the ellipse) from the pixels, so it adds the quantisation
a real image has.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roadgaze.evaluation.stats import RangeStats, range_stats
from roadgaze.pose.geometry import PAPER_CONSTANTS, YAW_MODELS, FaceModelConstants
from roadgaze.pose.geometry import forward_model as _forward_model
from roadgaze.types import FloatArray

YAW_RANGES_DEG: tuple[tuple[float, float], ...] = ((0, 30), (30, 60), (60, 90), (0, 90))
"""Ranges of |true yaw| over which the paper's tables report errors."""

IMAGE_SIZE = (640, 480)
PIVOT_PX = (320.0, 202.5)
HALF_WIDTH_PX = 150.0
_SUBPIXEL_BITS = 4


@dataclass(frozen=True, slots=True)
class Experiment:
    """True yaw and each model's estimate, degrees."""

    name: str
    true_yaw_deg: FloatArray
    estimates_deg: dict[str, FloatArray]

    def errors_deg(self, model: str) -> FloatArray:
        return self.estimates_deg[model] - self.true_yaw_deg


def experiment_1(
    true_yaw_deg: FloatArray | None = None,
    constants: FaceModelConstants = PAPER_CONSTANTS,
) -> Experiment:
    """Every model on the exact forward model, r = 150 px, x0 = 320 (the paper's Experiment 1)."""
    truth = np.arange(-90.0, 91.0, 1.0) if true_yaw_deg is None else true_yaw_deg
    face = _forward_model(truth, HALF_WIDTH_PX, PIVOT_PX[0], constants)
    estimates = {
        name: np.asarray(model(face.x_left, face.x_right, face.x_center, constants))
        for name, model in YAW_MODELS.items()
    }
    return Experiment("Table III, Experiment 1 (forward model)", truth, estimates)


def draw_head_top_view(
    true_yaw_deg: float, constants: FaceModelConstants = PAPER_CONSTANTS
) -> tuple[np.ndarray, np.ndarray]:
    """Top view of the head turned by `true_yaw_deg`: a filled ellipse mask and a centre-line mask.

    The camera looks from the bottom of the image (y grows towards it). The ellipse has
    half-width r = 150 px and half-depth beta r; its centre sits alpha r in front of the neck
    pivot (320, 202.5) and both turn about the pivot. Positive yaw moves the nose to image right.
    """
    import cv2

    r, alpha, beta = HALF_WIDTH_PX, constants.alpha, constants.beta
    t = np.radians(true_yaw_deg)
    nose_direction = np.array([np.sin(t), np.cos(t)])
    center = np.array(PIVOT_PX) + alpha * r * nose_direction
    scale = 1 << _SUBPIXEL_BITS
    width, height = IMAGE_SIZE
    ellipse = np.zeros((height, width), np.uint8)
    # OpenCV's angle turns the first axis from +x towards +y; the depth axis is the second one.
    cv2.ellipse(
        ellipse,
        tuple(round(v * scale) for v in center),
        (round(r * scale), round(beta * r * scale)),
        -true_yaw_deg,
        0,
        360,
        255,
        thickness=-1,
        lineType=cv2.LINE_8,
        shift=_SUBPIXEL_BITS,
    )
    line = np.zeros_like(ellipse)
    far_end = center + 2.0 * beta * r * nose_direction
    cv2.line(
        line,
        tuple(round(v * scale) for v in center),
        tuple(round(v * scale) for v in far_end),
        255,
        thickness=1,
        lineType=cv2.LINE_8,
        shift=_SUBPIXEL_BITS,
    )
    return ellipse, line


def measure_top_view(ellipse: np.ndarray, line: np.ndarray) -> tuple[float, float, float]:
    """x_left, x_right from the ellipse's bounding box; x_center where the centre line leaves it."""
    columns = np.flatnonzero(ellipse.any(axis=0))
    x_left, x_right = float(columns[0]), float(columns[-1])
    inside = np.argwhere((line > 0) & (ellipse > 0))  # rows of (y, x)
    # The nose tip is the crossing farthest along the line, i.e. nearest the camera (largest y);
    # for a head turned 90 deg the line is horizontal, so break ties by distance from the axis.
    far = inside[np.lexsort((np.abs(inside[:, 1] - PIVOT_PX[0]), inside[:, 0]))[-1]]
    return x_left, x_right, float(far[1])


def experiment_2(
    true_yaw_deg: FloatArray | None = None,
    constants: FaceModelConstants = PAPER_CONSTANTS,
) -> Experiment:
    """Every model on boundaries and centre measured from drawn 640x480 top views."""
    truth = np.arange(-90.0, 91.0, 1.0) if true_yaw_deg is None else true_yaw_deg
    measured = np.array([measure_top_view(*draw_head_top_view(t, constants)) for t in truth])
    estimates = {
        name: np.asarray(model(measured[:, 0], measured[:, 1], measured[:, 2], constants))
        for name, model in YAW_MODELS.items()
    }
    return Experiment("Table IV, Experiment 2 (drawn 640x480 top view)", truth, estimates)


def range_errors(
    experiment: Experiment, ranges: Sequence[tuple[float, float]] = YAW_RANGES_DEG
) -> list[RangeStats]:
    """The paper's table rows: per model and |true yaw| range (both ends included), the errors;
    the table shows RMSE and max, and `stats.undefined` counts what the model could not explain."""
    return [
        range_stats(model, experiment.true_yaw_deg, estimate, low, high, include_high=True)
        for model, estimate in experiment.estimates_deg.items()
        for low, high in ranges
    ]


def format_table(experiment: Experiment, rows: Sequence[RangeStats]) -> str:
    """A plain-text table: one line per model, RMSE / max for each range."""
    ranges = list(dict.fromkeys((row.low_deg, row.high_deg) for row in rows))
    header = f"{'model':<12}" + "".join(f"  [{lo:>2.0f},{hi:>2.0f}] RMSE/max" for lo, hi in ranges)
    lines = [experiment.name, header, "-" * len(header)]
    for model in experiment.estimates_deg:
        cells = {(r.low_deg, r.high_deg): r.stats for r in rows if r.label == model}
        text = f"{model:<12}"
        for key in ranges:
            cell = cells[key]
            text += f"  {cell.rmse_deg:>7.3f} /{cell.max_deg:>7.3f}"
        lines.append(text)
    return "\n".join(lines)


def save_plots(experiment: Experiment, directory: Path, stem: str) -> list[Path]:
    """Fig. 4/5-style PNGs: estimated vs true yaw, and error vs true yaw, one curve per model."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for kind in ("estimate", "error"):
        figure, axes = plt.subplots(figsize=(7, 5), dpi=110)
        for model, estimate in experiment.estimates_deg.items():
            values = estimate if kind == "estimate" else estimate - experiment.true_yaw_deg
            axes.plot(experiment.true_yaw_deg, values, label=model, linewidth=1.5)
        if kind == "estimate":
            axes.plot(experiment.true_yaw_deg, experiment.true_yaw_deg, "k:", label="truth")
        axes.set_xlabel("true yaw (deg)")
        axes.set_ylabel("estimated yaw (deg)" if kind == "estimate" else "error (deg)")
        axes.set_title(f"{experiment.name}: {kind}")
        axes.grid(True, alpha=0.3)
        axes.legend()
        path = directory / f"{stem}_{kind}.png"
        figure.tight_layout()
        figure.savefig(path)
        plt.close(figure)
        written.append(path)
    return written
