"""Full-range yaw: Center-CE within its range, blended continuously into the cylinder beyond it.

Pure numpy. Center-CE (the paper's eqs. 34-36) maps a true 90 deg to about 60 deg; on Pointing'04
its mean |estimate| is 52.9 / 56.4 / 56.8 deg at a labelled 60 / 75 / 90 deg. The cylinder
(eqs. 2-4) keeps growing but over-reads everything from 30 to 60 deg. All five paper models are
functions of the one ratio 2d/W, so none of them tells 60 from 75-90 deg by itself: the range cue
comes from MediaPipe's own facial-transformation-matrix yaw, which compresses large turns but
keeps growing with them. The blend (F1):

    w   = S((|yaw_matrix| - cue_start_deg) / (cue_end_deg - cue_start_deg)),
          S(u) = 3u^2 - 2u^3 on [0, 1] (smoothstep; 0 below, 1 above)
    yaw = (1 - w) * yaw_center_ce + w * yaw_cylinder

with yaw_cylinder = asin(clip(2d / W, -1, 1)) (eq. 4 with its argument clipped: +-90 deg where the
centre lies outside the boundaries). Both models share the sign of d and are continuous in the
boundaries and the centre, and w is continuous in the cue, so (F1) is continuous; it is exactly
Center-CE while |yaw_matrix| <= cue_start_deg and exactly antisymmetric under a mirror flip.
Without a matrix yaw it is Center-CE. The cue is never the label: it is measured on the image.

Constants 20 / 90 deg: global over all Pointing'04 dev subjects, chosen with a margin so that the
MAE within +-60 deg does not grow on either half of the subjects (docs/pose.md gives the per-bin
table, the leave-one-subject-out check and the study of other range cues). The ramp never reaches
w = 1 on real faces (the largest matrix yaw seen is about 70 deg): beyond 60 deg the result is a
cue-weighted compromise between the two models.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from roadgaze.pose.geometry import PAPER_CONSTANTS, FaceModelConstants, center_ce, is_scalar
from roadgaze.types import FloatArray

__all__ = [
    "DEFAULT_FULL_RANGE",
    "FullRangeConstants",
    "blend_weight",
    "clipped_cylinder_deg",
    "full_range_yaw_deg",
]


@dataclass(frozen=True, slots=True)
class FullRangeConstants:
    """Where the blend (F1) starts and would end, in degrees of |MediaPipe matrix yaw|."""

    cue_start_deg: float = 20.0
    cue_end_deg: float = 90.0

    def __post_init__(self) -> None:
        if not 0.0 <= self.cue_start_deg < self.cue_end_deg:
            raise ValueError(
                f"the blend needs 0 <= cue_start_deg < cue_end_deg, found "
                f"{self.cue_start_deg} and {self.cue_end_deg}"
            )


DEFAULT_FULL_RANGE = FullRangeConstants()


def _scalar_or_array(values: FloatArray) -> Any:
    return float(values) if values.ndim == 0 else values


def clipped_cylinder_deg(x_left: Any, x_right: Any, x_center: Any) -> Any:
    """Cylindrical yaw, eqs. 2-4, asin(2d / W) with the argument clipped to [-1, 1]; degrees.

    NaN only for a non-finite input or W <= 0. Float in gives float out.
    """
    left = np.asarray(x_left, dtype=np.float64)
    right = np.asarray(x_right, dtype=np.float64)
    center = np.asarray(x_center, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        width = right - left
        ratio = (2.0 * center - left - right) / np.where(width > 0, width, np.nan)
        yaw = np.degrees(np.arcsin(np.clip(ratio, -1.0, 1.0)))
    return _scalar_or_array(np.asarray(yaw, dtype=np.float64))


def blend_weight(mediapipe_yaw_deg: Any, constants: FullRangeConstants = DEFAULT_FULL_RANGE) -> Any:
    """w of (F1) in [0, 1]; 0 where the matrix yaw is missing (None or NaN)."""
    cue = np.abs(
        np.asarray(np.nan if mediapipe_yaw_deg is None else mediapipe_yaw_deg, dtype=np.float64)
    )
    span = constants.cue_end_deg - constants.cue_start_deg
    with np.errstate(invalid="ignore"):
        u = np.clip((cue - constants.cue_start_deg) / span, 0.0, 1.0)
        weight = u * u * (3.0 - 2.0 * u)
    return _scalar_or_array(np.asarray(np.where(np.isfinite(weight), weight, 0.0)))


def full_range_yaw_deg(
    x_left: Any,
    x_right: Any,
    x_center: Any,
    mediapipe_yaw_deg: Any,
    constants: FullRangeConstants = DEFAULT_FULL_RANGE,
    face: FaceModelConstants = PAPER_CONSTANTS,
) -> Any:
    """(F1): the service's yaw in degrees (> 0 = the driver's own left); float in gives float out.

    `mediapipe_yaw_deg` None or NaN gives plain Center-CE. NaN where Center-CE is undefined.
    """
    if is_scalar(x_left, x_right, x_center) and (
        mediapipe_yaw_deg is None or is_scalar(mediapipe_yaw_deg)
    ):
        return _full_range_of_scalars(x_left, x_right, x_center, mediapipe_yaw_deg, constants, face)
    inner = np.asarray(center_ce(x_left, x_right, x_center, face), dtype=np.float64)
    outer = np.asarray(clipped_cylinder_deg(x_left, x_right, x_center), dtype=np.float64)
    weight = np.asarray(blend_weight(mediapipe_yaw_deg, constants), dtype=np.float64)
    outer = np.where(np.isfinite(outer), outer, inner)
    return _scalar_or_array((1.0 - weight) * inner + weight * outer)


def _full_range_of_scalars(
    x_left: float,
    x_right: float,
    x_center: float,
    mediapipe_yaw_deg: float | None,
    constants: FullRangeConstants,
    face: FaceModelConstants,
) -> float:
    """(F1) for one face in plain floats: the per-frame path, the same operations in the same
    order as the array path above (`tests/pose/test_fullrange.py` checks that both agree)."""
    inner = float(center_ce(x_left, x_right, x_center, face))
    cue = math.nan if mediapipe_yaw_deg is None else abs(mediapipe_yaw_deg)
    span = constants.cue_end_deg - constants.cue_start_deg
    u = _clip((cue - constants.cue_start_deg) / span, 0.0, 1.0)
    weight = u * u * (3.0 - 2.0 * u)
    if not math.isfinite(weight):  # no cue: plain Center-CE
        return inner
    width = x_right - x_left
    ratio = (2.0 * x_center - x_left - x_right) / width if width > 0 else math.nan
    outer = math.degrees(math.asin(_clip(ratio, -1.0, 1.0)))  # NaN stays NaN
    if not math.isfinite(outer):
        outer = inner
    return (1.0 - weight) * inner + weight * outer


def _clip(value: float, low: float, high: float) -> float:
    """`np.clip` of one float: NaN stays NaN."""
    return value if math.isnan(value) else min(max(value, low), high)
