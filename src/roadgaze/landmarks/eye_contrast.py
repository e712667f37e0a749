"""Can the eyes be seen at all: the contrast inside the eye opening and the edges around it.

An open eye shows bright sclera beside a dark iris; a dark lens, glare or a hand is flat. Measured
relative to the skin just below the eye, so it does not depend on the exposure. With the lids
looking open, a flat opening in both eyes means the eyes are hidden (`EyesConfig.min_contrast`).
The lids are sharp edges in a focused image; motion blur, glare and a washed-out picture soften
them, and MediaPipe then draws the lids nearly shut over open eyes: lids that read closed on eyes
without edges cannot be judged (`EyesConfig.min_sharpness`). An eye's edges run mostly along it
(the lids, the lid crease, the brow), open or closed; hair hanging over it (a fringe) runs across
it: edges mostly across the eye in both eyes mean the eyes are hidden
(`EyesConfig.min_lid_share`). The evidence and its limits: docs/eyes.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
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
    return mask.view(np.bool_)  # the 0/1 bytes as booleans, without a copy


@dataclass(frozen=True, slots=True)
class _Outline:
    """One eye's opening in the image, measured once for both checks."""

    polygon: FloatArray
    """(16, 2) x, y of `EyeIndices.contour`, pixels, float64."""
    width_px: float
    """Outer to inner corner."""
    low: tuple[float, float]
    """The polygon's minimum x and y."""
    high: tuple[float, float]
    """Its maximum x and y."""
    lower_lid_y: float
    """The lowest y of the lower lid (the skin band is measured from it)."""
    axis: tuple[float, float]
    """The unit vector from the inner to the outer corner (along the lids)."""


def _outline(landmarks_px: npt.ArrayLike, eye: EyeIndices) -> _Outline:
    """The eye's polygon and width from the 478 landmarks.

    Only the eye's 18 rows are taken and converted to float64 (converting all 478 first, as a
    plain `np.asarray(..., float64)` would, costs more than the rest of this function).
    """
    rows = np.asarray(landmarks_px)[np.array((*eye.contour, eye.outer, eye.inner)), :2]
    points = rows.astype(np.float64)
    polygon = points[:-2]
    corners = points[-2] - points[-1]
    low, high = polygon.min(axis=0), polygon.max(axis=0)
    width_px = math.sqrt(corners.dot(corners))  # np.linalg.norm's arithmetic, without its checks
    along = corners / width_px if width_px > 0 else np.array([1.0, 0.0])
    return _Outline(
        polygon=polygon,
        width_px=width_px,
        low=(float(low[0]), float(low[1])),
        high=(float(high[0]), float(high[1])),
        lower_lid_y=float(polygon[9:, 1].max()),
        axis=(float(along[0]), float(along[1])),
    )


def eye_contrast(gray: npt.ArrayLike, landmarks_px: npt.ArrayLike, eye: EyeIndices) -> float:
    """Contrast of one eye opening: (p90 - p10 of its pixels) / the median of the skin below it.

    An open eye shows bright sclera beside a dark iris; a dark lens (or a closed lid) is flat.
    The skin is a band from 0.35 to 0.6 eye widths below the lower lid, as wide as the eye.
    `gray`: a 2-D uint8 or float image. NaN when the eye is narrower than `MIN_EYE_WIDTH_PX` or
    off the image.
    """
    return _contrast(np.asarray(gray), _outline(landmarks_px, eye))


def eye_sharpness(gray: npt.ArrayLike, landmarks_px: npt.ArrayLike, eye: EyeIndices) -> float:
    """Edge strength around one eye: the 90th percentile of the gradient magnitude (3x3 Sobel,
    grey levels per pixel) in the eye's box grown by 0.15 eye widths on every side, divided by the
    median of the skin below the eye (as `eye_contrast`). About 0.8-3 on focused faces, below 0.6
    under strong motion blur or glare (docs/eyes.md). NaN when the eye is narrower than
    `MIN_EYE_WIDTH_PX` or off the image.
    """
    return _edges(np.asarray(gray), _outline(landmarks_px, eye))[0]


def eye_lid_share(gray: npt.ArrayLike, landmarks_px: npt.ArrayLike, eye: EyeIndices) -> float:
    """How much of the edge energy around one eye runs along it: the share of the squared
    gradient (3x3 Sobel, in the box of `eye_sharpness`) that points across the eye's corner
    line, i.e. comes from edges parallel to it (the lids, the crease, the brow). Head roll does
    not change it. About 0.5-0.9 on seen eyes, open or closed; about 0.1 with hair strands
    hanging across them (docs/eyes.md). NaN when the eye is narrower than `MIN_EYE_WIDTH_PX`,
    off the image, or the box is flat.
    """
    return _edges(np.asarray(gray), _outline(landmarks_px, eye))[1]


def eye_checks(
    gray: npt.ArrayLike, landmarks_px: npt.ArrayLike, eye: EyeIndices
) -> tuple[float, float, float]:
    """(`eye_contrast`, `eye_sharpness`, `eye_lid_share`) of one eye, its outline measured
    once."""
    image: npt.NDArray[Any] = np.asarray(gray)
    outline = _outline(landmarks_px, eye)
    sharpness, lid_share = _edges(image, outline)
    return _contrast(image, outline), sharpness, lid_share


def _contrast(image: npt.NDArray[Any], outline: _Outline) -> float:
    x0 = max(0, math.floor(outline.low[0]))
    x1 = min(image.shape[1], math.ceil(outline.high[0]) + 1)
    y0 = max(0, math.floor(outline.low[1]))
    y1 = min(image.shape[0], math.ceil(outline.high[1]) + 1)
    if x1 - x0 < 4 or y1 - y0 < 2 or outline.width_px < MIN_EYE_WIDTH_PX:
        return math.nan
    mask = _fill_polygon(outline.polygon - np.array([x0, y0]), (y1 - y0, x1 - x0))
    values = image[y0:y1, x0:x1][mask]
    if values.size < 6:
        return math.nan
    reference = _skin_reference(image, outline, x0, x1)
    p10, p90 = _quantiles_10_90(values)
    return (p90 - p10) / reference


def _quantiles_10_90(values: npt.NDArray[Any]) -> tuple[float, float]:
    """`np.quantile(values.astype(float64), [0.1, 0.9])`, bit for bit: numpy's default (linear)
    method, its virtual index (n - 1) q and its interpolation formula, on a partition at the four
    ranks needed. np.quantile's generic path costs 50 times as much on a few hundred pixels.
    NaN pixels (a float image) give NaN, as in np.quantile. Partitions `values` in place (the
    caller's own copy)."""
    count = values.size
    ranks = []
    for q in (0.1, 0.9):
        index = (count - 1) * q
        below = math.floor(index)
        ranks.append((below, index - below))
    kth = [r for below, _ in ranks for r in (below, below + 1)]
    values.partition([*kth, count - 1])  # the last rank: NaN sorts there
    if math.isnan(float(values[-1])):
        return math.nan, math.nan
    result = []
    for below, gamma in ranks:
        a, b = float(values[below]), float(values[below + 1])
        difference = b - a
        # numpy's _lerp: from the nearer end, so that gamma 0 or 1 gives an end exactly.
        result.append(b - difference * (1 - gamma) if gamma >= 0.5 else a + difference * gamma)
    return result[0], result[1]


SKIN_BANDS = ((0.35, 0.6), (0.9, 1.2))
"""Where the skin is measured below the eye, in eye widths below the lower lid: just below it,
and on the cheek. The brighter median is the skin: large dark lenses cover the first band too
(their frame reaches half an eye width below the lid), and against their own dark glass a lens's
reflection reads as contrast."""


def _skin_reference(image: npt.NDArray[Any], outline: _Outline, x0: int, x1: int) -> float:
    """The skin below the eye: the brighter median of the `SKIN_BANDS` (columns `x0:x1`), at
    least 1; NaN when both bands are off the image."""
    lower_y, width = outline.lower_lid_y, outline.width_px
    medians = []
    for top, bottom in SKIN_BANDS:
        skin_y0 = max(0, int(lower_y + top * width))
        skin_y1 = min(image.shape[0], int(lower_y + bottom * width) + 1)
        skin = image[skin_y0:skin_y1, x0:x1]
        if skin.size:
            medians.append(_median(skin))
    if not medians:
        return math.nan
    return max(*medians, 1.0)


def _median(values: npt.NDArray[Any]) -> float:
    """`np.median(values)`. For integer grey levels by a partition at the middle rank(s): the
    mean of two integers is exact in floats, and np.median's generic path costs four times as
    much; other dtypes take np.median itself."""
    if values.dtype.kind not in "ui":
        return float(np.median(values))
    flat = values.flatten()  # a copy, partitioned in place
    middle = flat.size // 2
    if flat.size % 2:
        flat.partition(middle)
        return float(flat[middle])
    flat.partition([middle - 1, middle])
    return (int(flat[middle - 1]) + int(flat[middle])) / 2


def _edges(image: npt.NDArray[Any], outline: _Outline) -> tuple[float, float]:
    """(sharpness, lid share) of the eye's box: one Sobel pass for both."""
    import cv2

    pad = 0.15 * outline.width_px
    x0 = max(0, math.floor(outline.low[0] - pad))
    x1 = min(image.shape[1], math.ceil(outline.high[0] + pad) + 1)
    y0 = max(0, math.floor(outline.low[1] - pad))
    y1 = min(image.shape[0], math.ceil(outline.high[1] + pad) + 1)
    if x1 - x0 < 4 or y1 - y0 < 4 or outline.width_px < MIN_EYE_WIDTH_PX:
        return math.nan, math.nan
    crop = image[y0:y1, x0:x1]
    if crop.dtype != np.uint8:
        # A uint8 crop goes to Sobel as it is: its sums are small integers, exact in float32.
        crop = crop.astype(np.float32)
    gx = cv2.Sobel(crop, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(crop, cv2.CV_32F, 0, 1, ksize=3)
    magnitude = cv2.magnitude(gx, gy).ravel()
    rank = int(0.9 * (magnitude.size - 1))  # the 90th percentile, lower value (no interpolation)
    magnitude.partition(rank)
    edge = float(magnitude[rank])
    return edge / _skin_reference(image, outline, x0, x1), _lid_share(gx, gy, outline.axis)


def _lid_share(gx: npt.NDArray[Any], gy: npt.NDArray[Any], axis: tuple[float, float]) -> float:
    """The share of the squared gradient across `axis` (edges running along it): with the unit
    normal n = (-ay, ax), sum((g . n)^2) / sum(|g|^2), from the three sums of the structure
    tensor. NaN for a flat box."""
    xx, yy = float(np.dot(gx.ravel(), gx.ravel())), float(np.dot(gy.ravel(), gy.ravel()))
    total = xx + yy
    if total <= 0:
        return math.nan
    xy = float(np.dot(gx.ravel(), gy.ravel()))
    ax, ay = axis
    return (ay * ay * xx + ax * ax * yy - 2.0 * ax * ay * xy) / total
