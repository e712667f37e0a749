"""What covers part of the face and moves with it: a face mask, a hair fringe, eyelash makeup.

Painted on the texture (`roadgaze.synth.layers`), so the renderer turns them with the face;
geometry in face widths W (about 14 cm) and eye widths (the eye's corner-to-corner width):

- **A face mask** (`face_mask`): a light-blue surgical mask from the nose bridge (landmarks
  196-197-419, half way down the nose, where its wire is pinched) across the cheeks 1.5-2 cm
  under the eyes to the face's sides, down round the chin. It takes the face's own light
  (the skin's smoothed brightness, softened: cloth does not follow the nose's hollows), has
  three horizontal pleats across its middle and a faint weave; it hides the mouth, open or not.
  Under the chin and the ear loops are drawn on the frame (`MaskBelowChin`): the mask goes
  `MASK_UNDER_CHIN_W` under the chin, and each loop runs from its corners back to the ear on
  the side the camera sees.
- **A fringe** (`fringe`): hair strands of the driver's own hair colour (the photo's hair
  above the forehead, darkened to the shade under a fringe) hanging from the top of the
  forehead over the eyes to `FRINGE_BELOW_EYES_W` below them, dense at the top and with gaps
  lower down, so the eyes are glimpsed through it at best.
- **Thick eyelash makeup** (`lash_makeup`): a black line `LINER_EYE_W` thick along each upper
  lid with a short wing past the outer corner, mascara'd lashes (strokes up and out from the lid,
  `LASH_EYE_W` long) and a thinner line along the lower lid. Painted *under* the eyes: the lids
  close with it.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from roadgaze.landmarks.eye_landmarks import EYES
from roadgaze.synth.facial_hair import JAW_LINE, under_jaw
from roadgaze.synth.head import HeadFrame, turn
from roadgaze.synth.layers import Layer, region_alpha
from roadgaze.synth.renderer import FaceRenderer, ImageBGR
from roadgaze.types import FloatArray

MASK_AREA = (
    *(234, 93, 132, 58, 172, 136, 150, 149, 176, 148, 152, 377, 400, 378, 379),
    *(365, 397, 288, 361, 323, 454, 447, 345, 346, 347, 329, 277, 343, 419, 197),
    *(196, 114, 47, 100, 118, 117, 116, 227),
)
"""The mask's outline: the face oval from ear to ear round the chin, then its top edge back
across the left cheek, over the nose bridge and across the right cheek."""
MASK_BGR = (214, 190, 152)
"""Surgical-mask light blue."""
MASK_UNDER_CHIN_W = 0.08
PLEATS = (0.4, 0.55, 0.7)
"""The pleats' heights, as fractions of the way from the mask's top to the chin."""
FRINGE_BELOW_EYES_W = 0.05
FRINGE_STRANDS_PER_W = 90
HAIRLINE = (54, 103, 67, 109, 10, 338, 297, 332, 284)
"""The top of the mesh across the forehead, where the fringe starts."""
LINER_EYE_W, LASH_EYE_W = 0.11, 0.19
MAKEUP_BGR = (22, 18, 20)


def _face_light(renderer: FaceRenderer) -> npt.NDArray[np.float32]:
    """The face's light, smoothed and softened: 1 where the skin is as bright as its median."""
    import cv2

    grey = cv2.cvtColor(renderer.texture, cv2.COLOR_BGR2GRAY).astype(np.float32)
    smooth = cv2.GaussianBlur(grey, (0, 0), 0.08 * renderer.mesh.face_width_px)
    inside = region_alpha(grey.shape, renderer.mesh.points_px[list(MASK_AREA), :2], 0.0) > 0.5
    level = float(np.median(smooth[inside])) if inside.any() else float(smooth.mean())
    return np.asarray(np.clip(smooth / max(level, 1.0), 0.5, 1.3) ** 0.6, dtype=np.float32)


def face_mask(renderer: FaceRenderer, rng: np.random.Generator) -> Layer:
    """A surgical mask over the nose and mouth (a texture layer)."""
    points = renderer.mesh.points_px
    shape = renderer.texture.shape[:2]
    head = HeadFrame.of(renderer)
    area = region_alpha(shape, points[list(MASK_AREA), :2], 0.5)
    down = head.down_2d()
    top, chin = points[197, :2], points[152, :2]
    ys, xs = np.mgrid[0 : shape[0], 0 : shape[1]].astype(np.float64)
    height = max(float((chin - top) @ down), 1.0)
    fraction = ((xs - top[0]) * down[0] + (ys - top[1]) * down[1]) / height
    gain = np.ones(shape, dtype=np.float64)
    fold = 0.012 * head.width_px / height
    for pleat in PLEATS:
        gain -= 0.22 * np.exp(-(((fraction - pleat) / fold) ** 2))  # the fold's shadow
        gain += 0.1 * np.exp(-(((fraction - pleat + 2.2 * fold) / fold) ** 2))  # its lit edge
    weave = rng.normal(0.0, 2.5, (*shape, 1)).astype(np.float32)
    light = (_face_light(renderer) * gain.astype(np.float32))[..., None]
    colour = np.asarray(MASK_BGR, dtype=np.float32) * light + weave
    return Layer(np.clip(colour, 0, 255).astype(np.float32), area)


class MaskBelowChin:
    """The mask under the chin (in the chin's shade) and its ear loops, on the frame."""

    def __init__(self) -> None:
        along = np.linspace(0.0, 1.0, len(JAW_LINE))
        self.drop_w = MASK_UNDER_CHIN_W * np.sin(np.pi * along) ** 0.6

    def __call__(
        self,
        frame: ImageBGR,
        renderer: FaceRenderer,
        yaw_deg: float,
        pitch_deg: float,
        mouth_open: float = 0.0,
    ) -> ImageBGR:
        import cv2

        top, bottom, along = under_jaw(renderer, self.drop_w, -0.3, yaw_deg, pitch_deg, mouth_open)
        opened = renderer.jaw.open(renderer.mesh.points_px, mouth_open)
        head = HeadFrame.of(renderer)
        out = frame.copy()
        if len(along) >= 2:
            polygon = np.round(np.vstack([top, bottom[::-1]]) * 16).astype(np.int32)
            shade = tuple(round(0.78 * c) for c in MASK_BGR)
            cv2.fillPoly(out, [polygon], shade, cv2.LINE_AA, 4)
        for upper, lower, side in ((234, 132, -1.0), (454, 361, 1.0)):
            if math.sin(math.radians(yaw_deg)) * side > -0.15:
                continue  # the camera does not see this side of the head
            ear = head.at(
                0.5 * (opened[upper] + opened[lower]), np.array([[0.04 * side, 0.0, -0.3]])
            )
            loop = turn(
                renderer, np.vstack([opened[upper], ear, opened[lower]]), yaw_deg, pitch_deg
            )
            line = np.round(loop[:, :2] * 16).astype(np.int32)
            cv2.polylines(out, [line], False, MASK_BGR, 1, cv2.LINE_AA, 4)
        return out


def _hair_colour(renderer: FaceRenderer) -> FloatArray:
    """The photo's hair just above the forehead, in the shade of a fringe (0.85 of it)."""
    points = renderer.mesh.points_px
    head = HeadFrame.of(renderer)
    top = points[10, :2] - head.down_2d() * 0.12 * head.width_px
    x, y = (round(v) for v in top)
    half = max(2, round(0.05 * head.width_px))
    patch = renderer.texture[max(0, y - half) : y + half, max(0, x - 3 * half) : x + 3 * half]
    return np.asarray(0.85 * np.median(patch.reshape(-1, 3), axis=0), dtype=np.float64)


def _along(rng: np.random.Generator, count: int, scale_px: float) -> FloatArray:
    """Smooth noise in 0..1 over `count` pixels, varying over about `scale_px`."""
    import cv2

    raw = rng.normal(0.0, 1.0, (1, count + 8)).astype(np.float32)
    smooth = cv2.GaussianBlur(raw, (0, 0), max(scale_px, 0.5))[0, 4:-4]
    spread = max(float(np.ptp(smooth)), 1e-6)
    return np.asarray((smooth - smooth.min()) / spread, dtype=np.float64)


def fringe(renderer: FaceRenderer, rng: np.random.Generator) -> Layer:
    """Hair hanging from the top of the forehead over the eyes (a texture layer): opaque down
    to the brows, then thinning in clumps, strands of lighter and darker hair over it."""
    import cv2

    points = renderer.mesh.points_px
    head = HeadFrame.of(renderer)
    width = head.width_px
    down = head.down_2d()
    side = np.array([-down[1], down[0]])
    hair = _hair_colour(renderer)
    shape = renderer.texture.shape[:2]
    eyes_low = max(float((points[list(eye.contour), :2] @ down).max()) for eye in EYES)
    hairline = points[list(HAIRLINE), :2]
    hairline = hairline[np.argsort(hairline @ side)]
    ys, xs = np.mgrid[0 : shape[0], 0 : shape[1]].astype(np.float64)
    across = xs * side[0] + ys * side[1]
    depth = xs * down[0] + ys * down[1]
    low, high = float((hairline @ side).min()), float((hairline @ side).max())
    count = int(high - low) + 1
    column = np.clip(across - low, 0, count - 1).astype(np.int32)
    tips = eyes_low + FRINGE_BELOW_EYES_W * width + 0.05 * width * (_along(rng, count, 1.5) - 0.5)
    top = np.interp(across, hairline @ side, hairline @ down) - 0.02 * width
    fraction = (depth - top) / np.maximum(tips[column] - top, 1.0)
    veil = np.interp(fraction, [-0.01, 0.0, 0.45, 0.85, 1.0], [0.0, 1.0, 1.0, 0.6, 0.0])
    clumps = _along(rng, count, 0.012 * width)[column]
    veil *= np.where(fraction > 0.45, 0.45 + 0.55 * clumps, 1.0)
    veil *= np.clip(np.minimum(across - low, high - across) / (0.02 * width), 0.0, 1.0)
    tone = 0.8 + 0.4 * _along(rng, count, 0.01 * width)[column]
    colour = (hair[None, None, :] * tone[..., None]).astype(np.float32)
    alpha = veil.astype(np.float32)
    for _ in range(round(FRINGE_STRANDS_PER_W * (high - low) / width)):
        x = rng.uniform(low, high)
        start_depth = float(np.interp(x, hairline @ side, hairline @ down))
        start = x * side + start_depth * down
        reach = float(tips[min(int(x - low), count - 1)]) - start_depth
        steps = np.linspace(0.0, 1.0, 6)
        sway = rng.normal(0.0, 0.03) * width * steps**1.5
        line = start + np.outer(steps * reach, down) + np.outer(sway, side)
        shade = float(rng.uniform(0.6, 1.4))
        bgr = tuple(float(min(255.0, c * shade)) for c in hair)
        polyline = np.round(line * 16).astype(np.int32)
        cv2.polylines(colour, [polyline], False, bgr, 1, cv2.LINE_AA, 4)
        cv2.polylines(alpha, [polyline], False, 0.9, 1, cv2.LINE_AA, 4)
    return Layer(colour, np.clip(alpha, 0.0, 1.0))


def lash_makeup(renderer: FaceRenderer, rng: np.random.Generator) -> Layer:
    """Eyeliner, mascara'd upper lashes and a lower lash line (painted under the eyes)."""
    import cv2

    points = renderer.mesh.points_px
    shape = renderer.texture.shape[:2]
    alpha = np.zeros(shape, dtype=np.float32)
    up = -HeadFrame.of(renderer).down_2d()
    for eye in EYES:
        contour = points[list(eye.contour), :2]
        eye_w = float(np.hypot(*(points[eye.outer, :2] - points[eye.inner, :2])))
        upper, lower = contour[:9], np.vstack([contour[8:], contour[:1]])
        outward = (points[eye.outer, :2] - points[eye.inner, :2]) / max(eye_w, 1e-9)
        wing = upper[0] + 0.25 * eye_w * outward + 0.1 * eye_w * up
        liner = np.vstack([wing, upper])
        thick = max(1, round(LINER_EYE_W * eye_w))
        cv2.polylines(
            alpha, [np.round(liner * 16).astype(np.int32)], False, 1.0, thick, cv2.LINE_AA, 4
        )
        cv2.polylines(alpha, [np.round(lower * 16).astype(np.int32)], False, 0.7, 1, cv2.LINE_AA, 4)
        for index in np.linspace(0.5, len(upper) - 2.5, 14):
            base = upper[int(index)] + (index % 1) * (upper[int(index) + 1] - upper[int(index)])
            lean = (index / (len(upper) - 1) - 0.5) * -1.2  # the outer lashes lean outward
            tip = base + LASH_EYE_W * eye_w * (up + lean * outward * 0.6 + rng.normal(0, 0.08, 2))
            line = np.round(np.vstack([base, tip]) * 16).astype(np.int32)
            cv2.polylines(alpha, [line], False, 1.0, 1, cv2.LINE_AA, 4)
    colour = np.empty((*shape, 3), dtype=np.float32)
    colour[:] = MAKEUP_BGR
    return Layer(colour, np.clip(alpha, 0.0, 1.0))
