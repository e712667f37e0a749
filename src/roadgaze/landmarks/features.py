"""Face features from MediaPipe's 478 landmarks (pure numpy): boundaries and centre, roll removed.

`features_from_landmarks` turns one face's landmarks into the three inputs of the yaw models
(Narayanan et al. 2014): the eye line (outer corners 33 and 263) gives the roll; the landmarks
are rotated about the eye midpoint so that the eye line is horizontal; then

- the left and right boundaries are the extreme x of all mesh landmarks (the silhouette of the
  projected mesh) in a horizontal band from 0.1 to 0.5 of the eye-to-mouth distance below the eye
  line (cheek height, below the eyes and above the mouth), and
- the centre is the mean x of the nose tip (1) and the point just above it on the ridge (4),

a choice measured on Pointing'04 subjects 1-10 against the alternatives (docs/landmarks.md). The
pitch model's inputs are the roll-removed y of the forehead (10), the chin (152) and the nose
tip (1) on the face's mid-line (docs/pose.md).

Sign conventions: image x grows right, y down. `roll_deg` > 0 is a counter-clockwise head tilt as
seen in the image. Yaw > 0 is the head turned to the person's own left (ISO 8855), which an
unmirrored camera sees as the nose pointing to the image right.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.types import FaceFeatures

NUM_LANDMARKS = 478
RIGHT_EYE_OUTER = 33
"""The person's right eye, outer corner (image left for an unmirrored camera)."""
LEFT_EYE_OUTER = 263
"""The person's left eye, outer corner (image right for an unmirrored camera)."""
NOSE_TIP = 1
MOUTH_CORNERS = (61, 291)
MIDLINE_TOP = 10
"""Forehead, the top of the mesh on the face's mid-line (the pitch model's top point)."""
MIDLINE_BOTTOM = 152
"""Chin, the bottom of the mesh on the mid-line."""

FACE_OVAL = (
    10, 338, 297, 332, 284, 251, 389, 356, 454, 323, 361, 288, 397, 365, 379, 378, 400, 377,
    152, 148, 176, 149, 150, 136, 172, 58, 132, 93, 234, 127, 162, 21, 54, 103, 67, 109,
)  # fmt: skip
"""MediaPipe's face-oval landmarks (FaceLandmarksConnections.FACE_LANDMARKS_FACE_OVAL)."""


@dataclass(frozen=True, slots=True)
class LandmarkChoice:
    """Which landmarks give the face boundaries and the centre.

    Boundaries: the extreme (min and max) roll-removed x of `boundary_landmarks` (None: all 478
    landmarks, i.e. the silhouette of the projected mesh), keeping only those whose roll-removed
    height lies in `boundary_band`, measured in units of the eye-to-mouth distance below the eye
    line (0 = eye height, 1 = mouth-corner height; None = no height limit).
    Centre: the mean roll-removed x of `center_landmarks`.
    """

    name: str
    center_landmarks: tuple[int, ...]
    boundary_landmarks: tuple[int, ...] | None = None
    boundary_band: tuple[float, float] | None = None


DEFAULT_CHOICE = LandmarkChoice(
    name="mesh silhouette in band [0.1, 0.5] / nose 1+4",
    center_landmarks=(NOSE_TIP, 4),
    boundary_landmarks=None,
    boundary_band=(0.1, 0.5),
)
"""The measured best choice on Pointing'04 subjects 1-10 together (docs/landmarks.md)."""


def roll_from_eyes_deg(landmarks_px: npt.NDArray[np.floating[Any]]) -> float:
    """Counter-clockwise (as seen in the image) angle of the eye line 33 -> 263, degrees."""
    dx = float(landmarks_px[LEFT_EYE_OUTER, 0] - landmarks_px[RIGHT_EYE_OUTER, 0])
    dy = float(landmarks_px[LEFT_EYE_OUTER, 1] - landmarks_px[RIGHT_EYE_OUTER, 1])
    return math.degrees(math.atan2(-dy, dx))


def remove_roll(
    landmarks_px: npt.NDArray[np.floating[Any]], roll_deg: float
) -> npt.NDArray[np.float64]:
    """(N, 2) x, y rotated about the eye midpoint so that the eye line becomes horizontal."""
    # The pivot in plain floats (float64 arithmetic, as numpy's, without its small-array calls);
    # the shifts column by column, converting to float64 on the way: numpy applies an (N, 2)
    # array minus a pair as N loops of two elements, three times slower.
    right_x, right_y = landmarks_px[RIGHT_EYE_OUTER, :2].tolist()
    left_x, left_y = landmarks_px[LEFT_EYE_OUTER, :2].tolist()
    pivot_x, pivot_y = 0.5 * (right_x + left_x), 0.5 * (right_y + left_y)
    centred = np.empty((landmarks_px.shape[0], 2))
    np.subtract(landmarks_px[:, 0], pivot_x, out=centred[:, 0], dtype=np.float64)
    np.subtract(landmarks_px[:, 1], pivot_y, out=centred[:, 1], dtype=np.float64)
    # In y-down image coordinates a counter-clockwise (on screen) roll of r is undone by the
    # matrix [[cos r, -sin r], [sin r, cos r]] applied to (x, y).
    angle = math.radians(roll_deg)
    cos_a, sin_a = math.cos(angle), math.sin(angle)
    rotation = np.array([[cos_a, -sin_a], [sin_a, cos_a]])
    upright = np.asarray(centred @ rotation.T, dtype=np.float64)
    upright[:, 0] += pivot_x
    upright[:, 1] += pivot_y
    return upright


def boundaries_and_center(
    upright_px: npt.NDArray[np.float64], choice: LandmarkChoice = DEFAULT_CHOICE
) -> tuple[float, float, float]:
    """x_left, x_right, x_center from roll-removed (N, 2) landmarks under `choice`.

    When fewer than two landmarks fall in the height band (a degenerate face), the band is
    ignored rather than failing.
    """
    # np.mean's own sum and division without its generic path (for float32 too: a float64
    # quotient rounded to float32 is the float32 quotient).
    centers = upright_px[list(choice.center_landmarks), 0]
    x_center = float(centers.sum() / len(centers))
    candidates = (
        upright_px
        if choice.boundary_landmarks is None
        else upright_px[list(choice.boundary_landmarks)]
    )
    xs = candidates[:, 0]
    if choice.boundary_band is not None:
        # Plain floats: numpy's float64 arithmetic, without the cost of its scalars.
        eye_y = 0.5 * (float(upright_px[RIGHT_EYE_OUTER, 1]) + float(upright_px[LEFT_EYE_OUTER, 1]))
        mouth_y = 0.5 * (
            float(upright_px[MOUTH_CORNERS[0], 1]) + float(upright_px[MOUTH_CORNERS[1], 1])
        )
        span = mouth_y - eye_y
        if span > 0:
            low, high = choice.boundary_band
            level = (candidates[:, 1] - eye_y) / span
            in_band = (level >= low) & (level <= high)
            if np.count_nonzero(in_band) >= 2:
                xs = xs[in_band]
    return float(xs.min()), float(xs.max()), x_center


def finite_box_px(
    points: npt.NDArray[np.floating[Any]],
) -> tuple[float, float, float, float] | None:
    """(x_min, y_min, x_max, y_max) of (N, 2|3) landmarks; None when any value (z too) is NaN or
    infinite.

    One pass of min and max per column gives both: they propagate NaN, and an infinite value is
    an extreme. Taken along the rows of a transposed copy: reducing down the columns of the
    (478, 3) array, or testing each value with `np.isfinite`, costs several times as much.
    """
    columns = np.ascontiguousarray(points.T)
    low, high = columns.min(axis=1).tolist(), columns.max(axis=1).tolist()
    if not all(math.isfinite(value) for value in (*low, *high)):
        return None
    return (low[0], low[1], high[0], high[1])


def angles_from_matrix_deg(matrix: npt.ArrayLike) -> tuple[float, float]:
    """Yaw and pitch (degrees, project convention) from MediaPipe's facial transformation matrix.

    The matrix maps MediaPipe's canonical face model into camera space; its third column is the
    face's forward (nose) direction in the camera frame, from which yaw (about the vertical axis)
    and pitch (about the horizontal one) follow. Signs verified on Pointing'04 subjects 1-10
    (docs/landmarks.md): a nose pointing to the image right gives yaw > 0, a face looking up
    gives pitch > 0.
    """
    rotation = np.asarray(matrix, dtype=np.float64)[:3, :3]
    yaw_deg = math.degrees(math.atan2(float(rotation[0, 2]), float(rotation[2, 2])))
    pitch_deg = math.degrees(
        math.atan2(float(rotation[1, 2]), math.hypot(float(rotation[0, 2]), float(rotation[2, 2])))
    )
    return yaw_deg, pitch_deg


def face_quality(
    landmarks_px: npt.NDArray[np.floating[Any]],
    box_px: tuple[float, float, float, float],
    image_size_px: tuple[int, int] | None,
) -> float:
    """0..1: face width relative to 80 px, times the fraction of landmarks inside the image.

    `box_px` is the landmarks' own box (x_min, y_min, x_max, y_max), as `features_from_landmarks`
    gives it: when it lies inside the image, so does every landmark, and the fraction is 1 without
    testing each one.
    """
    width_px = box_px[2] - box_px[0]
    size_score = min(1.0, max(0.0, width_px / 80.0))
    if image_size_px is None:
        return size_score
    width, height = image_size_px
    if box_px[0] >= 0 and box_px[1] >= 0 and box_px[2] < width and box_px[3] < height:
        return size_score
    xy = landmarks_px[:, :2]
    inside = (xy[:, 0] >= 0) & (xy[:, 0] < width) & (xy[:, 1] >= 0) & (xy[:, 1] < height)
    return size_score * float(np.mean(inside))


def features_from_landmarks(
    landmarks_px: npt.ArrayLike,
    image_size_px: tuple[int, int] | None = None,
    transformation_matrix: npt.ArrayLike | None = None,
    choice: LandmarkChoice = DEFAULT_CHOICE,
    *,
    blendshapes: Mapping[str, float] | None = None,
    eye_contrast: tuple[float, float] | None = None,
    eye_sharpness: tuple[float, float] | None = None,
    eye_lid_share: tuple[float, float] | None = None,
) -> FaceFeatures:
    """The yaw models' inputs for one face from its (478, 3) landmarks in pixels (numpy only).

    `image_size_px` (width, height) enables the edge term of `quality`; `transformation_matrix`
    (MediaPipe's 4x4) fills `mediapipe_yaw_deg` / `mediapipe_pitch_deg`; the mid-line's `y_top_px`,
    `y_bottom_px` and `y_center_px` are always filled. `blendshapes`, `eye_contrast`,
    `eye_sharpness` and `eye_lid_share` are measured elsewhere and passed through into the record
    (built once: a `dataclasses.replace` afterwards would cost as much again). Raises ValueError
    for a wrong shape or non-finite landmarks.
    """
    points = np.asarray(landmarks_px, dtype=np.float32)
    if points.ndim != 2 or points.shape[0] != NUM_LANDMARKS or points.shape[1] not in (2, 3):
        raise ValueError(f"expected ({NUM_LANDMARKS}, 3) landmarks, found shape {points.shape}")
    if points.shape[1] == 2:
        points = np.concatenate([points, np.zeros((NUM_LANDMARKS, 1), np.float32)], axis=1)
    box = finite_box_px(points)
    if box is None:
        raise ValueError("landmarks contain NaN or infinite values")
    roll_deg = roll_from_eyes_deg(points)
    upright = remove_roll(points, roll_deg)
    x_left, x_right, x_center = boundaries_and_center(upright, choice)
    yaw_mp: float | None = None
    pitch_mp: float | None = None
    if transformation_matrix is not None:
        yaw_mp, pitch_mp = angles_from_matrix_deg(transformation_matrix)
    return FaceFeatures(
        y_top_px=float(upright[MIDLINE_TOP, 1]),
        y_bottom_px=float(upright[MIDLINE_BOTTOM, 1]),
        y_center_px=float(upright[NOSE_TIP, 1]),
        x_left_px=x_left,
        x_right_px=x_right,
        x_center_px=x_center,
        roll_deg=roll_deg,
        box_px=box,
        quality=face_quality(points, box, image_size_px),
        landmarks_px=points,
        mediapipe_yaw_deg=yaw_mp,
        mediapipe_pitch_deg=pitch_mp,
        blendshapes=blendshapes,
        eye_contrast=eye_contrast,
        eye_sharpness=eye_sharpness,
        eye_lid_share=eye_lid_share,
    )
