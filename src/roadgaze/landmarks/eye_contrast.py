"""Can the eyes be seen at all: the contrast inside the eye opening and the edges around it.

An open eye shows bright sclera beside a dark iris; a dark lens, glare or a hand is flat. Measured
relative to the skin just below the eye, so it does not depend on the exposure. With the lids
looking open, a flat opening in both eyes means the eyes are hidden (`EyesConfig.min_contrast`).
The lids are sharp edges in a focused image; motion blur, glare and a washed-out picture soften
them, and MediaPipe then draws the lids nearly shut over open eyes: lids that read closed on eyes
without edges cannot be judged (`EyesConfig.min_sharpness`). The evidence and its limits:
docs/eyes.md.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.landmarks.eyes import EyeIndices
from roadgaze.types import FloatArray

MIN_EYE_WIDTH_PX = 16.0
"""Narrower eyes are not checked (NaN): a blurred open eye 11.5 px wide (Intel's sample GIF)
reads as flat as a lens, while Pointing'04's eyes (about 23 px) never do."""


def polygon_mask(polygon: FloatArray, shape: tuple[int, int]) -> npt.NDArray[np.bool_]:
    """Pixels (by their centres) inside a polygon, even-odd rule; `shape` is (height, width)."""
    height, width = shape
    ys, xs = np.mgrid[0:height, 0:width]
    px, py = xs + 0.5, ys + 0.5
    inside = np.zeros(shape, dtype=bool)
    x0, y0 = polygon[:, 0], polygon[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    for ax, ay, bx, by in zip(x0, y0, x1, y1, strict=True):
        if ay == by:
            continue
        crosses = (py >= min(ay, by)) & (py < max(ay, by))
        x_at = ax + (py - ay) * (bx - ax) / (by - ay)
        inside ^= crosses & (px < x_at)
    return inside


def _fill_polygon(polygon: FloatArray, shape: tuple[int, int]) -> npt.NDArray[np.bool_]:
    """`polygon_mask` by OpenCV's rasteriser (sub-pixel vertices): the same pixels up to edge
    rounding, ten times faster."""
    import cv2

    mask = np.zeros(shape, dtype=np.uint8)
    vertices = np.round((polygon - 0.5) * 16).astype(np.int32)
    cv2.fillPoly(mask, [vertices], 1, lineType=cv2.LINE_8, shift=4)
    return mask.astype(bool)


def eye_contrast(gray: npt.ArrayLike, landmarks_px: npt.ArrayLike, eye: EyeIndices) -> float:
    """Contrast of one eye opening: (p90 - p10 of its pixels) / the median of the skin below it.

    An open eye shows bright sclera beside a dark iris; a dark lens (or a closed lid) is flat.
    The skin is a band from 0.35 to 0.6 eye widths below the lower lid, as wide as the eye.
    `gray`: a 2-D uint8 or float image. NaN when the eye is narrower than `MIN_EYE_WIDTH_PX` or
    off the image.
    """
    image: npt.NDArray[Any] = np.asarray(gray)
    points = np.asarray(landmarks_px, dtype=np.float64)[:, :2]
    polygon = points[list(eye.contour)]
    width = float(np.linalg.norm(points[eye.outer] - points[eye.inner]))
    x0 = max(0, math.floor(float(polygon[:, 0].min())))
    x1 = min(image.shape[1], math.ceil(float(polygon[:, 0].max())) + 1)
    y0 = max(0, math.floor(float(polygon[:, 1].min())))
    y1 = min(image.shape[0], math.ceil(float(polygon[:, 1].max())) + 1)
    if x1 - x0 < 4 or y1 - y0 < 2 or width < MIN_EYE_WIDTH_PX:
        return math.nan
    mask = _fill_polygon(polygon - np.array([x0, y0]), (y1 - y0, x1 - x0))
    values = image[y0:y1, x0:x1][mask].astype(np.float64)
    if values.size < 6:
        return math.nan
    reference = _skin_reference(image, polygon, width, x0, x1)
    p10, p90 = np.quantile(values, [0.1, 0.9])
    return float((p90 - p10) / reference)


def _skin_reference(
    image: npt.NDArray[Any], polygon: FloatArray, width: float, x0: int, x1: int
) -> float:
    """The median of the skin below the eye (a band 0.35-0.6 eye widths below the lower lid, as
    wide as the eye), at least 1; NaN when the band is off the image."""
    lower_y = float(polygon[9:, 1].max())
    skin_y0 = max(0, int(lower_y + 0.35 * width))
    skin_y1 = min(image.shape[0], int(lower_y + 0.6 * width) + 1)
    skin = image[skin_y0:skin_y1, x0:x1]
    if skin.size == 0:
        return math.nan
    return max(float(np.median(skin)), 1.0)


def eye_sharpness(gray: npt.ArrayLike, landmarks_px: npt.ArrayLike, eye: EyeIndices) -> float:
    """Edge strength around one eye: the 90th percentile of the gradient magnitude (3x3 Sobel,
    grey levels per pixel) in the eye's box grown by 0.15 eye widths on every side, divided by the
    median of the skin below the eye (as `eye_contrast`). About 0.8-3 on focused faces, below 0.6
    under strong motion blur or glare (docs/eyes.md). NaN when the eye is narrower than
    `MIN_EYE_WIDTH_PX` or off the image.
    """
    import cv2

    image: npt.NDArray[Any] = np.asarray(gray)
    points = np.asarray(landmarks_px, dtype=np.float64)[:, :2]
    polygon = points[list(eye.contour)]
    width = float(np.linalg.norm(points[eye.outer] - points[eye.inner]))
    pad = 0.15 * width
    x0 = max(0, math.floor(float(polygon[:, 0].min()) - pad))
    x1 = min(image.shape[1], math.ceil(float(polygon[:, 0].max()) + pad) + 1)
    y0 = max(0, math.floor(float(polygon[:, 1].min()) - pad))
    y1 = min(image.shape[0], math.ceil(float(polygon[:, 1].max()) + pad) + 1)
    if x1 - x0 < 4 or y1 - y0 < 4 or width < MIN_EYE_WIDTH_PX:
        return math.nan
    crop = image[y0:y1, x0:x1].astype(np.float32)
    magnitude = cv2.magnitude(
        cv2.Sobel(crop, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(crop, cv2.CV_32F, 0, 1, ksize=3)
    ).ravel()
    rank = int(0.9 * (magnitude.size - 1))  # the 90th percentile, lower value (no interpolation)
    edge = float(np.partition(magnitude, rank)[rank])
    return edge / _skin_reference(image, polygon, width, x0, x1)
