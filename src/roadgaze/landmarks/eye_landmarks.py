"""Which of MediaPipe's 478 landmarks are the eyes, and their roll-removed points in plain floats.

The eye measures (`roadgaze.landmarks.eyes`) read 18 landmarks: per eye the two corners, three
upper/lower lid pairs and the iris centre. `upright_eye_points` removes the head's roll from
those only, as `remove_roll` does for all 478, so the per-frame path stays in plain floats.
Sides are the person's own: 33/133 and iris 468 are the right eye (image left for an unmirrored
camera), 263/362 and iris 473 the left.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from roadgaze.landmarks.features import LEFT_EYE_OUTER, RIGHT_EYE_OUTER
from roadgaze.types import FloatArray

__all__ = [
    "EYES",
    "EYE_LANDMARKS",
    "LEFT_EYE",
    "RIGHT_EYE",
    "EyeIndices",
    "UprightPoints",
    "eye_width_px",
    "lid_openness",
    "upright_eye_points",
    "xy",
]


@dataclass(frozen=True, slots=True)
class EyeIndices:
    """MediaPipe landmark indices and blendshape names of one eye (the person's own side)."""

    side: str
    outer: int
    inner: int
    lid_pairs: tuple[tuple[int, int], ...]
    """(upper, lower) lid landmarks, the centre pair first."""
    iris_center: int
    iris_ring: tuple[int, int, int, int]
    """Iris contour: image right, top, image left, bottom."""
    contour: tuple[int, ...]
    """The eye opening as a closed loop: outer corner, upper lid, inner corner, lower lid."""
    lateral: float
    """+1 when the eye's outer corner lies toward the image right (the person's left eye)."""
    blink: str
    look_in: str
    look_out: str
    look_up: str
    look_down: str


RIGHT_EYE = EyeIndices(
    side="right",
    outer=33,
    inner=133,
    lid_pairs=((159, 145), (158, 153), (160, 144)),
    iris_center=468,
    iris_ring=(469, 470, 471, 472),
    contour=(33, 246, 161, 160, 159, 158, 157, 173, 133, 155, 154, 153, 145, 144, 163, 7),
    lateral=-1.0,
    blink="eyeBlinkRight",
    look_in="eyeLookInRight",
    look_out="eyeLookOutRight",
    look_up="eyeLookUpRight",
    look_down="eyeLookDownRight",
)
LEFT_EYE = EyeIndices(
    side="left",
    outer=263,
    inner=362,
    lid_pairs=((386, 374), (385, 380), (387, 373)),
    iris_center=473,
    iris_ring=(474, 475, 476, 477),
    contour=(263, 466, 388, 387, 386, 385, 384, 398, 362, 382, 381, 380, 374, 373, 390, 249),
    lateral=1.0,
    blink="eyeBlinkLeft",
    look_in="eyeLookInLeft",
    look_out="eyeLookOutLeft",
    look_up="eyeLookUpLeft",
    look_down="eyeLookDownLeft",
)
EYES = (RIGHT_EYE, LEFT_EYE)
EYE_LANDMARKS = tuple(
    sorted(
        {RIGHT_EYE_OUTER, LEFT_EYE_OUTER}
        | {i for e in EYES for i in (e.outer, e.inner, e.iris_center)}
        | {i for e in EYES for pair in e.lid_pairs for i in pair}
    )
)
"""The landmarks `eye_features` measures (corners, lids, iris centres; the eye line's ends)."""
_EYE_ROWS = np.array(EYE_LANDMARKS)
_RIGHT_OUTER_ROW = EYE_LANDMARKS.index(RIGHT_EYE_OUTER)
_LEFT_OUTER_ROW = EYE_LANDMARKS.index(LEFT_EYE_OUTER)

UprightPoints = Mapping[int, tuple[float, float]] | FloatArray
"""Roll-removed landmark (x, y) by landmark index: `upright_eye_points`' mapping, or an (N, 2)
array such as `remove_roll`'s."""


def lid_openness(upright_px: UprightPoints, eye: EyeIndices, scale_px: float) -> float:
    """Mean vertical lid gap of the eye's lid pairs / `scale_px` (negative when lids cross)."""
    total = 0.0
    for upper, lower in eye.lid_pairs:
        total += xy(upright_px, lower)[1] - xy(upright_px, upper)[1]
    return total / len(eye.lid_pairs) / scale_px


def eye_width_px(upright_px: UprightPoints, eye: EyeIndices) -> float:
    """Outer to inner corner of one eye in the image, pixels."""
    outer_x, outer_y = xy(upright_px, eye.outer)
    inner_x, inner_y = xy(upright_px, eye.inner)
    return math.hypot(outer_x - inner_x, outer_y - inner_y)


def upright_eye_points(points: FloatArray, roll_deg: float) -> dict[int, tuple[float, float]]:
    """The roll-removed (x, y) of the landmarks the eye measures use (`EYE_LANDMARKS`), by index:
    `remove_roll` on those points only, in plain floats."""
    # `take` with a ready index array: fancy indexing with a list converts the list every call.
    rows: list[list[float]] = points.take(_EYE_ROWS, axis=0)[:, :2].tolist()
    pivot_x = 0.5 * (rows[_RIGHT_OUTER_ROW][0] + rows[_LEFT_OUTER_ROW][0])
    pivot_y = 0.5 * (rows[_RIGHT_OUTER_ROW][1] + rows[_LEFT_OUTER_ROW][1])
    angle = math.radians(roll_deg)
    cos_a, sin_a = math.cos(angle), math.sin(angle)
    upright = {}
    for index, (x, y) in zip(EYE_LANDMARKS, rows, strict=True):
        dx, dy = x - pivot_x, y - pivot_y
        upright[index] = (cos_a * dx - sin_a * dy + pivot_x, sin_a * dx + cos_a * dy + pivot_y)
    return upright


def xy(upright_px: UprightPoints, index: int) -> tuple[float, float]:
    """Landmark `index`'s (x, y) as floats."""
    point = upright_px[index]
    return float(point[0]), float(point[1])
