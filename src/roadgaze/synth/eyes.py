"""Synthetic eyes with known truth: the irises turned and the lids closed in the photo's texture.

`EyeRenderer` is a `FaceRenderer` whose frames also take an `EyeState` (eye-in-head yaw and
pitch, openness of each eye). Both edits are made in the texture, in the photo's own frame, so
the renderer's per-triangle warp then turns them with the head like the rest of the face:

1. **Eye rotation.** Inside the eye opening the photo's iris disc is in-painted away (push-pull
   from the visible sclera) and drawn again where an eyeball would put it: the photo's iris
   centre is taken to lie `b W` in front of the corner midpoint and `k W` in front of the eye's
   rotation centre (W = the eye's corner-to-corner width; k = 0.40, b = 0.20 as in
   `roadgaze.landmarks.eyes.EyeballConstants`). The rotated iris centre is turned with the head,
   projected, and mapped back into the texture through the affine map that takes the eye contour
   from the texture to the frame; the disc is foreshortened by the angle between the gaze and
   the camera axis and clipped by the lids. Iris pixels the photo's lids hid are filled with the
   iris's mean colour at the same radius.
2. **Lids.** Each column of the eye opening closes toward a meeting line a quarter of the way up
   from the lower lid: the upper lid's margin (the lash line and lid edge, a band 0.12 W tall)
   slides down, the lid skin above it follows, filled from the skin around the eye; the lower
   margin rises. At openness 0 the opening is lid skin with the lash line at the meeting line,
   as a closed eye looks. With `lid_follow` the upper lid also follows downward gaze (about 1:1,
   as real lids do), so a downward glance narrows the eye.

Truth: eye-in-head yaw and pitch relative to the photo's own eyes (degrees, project convention),
openness as a fraction of the photo's own aperture (1 open as photographed, 0 closed). The mesh
is not edited, so with open eyes looking ahead the frame is the plain render. What MediaPipe
recovers from these renders, and where it stops being trustworthy (a turned or pitched head):
docs/synth.md.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.config import Config
from roadgaze.landmarks.eyes import EYEBALL, EYES, EyeIndices
from roadgaze.synth.eye_state import EyeState as EyeState
from roadgaze.synth.layers import Layer
from roadgaze.synth.renderer import (
    DEFAULT_SIZE,
    FaceRenderer,
    ImageBGR,
    push_pull_fill,
    turn_points,
)
from roadgaze.types import FloatArray

MEETING_FRACTION = 0.25
"""Closed lids meet this fraction of the aperture above the lower lid (the lower lid rises)."""
UPPER_BAND_EYE_WIDTHS = 0.2
"""The upper lid margin that slides down as the lid closes: lashes and lid edge."""
LASH_EYE_WIDTHS = 0.07
"""Thickness of the lash line drawn along a closing upper lid."""
LOWER_BAND_EYE_WIDTHS = 0.05
LOWER_MARGIN_DROP_EYE_WIDTHS = 0.06
"""MediaPipe's lower-lid landmarks lie 1-2 px (0.03-0.06 W) above the visible lower margin on the
astronaut photo: the opening is taken that much lower, so no sclera shows through a closed lid."""
_FOLLOW_WEIGHTS = (0.55, 0.85, 1.0, 1.0, 1.0, 0.85, 0.55)
"""How far each upper-lid landmark (outer to inner) follows the gaze: the corners stay put."""


@dataclass(frozen=True, slots=True)
class _EyePatch:
    """One eye's precomputed texture region (output-frame pixels of the unturned photo)."""

    x0: int
    y0: int
    original: npt.NDArray[np.float32]
    sclera: npt.NDArray[np.float32]
    """The region with the iris in-painted away."""
    iris: npt.NDArray[np.float32]
    """The region whose iris disc is complete (hidden parts filled radially)."""
    skin: npt.NDArray[np.float32]
    """The region with the opening and both lid margins filled from the skin around the eye."""
    opening: npt.NDArray[np.float32]
    """Alpha (0..1) of the eye opening between the lid landmarks (where the iris is drawn)."""
    upper_y: FloatArray
    """Per column: y of the upper lid margin (NaN outside the eye's corners), region pixels."""
    lower_y: FloatArray
    """Per column: y of the visible lower lid margin (`LOWER_MARGIN_DROP_EYE_WIDTHS` below the
    landmarks)."""
    lash_bgr: npt.NDArray[np.float32]
    """The colour of the photo's upper lashes (the darkest tenth of the upper margin)."""
    centre: tuple[float, float]
    """Iris centre, region pixels."""
    radius_px: float
    width_px: float


def _lid_curves(
    contour: FloatArray, columns: int, x0: int, y0: int
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Upper and lower lid y per region column (pixel centres; NaN beyond the corners), and the
    column's position between the corners (0..1)."""
    upper = contour[:9]  # outer corner, 7 upper lid points, inner corner
    lower = np.vstack([contour[8:], contour[:1]])  # inner corner, 7 lower lid points, outer
    xs = np.arange(columns) + 0.5 + x0
    left, right = float(contour[:, 0].min()), float(contour[:, 0].max())
    inside = (xs >= left) & (xs <= right)
    curves = []
    for line in (upper, lower):
        order = np.argsort(line[:, 0])
        along = np.interp(xs, line[order, 0], line[order, 1]) - y0
        curves.append(np.where(inside, along, np.nan))
    position = np.clip((xs - left) / max(right - left, 1e-9), 0.0, 1.0)
    return curves[0], curves[1], position


class EyeRenderer(FaceRenderer):
    """A `FaceRenderer` whose frames also take an `EyeState` (`render_eyes`).

    `lid_follow`: how far the upper lid follows downward gaze (0 not at all, 1 as far as the iris
    centre moves). `render(yaw, pitch)` is unchanged, and `render_eyes` with `EyeState()` gives the
    same frame, unless `eyeball_at_rest`: then the iris of eyes at rest is drawn by the eyeball
    model too whenever the head is turned or pitched. The photo's own iris lies flat in the eye
    opening (the mesh closes the opening with a flat strip), so with the head pitched up 20 deg
    MediaPipe reads eyes at rest as looking 14 deg down; the eyeball model puts the iris `b W` in
    front of the corners, where a turned head shows it (the conformance drives use it).
    """

    def __init__(
        self,
        photo_bgr: ImageBGR,
        size: tuple[int, int] = DEFAULT_SIZE,
        landmarks_px: FloatArray | None = None,
        config: Config | None = None,
        lid_follow: float = 1.0,
        eyeball_at_rest: bool = False,
    ) -> None:
        super().__init__(photo_bgr, size, landmarks_px, config)
        self.k = EYEBALL.k
        self.b = EYEBALL.b
        self.lid_follow = lid_follow
        self.eyeball_at_rest = eyeball_at_rest
        self.base_texture: ImageBGR = np.asarray(self.texture, dtype=np.uint8)
        self.over: Layer | None = None
        self.rest_texture = self.base_texture
        self._patches = {eye.side: self._eye_patch(eye) for eye in EYES}

    def _contour(self, eye: EyeIndices) -> FloatArray:
        return np.asarray(self.mesh.points_px[list(eye.contour), :2], dtype=np.float64)

    def _eye_patch(self, eye: EyeIndices) -> _EyePatch:
        import cv2

        points = self.mesh.points_px
        centre = points[eye.iris_center, :2]
        radius = float(np.mean(np.linalg.norm(points[list(eye.iris_ring), :2] - centre, axis=1)))
        width = float(np.linalg.norm(points[eye.outer, :2] - points[eye.inner, :2]))
        contour = self._contour(eye)
        margin = math.ceil(max(radius, UPPER_BAND_EYE_WIDTHS * width) + 6)
        x0 = math.floor(float(contour[:, 0].min())) - margin
        y0 = math.floor(float(contour[:, 1].min())) - margin
        x1 = math.ceil(float(contour[:, 0].max())) + margin
        y1 = math.ceil(float(contour[:, 1].max())) + margin
        original = self.base_texture[y0:y1, x0:x1].astype(np.float32)
        height, columns = original.shape[:2]
        upper_y, landmark_lower_y, position = _lid_curves(contour, columns, x0, y0)
        lower_y = landmark_lower_y + LOWER_MARGIN_DROP_EYE_WIDTHS * width * np.sin(np.pi * position)
        ys = np.arange(height, dtype=np.float64)[:, None] + 0.5
        inside = np.minimum(ys - upper_y[None, :], landmark_lower_y[None, :] - ys) + 0.5
        opening = np.asarray(np.nan_to_num(np.clip(inside, 0.0, 1.0)), dtype=np.float32)
        xs = np.arange(columns, dtype=np.float64)[None, :] + 0.5
        cx, cy = float(centre[0] - x0), float(centre[1] - y0)
        distance = np.hypot(xs - cx, ys - cy)
        disc = distance <= radius + 1.5
        sclera = original.copy()
        filled = push_pull_fill(original, np.asarray((opening > 0.6) & ~disc, dtype=np.float32))
        hole = (opening > 0.0) & disc
        sclera[hole] = filled[hole]
        # The complete iris: visible pixels as they are, hidden ones from the radial mean colour.
        visible = (opening > 0.8) & (distance <= radius + 0.5)
        rings = np.minimum((distance / 0.5).astype(np.int32), 200)
        iris = original.copy()
        counts = np.bincount(rings[visible], minlength=201)
        valid = np.flatnonzero(counts > 0)
        for channel in range(3):
            sums = np.bincount(rings[visible], original[..., channel][visible], minlength=201)
            profile = np.interp(np.arange(201), valid, sums[valid] / counts[valid])
            iris[..., channel] = np.where(visible, original[..., channel], profile[rings])
        # Lid skin: everything but the opening and the lid margins, pushed into them.
        upper_band = UPPER_BAND_EYE_WIDTHS * width
        lower_band = LOWER_BAND_EYE_WIDTHS * width
        lids = (ys >= upper_y[None, :] - upper_band - 1.0) & (
            ys <= lower_y[None, :] + lower_band + 1.0
        )
        known = np.asarray(~lids, dtype=np.float32)
        blurred = np.asarray(cv2.GaussianBlur(original, (0, 0), 0.6), dtype=np.float32)
        skin = push_pull_fill(blurred, known)
        margin_band = (ys >= upper_y[None, :] - upper_band) & (ys <= upper_y[None, :] + 1.0)
        margin_pixels = original[margin_band]
        luma = margin_pixels.mean(axis=1)
        lash = margin_pixels[luma <= np.percentile(luma, 10)].mean(axis=0)
        return _EyePatch(
            x0=x0,
            y0=y0,
            original=original,
            sclera=sclera.astype(np.float32),
            iris=iris.astype(np.float32),
            skin=skin.astype(np.float32),
            opening=opening,
            upper_y=upper_y,
            lower_y=lower_y,
            lash_bgr=np.asarray(lash, dtype=np.float32),
            centre=(cx, cy),
            radius_px=radius,
            width_px=width,
        )

    def iris_placement(
        self, eye: EyeIndices, yaw_deg: float, pitch_deg: float, state: EyeState
    ) -> tuple[FloatArray, FloatArray]:
        """Where the turned iris is drawn in the texture: (centre in texture pixels, 2x2 map from
        texture offsets to offsets in the photo's iris disc)."""
        patch = self._patches[eye.side]
        points = self.mesh.points_px
        contour = list(eye.contour)
        source = points[contour, :2]
        target = turn_points(points[contour], self.mesh.pivot_px, yaw_deg, pitch_deg)[:, :2]
        design = np.column_stack([source, np.ones(len(source))])
        affine = np.linalg.lstsq(design, target, rcond=None)[0].T  # 2x3, texture -> frame
        linear = affine[:, :2]
        middle_z = float(points[[eye.outer, eye.inner], 2].mean())
        width = patch.width_px
        centre_texture = np.array([patch.centre[0] + patch.x0, patch.centre[1] + patch.y0])
        rest = np.array([centre_texture[0], centre_texture[1], middle_z - self.b * width])
        rotation_centre = rest + np.array([0.0, 0.0, self.k * width])  # z grows away
        e, p = math.radians(state.eye_yaw_deg), math.radians(state.eye_pitch_deg)
        direction = np.array([math.sin(e) * math.cos(p), -math.sin(p), -math.cos(e) * math.cos(p)])
        iris_frame = turn_points(
            (rotation_centre + self.k * width * direction)[None, :],
            self.mesh.pivot_px,
            yaw_deg,
            pitch_deg,
        )[0, :2]
        centre = np.linalg.solve(linear, iris_frame - affine[:, 2])
        ends = turn_points(np.vstack([np.zeros(3), direction]), np.zeros(3), yaw_deg, pitch_deg)
        gaze = ends[1] - ends[0]
        planar = float(np.hypot(gaze[0], gaze[1]))
        if planar < 1e-9:
            squash = np.eye(2)
        else:
            along = gaze[:2] / planar
            across = np.array([-along[1], along[0]])
            squash = np.outer(across, across) + abs(gaze[2]) * np.outer(along, along)
        scale = math.sqrt(abs(float(np.linalg.det(linear))))
        to_disc = np.linalg.solve(squash, linear) / scale
        return centre, to_disc

    def _draw_iris(
        self, patch: _EyePatch, centre: FloatArray, to_disc: FloatArray
    ) -> npt.NDArray[np.float32]:
        import cv2

        height, columns = patch.opening.shape
        ys, xs = np.mgrid[0:height, 0:columns].astype(np.float64)
        dx = xs + 0.5 - (centre[0] - patch.x0)
        dy = ys + 0.5 - (centre[1] - patch.y0)
        u = to_disc[0, 0] * dx + to_disc[0, 1] * dy
        v = to_disc[1, 0] * dx + to_disc[1, 1] * dy
        cx, cy = patch.centre
        iris = cv2.remap(
            patch.iris,
            (cx + u - 0.5).astype(np.float32),
            (cy + v - 0.5).astype(np.float32),
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REPLICATE,
        )
        alpha = np.clip(patch.radius_px + 0.5 - np.hypot(u, v), 0.0, 1.0)[..., None]
        eye = patch.sclera * (1 - alpha) + iris * alpha
        opening = patch.opening[..., None]
        return np.asarray(patch.original * (1 - opening) + eye * opening, dtype=np.float32)

    def _close_lids(
        self,
        patch: _EyePatch,
        region: npt.NDArray[np.float32],
        openness: float,
        lid_drop_px: FloatArray,
    ) -> npt.NDArray[np.float32]:
        """Slide the upper margin down to its new place (skin above it) and the lower one up."""
        import cv2

        height, columns = region.shape[:2]
        upper, lower = patch.upper_y, patch.lower_y
        meet = lower - MEETING_FRACTION * (lower - upper)
        new_upper = meet + openness * (upper - meet)
        new_upper = np.minimum(np.maximum(new_upper, upper + lid_drop_px), lower)
        new_lower = np.maximum(meet + openness * (lower - meet), new_upper)
        down = np.nan_to_num(new_upper - upper)
        up = np.nan_to_num(lower - new_lower)
        ys = np.arange(height, dtype=np.float64)[:, None] + 0.5
        upper_band = UPPER_BAND_EYE_WIDTHS * patch.width_px
        lower_band = LOWER_BAND_EYE_WIDTHS * patch.width_px
        # Where each pixel's colour comes from: the margins move, nothing else does.
        in_upper = (ys >= upper - upper_band + down) & (ys < new_upper + 0.5)
        in_lower = (ys > new_lower - 0.5) & (ys <= lower + lower_band - up)
        source_y = np.where(in_upper, ys - down, np.where(in_lower, ys + up, ys))
        xs = np.broadcast_to(np.arange(columns, dtype=np.float64)[None, :], (height, columns))
        moved = cv2.remap(
            region,
            xs.astype(np.float32),
            np.nan_to_num(source_y - 0.5, nan=0.0).astype(np.float32),
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REPLICATE,
        )
        # Uncovered above the moved upper margin, and below the moved lower one: lid skin.
        skin_upper = np.clip(upper - upper_band + down - ys + 0.5, 0.0, 1.0) * (
            ys > upper - upper_band - 0.5
        )
        skin_lower = np.clip(ys - (lower + lower_band - up) + 0.5, 0.0, 1.0) * (
            ys < lower + lower_band + 0.5
        )
        skin_alpha = np.nan_to_num(np.maximum(skin_upper * (down > 0), skin_lower * (up > 0)))
        alpha = skin_alpha[..., None].astype(np.float32)
        result = moved * (1 - alpha) + patch.skin * alpha
        # The lash line along the lowered upper lid, as strong as the lid is closed.
        closed = np.clip((down / max(patch.width_px, 1e-9)) / 0.1, 0.0, 1.0)
        half = 0.5 * LASH_EYE_WIDTHS * patch.width_px + 0.5
        lash = np.clip(half - np.abs(ys - (new_upper - half + 0.5)), 0.0, 1.0) * closed
        lash_alpha = (0.85 * np.nan_to_num(lash))[..., None].astype(np.float32)
        return np.asarray(result * (1 - lash_alpha) + patch.lash_bgr * lash_alpha, dtype=np.float32)

    def eye_texture(self, yaw_deg: float, pitch_deg: float, state: EyeState) -> ImageBGR:
        """The photo texture with both eyes drawn as `state` says, for this head pose."""
        head_moved = self.eyeball_at_rest and (yaw_deg != 0.0 or pitch_deg != 0.0)
        if state.at_rest and not head_moved:
            return self.rest_texture
        texture = self.base_texture.copy()
        for eye, openness in ((EYES[0], state.openness_right), (EYES[1], state.openness_left)):
            patch = self._patches[eye.side]
            region = patch.original
            if head_moved or state.eye_yaw_deg != 0.0 or state.eye_pitch_deg != 0.0:
                centre, to_disc = self.iris_placement(eye, yaw_deg, pitch_deg, state)
                region = self._draw_iris(patch, centre, to_disc)
            drop_px = max(
                0.0, -self.lid_follow * self.k * math.sin(math.radians(state.eye_pitch_deg))
            )
            drop = self._lid_drop(patch, drop_px * patch.width_px)
            region = self._close_lids(patch, region, min(1.0, max(0.0, openness)), drop)
            height, columns = region.shape[:2]
            texture[patch.y0 : patch.y0 + height, patch.x0 : patch.x0 + columns] = np.clip(
                region + 0.5, 0, 255
            ).astype(np.uint8)
        return texture if self.over is None else self.over.over(texture)

    def repainted(self, texture: ImageBGR, over: Layer | None = None) -> EyeRenderer:
        """A copy whose photo texture is `texture` (paint under the eyes: the lids close over
        it) with `over` composited after the eyes are drawn (`roadgaze.synth.layers`)."""
        dressed = copy.copy(self)
        dressed.base_texture = np.asarray(texture, dtype=np.uint8)
        dressed._patches = {eye.side: dressed._eye_patch(eye) for eye in EYES}
        dressed.over = over
        dressed.rest_texture = dressed.base_texture if over is None else over.over(texture)
        dressed.texture = dressed.rest_texture
        return dressed

    @staticmethod
    def _lid_drop(patch: _EyePatch, drop_px: float) -> FloatArray:
        """Per column, how far the upper lid follows a downward gaze (less toward the corners)."""
        valid = np.flatnonzero(np.isfinite(patch.upper_y))
        weights = np.zeros_like(patch.upper_y)
        if valid.size:
            along = np.linspace(0.0, 1.0, valid.size)
            weights[valid] = np.interp(
                along, np.linspace(0, 1, len(_FOLLOW_WEIGHTS)), _FOLLOW_WEIGHTS
            )
        return np.asarray(drop_px * weights, dtype=np.float64)

    def render_eyes(
        self, yaw_deg: float, pitch_deg: float, state: EyeState, mouth_open: float = 0.0
    ) -> ImageBGR:
        """One BGR frame: the head at yaw/pitch, the eyes as `state` says, the jaw opened by
        `mouth_open` (`roadgaze.synth.mouth`)."""
        self.texture = self.eye_texture(yaw_deg, pitch_deg, state)
        try:
            return self.render(yaw_deg, pitch_deg, mouth_open)
        finally:
            self.texture = self.rest_texture
