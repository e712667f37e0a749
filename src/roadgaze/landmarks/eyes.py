"""The driver's eyes from MediaPipe's 478 landmarks and blendshapes (plain floats, numpy; no I/O).

`eye_features(...)` measures, per eye, the lid aperture (openness), the eye-in-head direction and
whether the eye can be used, and returns an `EyesFeatures`. Definitions (measured choices and
their evidence: docs/eyes.md):

- **Sides.** MediaPipe's iris 468-472 and `eyeBlinkRight` belong to the person's right eye (on
  the image's left for an unmirrored camera); 473-477 and `*Left` to the left eye.
- **Openness** = mean vertical gap of three upper/lower lid landmark pairs, roll removed, divided
  by W, the width (outer to inner corner) of the wider eye in the image. Dividing by the wider
  eye keeps the far eye of a turned head from reading wide open. About 0.3 open, 0.1 closed
  (MediaPipe's lids never quite meet).
- **Direction** (default): the eyeLook* blendshapes scaled to degrees by a synthetic
  calibration, yaw = (eyeLookOut - eyeLookIn) / 0.0229 (sign by side), pitch = (eyeLookUp -
  eyeLookDown) / 0.0148. The iris model (an eyeball of radius k W rotating about a centre behind
  the corner midpoint, orthographic camera) is computed beside it as a diagnostic.
- **Usable eyes.** No eye without a head yaw, beyond `max_head_yaw_deg`, below
  `min_eye_width_px`, at landmark quality under `min_quality`, or when the image check finds the
  eyes hidden (a dark lens: a flat opening; hair: edges across both eyes). Beyond
  `far_eye_max_yaw_deg`, or narrower than `far_eye_min_width_ratio` of the other, the far eye is
  dropped. The nearer eye's openness is
  still judged up to `closure_max_head_yaw_deg`.

Sign convention: image x right, y down; yaw > 0 toward the person's own left (the iris moves to
the image right), pitch > 0 up.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.config import EyesConfig
from roadgaze.landmarks.eye_landmarks import (
    EYE_LANDMARKS,
    EYES,
    LEFT_EYE,
    RIGHT_EYE,
    EyeIndices,
    UprightPoints,
    eye_width_px,
    lid_openness,
    upright_eye_points,
    xy,
)
from roadgaze.landmarks.features import NUM_LANDMARKS, roll_from_eyes_deg
from roadgaze.types import EyeMeasurement, EyesFeatures, FaceFeatures, FloatArray

__all__ = [  # the eye landmarks are re-exported from their own module, where they moved
    "BLENDSHAPE_PITCH_PER_DEG",
    "BLENDSHAPE_YAW_PER_DEG",
    "EYEBALL",
    "EYES",
    "EYE_LANDMARKS",
    "LEFT_EYE",
    "RIGHT_EYE",
    "EyeIndices",
    "EyeballConstants",
    "blendshape_direction_deg",
    "driver_eyes",
    "eye_features",
    "eye_width_px",
    "head_rotation",
    "iris_direction_deg",
    "lid_openness",
    "swap_sides",
    "upright_eye_points",
]

BLENDSHAPE_YAW_PER_DEG = 0.0229
"""eyeLookOut - eyeLookIn per degree of eye-in-head yaw: the slope on rendered eyes turned
-30..30 deg with the head frontal (`roadgaze synth --measure --eyes`, docs/eyes.md)."""
BLENDSHAPE_PITCH_PER_DEG = 0.0148
"""eyeLookUp - eyeLookDown per degree of eye pitch (same renders, eye pitch -20..20 deg)."""


@dataclass(frozen=True, slots=True)
class EyeballConstants:
    """The iris model's constants in units of the frontal eye width W.

    `k`: the iris centre lies k W in front of the eye's rotation centre (the pupil plane is about
    10.5 mm in front of it, W about 27 mm). `lam`, `mu`: the iris at rest lies lam W lateral of
    and mu W above the corner midpoint (measured on Pointing'04's frontal stills). `b`: the iris
    at rest lies b W in front of the corner midpoint.
    """

    k: float = 0.40
    lam: float = 0.047
    mu: float = 0.078
    b: float = 0.20


EYEBALL = EyeballConstants()


def head_rotation(yaw_deg: float, pitch_deg: float) -> FloatArray:
    """Head frame -> camera frame (x right, y down, z toward the camera): yaw, then pitch.

    Yaw > 0 moves a point in front of the face (z > 0) to +x; pitch > 0 moves it up (-y).
    """
    yaw, pitch = math.radians(yaw_deg), math.radians(pitch_deg)
    rotate_yaw = np.array(
        [
            [math.cos(yaw), 0.0, math.sin(yaw)],
            [0.0, 1.0, 0.0],
            [-math.sin(yaw), 0.0, math.cos(yaw)],
        ]
    )
    rotate_pitch = np.array(
        [
            [1.0, 0.0, 0.0],
            [0.0, math.cos(pitch), -math.sin(pitch)],
            [0.0, math.sin(pitch), math.cos(pitch)],
        ]
    )
    return np.asarray(rotate_pitch @ rotate_yaw, dtype=np.float64)


def iris_direction_deg(
    upright_px: UprightPoints,
    eye: EyeIndices,
    scale_px: float,
    head_yaw_deg: float,
    head_pitch_deg: float,
    constants: EyeballConstants = EYEBALL,
) -> tuple[float, float]:
    """Eye-in-head yaw and pitch (degrees) of one eye by the iris (eyeball-centre) model.

    The rotation centre E lies at `(lateral lam, -mu, b - k) W` from the corner midpoint in the
    head frame; it is projected with the head rotation, and the iris centre's offset from it
    divided by k W is the x, y of the unit gaze vector in the camera frame. Rotated back by the
    head it gives the eye-in-head direction; for pitch 0, sin(yaw_head + yaw_eye) = dx / (k W).
    `upright_px[i]` is landmark i's roll-removed (x, y). Plain floats: `head_rotation`'s matrix
    written out (the per-frame path; `tests/landmarks/test_eyes.py` checks it against the matrix).
    """
    yaw, pitch = math.radians(head_yaw_deg), math.radians(head_pitch_deg)
    cos_y, sin_y, cos_p, sin_p = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch)
    # head_rotation(yaw, pitch) = [[cy, 0, sy], [sp sy, cp, -sp cy], [-cp sy, sp, cp cy]].
    outer_x, outer_y = xy(upright_px, eye.outer)
    inner_x, inner_y = xy(upright_px, eye.inner)
    iris_x, iris_y = xy(upright_px, eye.iris_center)
    c0 = eye.lateral * constants.lam * scale_px
    c1 = -constants.mu * scale_px
    c2 = (constants.b - constants.k) * scale_px
    centre_x = 0.5 * (outer_x + inner_x) + (cos_y * c0 + sin_y * c2)
    centre_y = 0.5 * (outer_y + inner_y) + (sin_p * sin_y * c0 + cos_p * c1 - sin_p * cos_y * c2)
    radius_px = constants.k * scale_px
    dx, dy = (iris_x - centre_x) / radius_px, (iris_y - centre_y) / radius_px
    planar = math.hypot(dx, dy)
    if planar > 1.0:  # further out than an eyeball allows: saturate at the limb
        dx, dy, planar = dx / planar, dy / planar, 1.0
    dz = math.sqrt(max(0.0, 1.0 - planar * planar))
    # The gaze back in the head frame: the transpose of the rotation applied to (dx, dy, dz).
    x = cos_y * dx + sin_p * sin_y * dy - cos_p * sin_y * dz
    y = cos_p * dy + sin_p * dz
    z = sin_y * dx - sin_p * cos_y * dy + cos_p * cos_y * dz
    return math.degrees(math.atan2(x, z)), math.degrees(math.atan2(-y, math.hypot(x, z)))


def blendshape_direction_deg(
    blendshapes: Mapping[str, float], eye: EyeIndices
) -> tuple[float, float] | None:
    """Eye-in-head yaw and pitch (degrees) of one eye from the eyeLook* blendshapes.

    For the left eye, looking out turns it to the person's left (yaw > 0); for the right eye,
    looking in does. None when a score is missing.
    """
    try:
        out_minus_in = blendshapes[eye.look_out] - blendshapes[eye.look_in]
        up_minus_down = blendshapes[eye.look_up] - blendshapes[eye.look_down]
    except KeyError:
        return None
    toward_left = out_minus_in if eye.side == "left" else -out_minus_in
    return toward_left / BLENDSHAPE_YAW_PER_DEG, up_minus_down / BLENDSHAPE_PITCH_PER_DEG


def _face_reason(
    head_yaw_deg: float | None,
    scale_px: float,
    quality: float,
    occluded: bool,
    max_yaw_deg: float,
    config: EyesConfig,
) -> str:
    if head_yaw_deg is None:
        return "no head yaw"
    if abs(head_yaw_deg) > max_yaw_deg:
        return "head turned"
    if scale_px < config.min_eye_width_px:
        return "eyes too small"
    if quality < config.min_quality:
        return "low landmark quality"
    if occluded:
        return "eyes hidden"
    return ""


def eye_features(
    landmarks_px: npt.ArrayLike,
    head_yaw_deg: float | None,
    head_pitch_deg: float | None = None,
    blendshapes: Mapping[str, float] | None = None,
    quality: float = 1.0,
    contrast: tuple[float, float] | None = None,
    config: EyesConfig | None = None,
    sharpness: tuple[float, float] | None = None,
    lid_share: tuple[float, float] | None = None,
) -> EyesFeatures:
    """Openness, direction and usability of both eyes of one face.

    `landmarks_px`: MediaPipe's (478, 2|3) landmarks in pixels. `head_yaw_deg`: the service's head
    yaw (None when unknown: no eye gives a direction). `head_pitch_deg`: MediaPipe's matrix pitch
    (0 when None), used by the iris model only. `blendshapes`: the 52 scores by name (None: the
    direction falls back to the iris model, and there is no blink score). `contrast`: (right,
    left) from `eye_contrast`, `sharpness` likewise from `eye_sharpness`, `lid_share` from
    `eye_lid_share`. Raises ValueError for
    a wrong shape or non-finite landmarks.
    """
    config = config if config is not None else EyesConfig()
    points = np.asarray(landmarks_px, dtype=np.float64)
    if points.ndim != 2 or points.shape[0] != NUM_LANDMARKS or points.shape[1] not in (2, 3):
        raise ValueError(f"expected ({NUM_LANDMARKS}, 2|3) landmarks, found shape {points.shape}")
    # x, y copied together first: np.isfinite on the contiguous copy is several times faster than
    # on the strided columns.
    xy_px = np.ascontiguousarray(points[:, :2])
    if not np.isfinite(xy_px).all():
        raise ValueError("landmarks contain NaN or infinite values")
    upright = upright_eye_points(xy_px, roll_from_eyes_deg(xy_px))
    widths = {e.side: eye_width_px(upright, e) for e in EYES}
    scale = max(widths.values())
    yaw = None if head_yaw_deg is None or not math.isfinite(head_yaw_deg) else head_yaw_deg
    pitch = 0.0 if head_pitch_deg is None or not math.isfinite(head_pitch_deg) else head_pitch_deg
    use_blendshapes = config.method == "blendshapes" and blendshapes is not None
    openness = {e.side: lid_openness(upright, e, scale) for e in EYES}
    contrasts = (
        {"right": None, "left": None}
        if contrast is None
        else dict(zip(("right", "left"), contrast, strict=True))
    )
    occluded_by = _occluded(openness, contrasts, lid_share, config)
    occluded = occluded_by is not None
    blurred = _blurred(sharpness, config)
    gaze_face = _face_reason(yaw, scale, quality, occluded, config.max_head_yaw_deg, config)
    closure_face = _face_reason(
        0.0 if yaw is None else yaw,
        scale,
        quality,
        occluded,
        config.closure_max_head_yaw_deg,
        config,
    )
    # The nearer eye: toward the camera when the head turns (yaw > 0 shows the right eye more),
    # else the wider one in the image.
    if yaw is not None and abs(yaw) > config.far_eye_max_yaw_deg:
        near = "right" if yaw > 0 else "left"
    else:
        near = max(widths, key=lambda side: widths[side])
    measured = []
    for eye in EYES:
        far_reason = ""
        if eye.side != near:
            if yaw is not None and abs(yaw) > config.far_eye_max_yaw_deg:
                far_reason = "far eye"
            elif widths[eye.side] < config.far_eye_min_width_ratio * scale:
                far_reason = "far eye narrow"
        gaze_reason = gaze_face or far_reason
        closure_reason = closure_face or far_reason
        yaw_deg = pitch_deg = iris_yaw = iris_pitch = None
        if not gaze_reason and yaw is not None:
            iris_yaw, iris_pitch = iris_direction_deg(upright, eye, scale, yaw, pitch)
            direction = (
                blendshape_direction_deg(blendshapes, eye)
                if use_blendshapes and blendshapes is not None
                else (iris_yaw, iris_pitch)
            )
            if direction is not None:
                yaw_deg, pitch_deg = direction
        measured.append(
            EyeMeasurement(
                side=eye.side,
                width_px=widths[eye.side],
                openness=openness[eye.side],
                gaze_usable=yaw_deg is not None,
                closure_usable=not closure_reason,
                reason=gaze_reason or closure_reason,
                yaw_deg=yaw_deg,
                pitch_deg=pitch_deg,
                blink=_score(blendshapes, eye.blink),
                look_down=_look_down(blendshapes, eye),
                iris_yaw_deg=iris_yaw,
                iris_pitch_deg=iris_pitch,
                contrast=contrasts[eye.side],
            )
        )
    right, left = measured
    reason = "" if right.gaze_usable or left.gaze_usable else (gaze_face or "no eye")
    return EyesFeatures(
        right=right,
        left=left,
        method="blendshapes" if use_blendshapes else "iris",
        scale_px=scale,
        reason=reason,
        occluded=occluded,
        occluded_by=occluded_by or "",
        blurred=blurred,
    )


def driver_eyes(
    face: FaceFeatures | None, head_yaw_deg: float | None, config: EyesConfig | None = None
) -> EyesFeatures | None:
    """`eye_features` of one detected face; None without a face or without MediaPipe's 478
    landmarks (a test's fake detector)."""
    if face is None or face.landmarks_px.shape[0] != NUM_LANDMARKS:
        return None
    try:
        return eye_features(
            face.landmarks_px,
            head_yaw_deg,
            face.mediapipe_pitch_deg,
            face.blendshapes,
            face.quality,
            face.eye_contrast,
            config,
            face.eye_sharpness,
            face.eye_lid_share,
        )
    except ValueError:
        return None


def _score(blendshapes: Mapping[str, float] | None, name: str) -> float | None:
    if blendshapes is None or name not in blendshapes:
        return None
    return float(blendshapes[name])


def _look_down(blendshapes: Mapping[str, float] | None, eye: EyeIndices) -> float | None:
    down, up = _score(blendshapes, eye.look_down), _score(blendshapes, eye.look_up)
    return None if down is None or up is None else down - up


def _occluded(
    openness: Mapping[str, float],
    contrasts: Mapping[str, float | None],
    lid_share: tuple[float, float] | None,
    config: EyesConfig,
) -> str | None:
    """What hides the eyes: '' for a flat opening in both measured eyes although the lids look
    open (a dark lens), `strands` for edges mostly across both eyes, both measured (hair: one
    eye alone may be a glasses rim or a lock beside it), None when nothing does."""
    measured = [
        (openness[side], value)
        for side, value in contrasts.items()
        if value is not None and math.isfinite(value)
    ]
    if (
        config.min_contrast > 0
        and measured
        and all(
            value < config.min_contrast and open_value >= config.occluded_min_openness
            for open_value, value in measured
        )
    ):
        return ""
    shares = [value for value in lid_share or () if math.isfinite(value)]
    if config.min_lid_share > 0 and len(shares) == 2 and max(shares) < config.min_lid_share:
        return "strands"
    return None


def _blurred(sharpness: tuple[float, float] | None, config: EyesConfig) -> bool:
    """Every measured eye's surroundings show weaker edges than `min_sharpness`."""
    if sharpness is None or config.min_sharpness <= 0:
        return False
    measured = [value for value in sharpness if math.isfinite(value)]
    return bool(measured) and all(value < config.min_sharpness for value in measured)


def swap_sides(blendshapes: Mapping[str, float]) -> dict[str, float]:
    """Blendshape scores with every Left and Right name swapped (for a mirrored image)."""
    swapped: dict[str, float] = {}
    for name, score in blendshapes.items():
        if name.endswith("Left"):
            name = name[: -len("Left")] + "Right"
        elif name.endswith("Right"):
            name = name[: -len("Right")] + "Left"
        swapped[name] = score
    return swapped
