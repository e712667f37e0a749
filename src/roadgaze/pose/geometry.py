"""The yaw models of Narayanan, Kaimal & Bijlani (IEEE T-ITS 15(5), 2014): pure numpy, no I/O.

Every model maps the roll-removed x of the left face boundary, the right face boundary and the
face centre to a yaw in degrees. Image x grows to the right; yaw is positive when the centre is
right of the boundaries' midpoint, which for an unmirrored camera is the head turned to the
person's own left (ISO 8855). The models use only these three numbers, so they do not depend on
pitch, face size or where the face is in the image.

Impossible geometry gives NaN: `x_right <= x_left`, a NaN or infinite input, or a centre so far
from the midpoint that the model cannot explain it. No numpy warning is emitted.

Implementation note: each `yaw = asin(d / (b * r))` of the paper with
`r = 1/2 sqrt(W^2 - k (2d)^2)`, `W = x_right - x_left`, `d = x_center - (x_left + x_right)/2`,
is evaluated in the algebraically equal, well-conditioned form
`yaw = atan2(2d, sqrt(b^2 W^2 - (b^2 k + 1) (2d)^2))`, which is exact near +-90 deg where asin
loses half of its digits, and whose square-root argument is negative exactly when asin's argument
would exceed 1.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, overload

import numpy as np
import numpy.typing as npt

from roadgaze.types import FloatArray

if TYPE_CHECKING:
    from roadgaze.config import GeometryConfig

__all__ = [
    "PAPER_CONSTANTS",
    "YAW_MODELS",
    "FaceModelConstants",
    "ProjectedFace",
    "YawModel",
    "boundary_ce",
    "ce",
    "center_ce",
    "cylindrical",
    "ellipsoidal",
    "expected_error_deg",
    "forward_model",
]


@dataclass(frozen=True, slots=True)
class FaceModelConstants:
    """Anthropometric constants of the ellipsoidal face (the paper's values by default).

    alpha: neck pivot behind the ellipse centre, in units of the half face width r.
    beta: ratio of the ellipse's depth (major) to width (minor) axis.
    gamma_c: Center-CE's face-centre correction (eq. 34). gamma_b: Boundary-CE's (eq. 37).
    """

    alpha: float = 0.25
    beta: float = 1.25
    gamma_c: float = 0.1269
    gamma_b: float = 0.5774

    @classmethod
    def from_config(cls, config: GeometryConfig) -> FaceModelConstants:
        """The constants `[geometry]` configures."""
        return cls(config.alpha, config.beta, config.gamma_c, config.gamma_b)


PAPER_CONSTANTS = FaceModelConstants()


class YawModel(Protocol):
    """f(x_left, x_right, x_center) -> yaw_deg; float in gives float out, arrays give an array."""

    @overload
    def __call__(
        self,
        x_left: float,
        x_right: float,
        x_center: float,
        constants: FaceModelConstants = ...,
    ) -> float: ...

    @overload
    def __call__(
        self,
        x_left: npt.ArrayLike,
        x_right: npt.ArrayLike,
        x_center: npt.ArrayLike,
        constants: FaceModelConstants = ...,
    ) -> FloatArray: ...


def _inputs(
    x_left: npt.ArrayLike, x_right: npt.ArrayLike, x_center: npt.ArrayLike
) -> tuple[FloatArray, FloatArray, bool]:
    """Return face width W, twice the centre offset 2d, and whether the inputs were all scalar."""
    left = np.asarray(x_left, dtype=np.float64)
    right = np.asarray(x_right, dtype=np.float64)
    center = np.asarray(x_center, dtype=np.float64)
    if not (left.shape == right.shape == center.shape):
        raise ValueError(
            f"x_left, x_right and x_center must have equal shapes, "
            f"found {left.shape}, {right.shape}, {center.shape}"
        )
    with np.errstate(invalid="ignore", over="ignore"):
        width = right - left
        twice_offset = 2.0 * center - left - right
        bad = ~(np.isfinite(width) & np.isfinite(twice_offset) & (width > 0))
    width = np.where(bad, np.nan, width)
    return width, np.where(bad, np.nan, twice_offset), left.ndim == 0


def _finish(yaw_rad: FloatArray, scalar: bool) -> Any:
    yaw_deg = np.degrees(yaw_rad)
    return float(yaw_deg) if scalar else yaw_deg


def _atan_form(twice_offset: FloatArray, width: FloatArray, b: float, k: float) -> FloatArray:
    """yaw = asin(d / (b r)) with r = 1/2 sqrt(W^2 - k (2d)^2), as atan2; NaN where undefined."""
    with np.errstate(invalid="ignore", over="ignore"):
        radicand = (b * width) ** 2 - (b * b * k + 1.0) * twice_offset**2
        return np.where(
            radicand >= 0.0, np.arctan2(twice_offset, np.sqrt(np.maximum(radicand, 0.0))), np.nan
        )


def is_scalar(*values: Any) -> bool:
    """Whether every value is a plain number (int, float or a numpy float64), not an array."""
    return all(type(value) in _SCALAR_TYPES for value in values)


_SCALAR_TYPES = frozenset((float, int, np.float64))


def _yaw_of_scalars(
    x_left: float,
    x_right: float,
    x_center: float,
    b: float,
    k: float,
    offset_scale: float = 1.0,
    within_cylinder: bool = False,
) -> float:
    """`_atan_form` for one face in plain floats (the per-frame path: about ten times faster than
    numpy on 0-d arrays), with `_inputs`' NaN rules; `within_cylinder` also requires |2d| <= W.
    The same operations in the same order as the array path (`tests/pose/test_geometry.py`
    checks that both agree)."""
    width = x_right - x_left
    twice_offset = 2.0 * x_center - x_left - x_right
    if not (math.isfinite(width) and math.isfinite(twice_offset) and width > 0):
        return math.nan
    if within_cylinder and not abs(twice_offset) <= width:
        return math.nan
    twice_offset = twice_offset * offset_scale
    scaled_width = b * width
    radicand = scaled_width * scaled_width - (b * b * k + 1.0) * (twice_offset * twice_offset)
    if not radicand >= 0.0:
        return math.nan
    return math.degrees(math.atan2(twice_offset, math.sqrt(radicand)))


def cylindrical(
    x_left: Any, x_right: Any, x_center: Any, constants: FaceModelConstants = PAPER_CONSTANTS
) -> Any:
    """Ohue et al.'s cylinder, eqs. 2-4: r = W/2, yaw = asin(d / r)."""
    if is_scalar(x_left, x_right, x_center):
        return _yaw_of_scalars(x_left, x_right, x_center, b=1.0, k=0.0)
    width, twice_offset, scalar = _inputs(x_left, x_right, x_center)
    return _finish(_atan_form(twice_offset, width, b=1.0, k=0.0), scalar)


def ellipsoidal(
    x_left: Any, x_right: Any, x_center: Any, constants: FaceModelConstants = PAPER_CONSTANTS
) -> Any:
    """Lee et al.'s ellipse with a neck pivot, eqs. 6-10.

    With theta_c the cylindrical yaw, x_pivot = mid - alpha r sin(theta_c) = mid - alpha d, so
    yaw = asin((1 + alpha) d / ((alpha + beta) r)) (eq. 42: sin(yaw_e) = 0.833 sin(yaw_c)).
    Undefined wherever the cylindrical yaw is.
    """
    alpha, beta = constants.alpha, constants.beta
    ratio = (1.0 + alpha) / (alpha + beta)
    if is_scalar(x_left, x_right, x_center):
        return _yaw_of_scalars(x_left, x_right, x_center, 1.0, 0.0, ratio, within_cylinder=True)
    width, twice_offset, scalar = _inputs(x_left, x_right, x_center)
    cylinder_defined = np.abs(twice_offset) <= width
    yaw = _atan_form(twice_offset * ratio, width, b=1.0, k=0.0)
    return _finish(np.where(cylinder_defined, yaw, np.nan), scalar)


def ce(
    x_left: Any, x_right: Any, x_center: Any, constants: FaceModelConstants = PAPER_CONSTANTS
) -> Any:
    """Centre-of-ellipse model, eqs. 27, 32: r is the frontal half width (the radius rule)."""
    beta = constants.beta
    k = (beta * beta - 1.0) / beta**2
    if is_scalar(x_left, x_right, x_center):
        return _yaw_of_scalars(x_left, x_right, x_center, b=beta, k=k)
    width, twice_offset, scalar = _inputs(x_left, x_right, x_center)
    return _finish(_atan_form(twice_offset, width, b=beta, k=k), scalar)


def center_ce(
    x_left: Any, x_right: Any, x_center: Any, constants: FaceModelConstants = PAPER_CONSTANTS
) -> Any:
    """Center-CE, eqs. 34-36: CE with the face-centre term corrected by gamma_c (the angle rule).

    A true 90 deg maps to about 60 deg, so estimates of real faces stay within about +-60 deg.
    """
    beta, b = constants.beta, constants.beta + constants.gamma_c
    k = (beta * beta - 1.0) / b**2
    if is_scalar(x_left, x_right, x_center):
        return _yaw_of_scalars(x_left, x_right, x_center, b=b, k=k)
    width, twice_offset, scalar = _inputs(x_left, x_right, x_center)
    return _finish(_atan_form(twice_offset, width, b=b, k=k), scalar)


def boundary_ce(
    x_left: Any, x_right: Any, x_center: Any, constants: FaceModelConstants = PAPER_CONSTANTS
) -> Any:
    """Boundary-CE, eqs. 37-40: CE with the boundary terms corrected by gamma_b."""
    beta, gamma_b = constants.beta, constants.gamma_b
    k = (beta * beta - gamma_b * gamma_b - 1.0) / beta**2
    if is_scalar(x_left, x_right, x_center):
        return _yaw_of_scalars(x_left, x_right, x_center, b=beta, k=k)
    width, twice_offset, scalar = _inputs(x_left, x_right, x_center)
    return _finish(_atan_form(twice_offset, width, b=beta, k=k), scalar)


YAW_MODELS: Mapping[str, YawModel] = {
    "cylindrical": cylindrical,
    "ellipsoidal": ellipsoidal,
    "ce": ce,
    "center_ce": center_ce,
    "boundary_ce": boundary_ce,
}
"""The five models by name, in the paper's order."""


@dataclass(frozen=True, slots=True)
class ProjectedFace:
    """Boundaries and centre of a synthetic face, from the forward model."""

    x_left: FloatArray
    x_right: FloatArray
    x_center: FloatArray


def forward_model(
    true_yaw_deg: npt.ArrayLike,
    half_width_px: float = 150.0,
    pivot_x_px: float = 320.0,
    constants: FaceModelConstants = PAPER_CONSTANTS,
) -> ProjectedFace:
    """The paper's forward model, eqs. 53-55: boundaries and centre of an ellipse turned by t.

    w = r sqrt(1 + (beta^2 - 1) sin^2 t), x_left/right = x0 -/+ w + alpha r sin t,
    x_center = x0 + (alpha + beta) r sin t.
    """
    sin_t = np.sin(np.radians(np.asarray(true_yaw_deg, dtype=np.float64)))
    r, alpha, beta = half_width_px, constants.alpha, constants.beta
    half_extent = r * np.sqrt(1.0 + (beta * beta - 1.0) * sin_t**2)
    shift = alpha * r * sin_t
    return ProjectedFace(
        x_left=pivot_x_px - half_extent + shift,
        x_right=pivot_x_px + half_extent + shift,
        x_center=pivot_x_px + (alpha + beta) * r * sin_t,
    )


def expected_error_deg(
    model: str, true_yaw_deg: npt.ArrayLike, constants: FaceModelConstants = PAPER_CONSTANTS
) -> FloatArray:
    """Closed-form error (estimate minus truth, degrees) of a model on the forward model.

    Eqs. 49 (cylindrical), 50 (ellipsoidal), 51 (Center-CE), 52 (Boundary-CE); CE is exact.
    """
    t = np.radians(np.asarray(true_yaw_deg, dtype=np.float64))
    sin_t = np.sin(t)
    alpha, beta = constants.alpha, constants.beta
    b_c, gamma_b = beta + constants.gamma_c, constants.gamma_b
    stretch = np.sqrt(1.0 + (beta * beta - 1.0) * sin_t**2)
    with np.errstate(invalid="ignore"):
        if model == "ce":
            estimate = t
        elif model == "cylindrical":
            estimate = np.arcsin(np.clip(beta * sin_t / stretch, -1.0, 1.0))
        elif model == "ellipsoidal":
            estimate = np.arcsin(beta * (1 + alpha) * sin_t / ((alpha + beta) * stretch))
        elif model == "center_ce":
            shrink = 1.0 - (beta / b_c) ** 2
            denominator = b_c * np.sqrt(1.0 + (beta * beta - 1.0) * sin_t**2 * shrink)
            estimate = np.arcsin(beta * sin_t / denominator)
        elif model == "boundary_ce":
            estimate = np.arcsin(sin_t / np.sqrt(1.0 + gamma_b * gamma_b * sin_t**2))
        else:
            raise KeyError(f"unknown yaw model '{model}'; choose one of {', '.join(YAW_MODELS)}")
    return np.asarray(np.degrees(estimate - t), dtype=np.float64)
