"""Head pitch: the vertical analogue of the paper's CE model, and the service's pitch. Pure numpy.

Pitch is in degrees, > 0 = looking up; it is the elevation of the face's forward direction (nod
first, then turn about the vertical axis), the convention of Pointing'04's tilt and of
`roadgaze.landmarks.angles_from_matrix_deg`. Derivation, closed-form check and measurements:
docs/pose.md.

Geometric model (vertical CE). Three points on the face's mid-line, measured in the roll-removed
image (y grows down, pixels): the top `y_top` (MediaPipe landmark 10, forehead), the bottom
`y_bottom` (152, chin) and the centre `y_center` (1, nose tip). With a = half the top-bottom
height, the nose tip `drop * a` below the top/bottom midpoint and `depth * a` in front of it, and
the top `2 * lean * a` in front of the bottom, a nod by p about any horizontal axis gives

    d = (y_top + y_bottom)/2 - y_center = a (depth sin p - drop cos p)        (P1)
    H = y_bottom - y_top                = 2a (cos p + lean sin p)               (P2)
    q = 2d / H = (depth sin p - drop cos p) / (cos p + lean sin p)             (P3)
    tan p = (q + drop) / (depth - lean q)                  (the estimator)     (P4)

The pivot, the face's size and its position cancel in q, as the pivot cancels in the paper's
eqs. 53-55. The constants come from MediaPipe's canonical face mesh; nothing is fitted.

The service's default pitch is MediaPipe's matrix pitch with its deviation below the neutral pose
stretched by `DOWN_GAIN` (`head_pitch_deg`): it ranks Pointing'04's tilt better than (P4) and
separates the lap from level better (docs/pose.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.pose.geometry import is_scalar
from roadgaze.types import FloatArray

__all__ = [
    "CANONICAL_MIDLINE",
    "DOWN_GAIN",
    "MidlineConstants",
    "ProjectedMidline",
    "head_pitch_deg",
    "midline_forward_model",
    "midline_pitch_deg",
    "naive_pitch_error_deg",
]


@dataclass(frozen=True, slots=True)
class MidlineConstants:
    """The face's mid-line in units of a = half the top-bottom (landmark 10 to 152) height.

    depth: the nose tip in front of the top/bottom midpoint. drop: the nose tip below that midpoint
    in the frontal pose (the neutral offset). lean: the top in front of the bottom, over 2a.
    """

    depth: float = 0.35127
    drop: float = 0.06296
    lean: float = 0.01229


CANONICAL_MIDLINE = MidlineConstants()
"""From MediaPipe's canonical face mesh (in face_landmarker.task): landmark 10 at (up 8.262,
depth 4.482) cm, 152 at (-9.403, 4.264), 1 at (-1.127, 7.476); a = 8.833 cm."""

DOWN_GAIN = 1.48
"""MediaPipe's matrix pitch reads a downward turn too small: below the neutral its deviation is
multiplied by this. Fitted without labels: a least-absolute-deviation fit of the matrix pitch to
the geometric pitch (P4) on Pointing'04 dev faces with |Center-CE yaw| <= 30 (halves of the
subjects: 1.46 and 1.44). Upward the gain is 1: the synthetic truth shows no under-reading there."""


def _scalar_or_array(values: FloatArray) -> Any:
    return float(values) if values.ndim == 0 else values


def midline_pitch_deg(
    y_top_px: Any,
    y_bottom_px: Any,
    y_center_px: Any,
    constants: MidlineConstants = CANONICAL_MIDLINE,
) -> Any:
    """Pitch by (P4), degrees (> 0 = up); float in gives float out, arrays give an array.

    NaN where the geometry is impossible (a non-finite input or y_bottom <= y_top); no warning.
    """
    top = np.asarray(y_top_px, dtype=np.float64)
    bottom = np.asarray(y_bottom_px, dtype=np.float64)
    center = np.asarray(y_center_px, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        height = bottom - top
        offset = 0.5 * (top + bottom) - center
        usable = np.isfinite(height) & np.isfinite(offset) & (height > 0)
        ratio = np.where(usable, 2.0 * offset / np.where(usable, height, 1.0), np.nan)
        pitch = np.degrees(
            np.arctan2(ratio + constants.drop, constants.depth - constants.lean * ratio)
        )
    return _scalar_or_array(np.asarray(pitch, dtype=np.float64))


@dataclass(frozen=True, slots=True)
class ProjectedMidline:
    """Image y (down, pixels) of the top, bottom and centre points from the forward model."""

    y_top: FloatArray
    y_bottom: FloatArray
    y_center: FloatArray


def midline_forward_model(
    true_pitch_deg: npt.ArrayLike,
    half_height_px: float = 150.0,
    pivot_y_px: float = 240.0,
    pivot_below_px: float = 120.0,
    pivot_behind_px: float = 180.0,
    constants: MidlineConstants = CANONICAL_MIDLINE,
) -> ProjectedMidline:
    """(P1, P2) with an explicit neck pivot: the rigid mid-line nodded by p, seen orthographically.

    The top/bottom midpoint sits `pivot_below_px` above and `pivot_behind_px` in front of the
    pivot; the pivot projects to image row `pivot_y_px`. (P4) recovers p exactly for any pivot.
    """
    p = np.radians(np.asarray(true_pitch_deg, dtype=np.float64))
    a = half_height_px
    cos_p, sin_p = np.cos(p), np.sin(p)

    def image_y(up: float, depth: float) -> FloatArray:
        """A point (up, depth) relative to the pivot, nodded by p: up' = up cos p + depth sin p."""
        return np.asarray(
            pivot_y_px - (pivot_below_px + up) * cos_p - (pivot_behind_px + depth) * sin_p,
            dtype=np.float64,
        )

    return ProjectedMidline(
        y_top=image_y(a, constants.lean * a),
        y_bottom=image_y(-a, -constants.lean * a),
        y_center=image_y(-constants.drop * a, constants.depth * a),
    )


def naive_pitch_error_deg(
    true_pitch_deg: npt.ArrayLike, constants: MidlineConstants = CANONICAL_MIDLINE
) -> FloatArray:
    """Closed-form error (estimate minus truth, degrees) of the offset-free estimator
    tan p^ = q / depth (drop = lean = 0) on the forward model (P5):

        p^ - p = atan((depth tan p - drop) / (depth (1 + lean tan p))) - p

    At p = 0 it is -atan(drop / depth), -10.2 deg for the canonical face: the neutral offset (P4)
    removes.
    """
    p = np.radians(np.asarray(true_pitch_deg, dtype=np.float64))
    tan_p = np.tan(p)
    c = constants
    estimate = np.arctan((c.depth * tan_p - c.drop) / (c.depth * (1.0 + c.lean * tan_p)))
    return np.asarray(np.degrees(estimate - p), dtype=np.float64)


def head_pitch_deg(
    model_pitch_deg: Any, neutral_pitch_deg: Any = 0.0, down_gain: float = DOWN_GAIN
) -> Any:
    """The pitch with its deviation below the neutral stretched: neutral + (pitch - neutral) times
    `down_gain` below the neutral, times 1 above it. Degrees, > 0 = up; continuous.

    Stills take neutral 0; a stream takes the monitor's learned neutral pitch, so the kink sits at
    the driver's road-ahead pose, not at the camera's axis. Float in gives float out, arrays give
    an array; NaN stays NaN.
    """
    if is_scalar(model_pitch_deg, neutral_pitch_deg):  # the per-frame path, in plain floats
        offset = model_pitch_deg - neutral_pitch_deg
        return float(neutral_pitch_deg + (down_gain * offset if offset < 0.0 else offset))
    pitch = np.asarray(model_pitch_deg, dtype=np.float64)
    neutral = np.asarray(neutral_pitch_deg, dtype=np.float64)
    offset = pitch - neutral
    with np.errstate(invalid="ignore"):
        stretched = neutral + np.where(offset < 0.0, down_gain * offset, offset)
    return _scalar_or_array(np.asarray(stretched, dtype=np.float64))
