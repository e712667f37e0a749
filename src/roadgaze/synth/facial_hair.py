"""Facial hair painted on the face: stubble and a full beard (`roadgaze.synth.layers`).

Both cover the beard area of the mesh: from the sideburns in front of the ears (234, 454) down
the jaw line round the chin, and up the cheeks along the beard line to under the nose (the
moustache), the lips left bare. Geometry in face widths W (about 14 cm):

- **Stubble** (short facial hair, a few days' growth): no single hair is resolved at a cabin
  camera's scale (a face 100-200 px wide); what shows is a darker, grainy area. Each pixel is
  covered by `STUBBLE_ALPHA` of the hair colour plus up to `STUBBLE_GRAIN` more by a grain of
  1 px dots, its edge softened over 0.015 W.
- **A full beard** (long facial hair): the same area covered by hair (`BEARD_ALPHA`) drawn as
  short strokes along the head's down direction, and a part hanging `BEARD_DROP_W` below the
  chin (4 cm), tapering to nothing at the jaw's corners, drawn on the frame under the turned jaw
  (`BeardBelowChin`), with the same strokes, so it follows the head and an opening jaw.

The hair is dark brown (`HAIR_BGR`), the common case and the one with the most contrast on
light skin.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from roadgaze.synth.head import HeadFrame, turn
from roadgaze.synth.layers import Layer, region_alpha
from roadgaze.synth.mouth import LOWER_OUTER, UPPER_OUTER
from roadgaze.synth.renderer import FaceRenderer, ImageBGR
from roadgaze.types import FloatArray

BEARD_AREA = (
    *(234, 93, 132, 58, 172, 136, 150, 149, 176, 148, 152),
    *(377, 400, 378, 379, 365, 397, 288, 361, 323, 454),
    *(376, 411, 427, 426, 423, 327, 326, 2, 97, 98, 203, 206, 207, 187, 147),
)
"""The beard area's outline: the jaw line from ear to ear, then the beard line back across the
cheeks and under the nose."""
JAW_LINE = (132, 58, 172, 136, 150, 149, 176, 148, 152, 377, 400, 378, 379, 365, 397, 288, 361)
"""The lower face oval from one jaw corner round the chin to the other."""
LIPS = (*UPPER_OUTER, *LOWER_OUTER[::-1])
HAIR_BGR = (34, 38, 48)
STUBBLE_ALPHA, STUBBLE_GRAIN = 0.3, 0.25
BEARD_ALPHA = 0.92
BEARD_DROP_W = 0.28
SHADE_STEPS = (0.8, 1.05, 1.3)
"""The hanging beard's strokes are drawn in four tones (darker and lighter than `HAIR_BGR`)."""
STROKE_W = (0.03, 0.08)
"""A beard stroke's length, in face widths."""


def _lips(points: FloatArray) -> FloatArray:
    return np.asarray(points[list(LIPS), :2], dtype=np.float64)


def stubble(renderer: FaceRenderer, rng: np.random.Generator) -> Layer:
    """Stubble over the beard area: a dark, grainy cover (a texture layer)."""
    import cv2

    points = renderer.mesh.points_px
    width = renderer.mesh.face_width_px
    shape = renderer.texture.shape[:2]
    area = region_alpha(shape, points[list(BEARD_AREA), :2], 0.015 * width, [_lips(points)])
    grain = (rng.random(shape) < 0.5).astype(np.float32)
    grain = np.asarray(cv2.GaussianBlur(grain, (0, 0), 0.7), dtype=np.float32)
    alpha = area * (STUBBLE_ALPHA + STUBBLE_GRAIN * grain)
    colour = np.empty((*shape, 3), dtype=np.float32)
    colour[:] = HAIR_BGR
    return Layer(colour, alpha.astype(np.float32))


def _strokes(
    canvas: npt.NDArray[np.float32],
    starts: FloatArray,
    direction: FloatArray,
    width_px: float,
    rng: np.random.Generator,
) -> None:
    """Draw hair strokes from `starts` ((N, 2) px) along `direction` on `canvas` (in place),
    each a little darker or lighter than the hair colour, slightly curved."""
    import cv2

    for start in starts:
        length = rng.uniform(*STROKE_W) * width_px
        bend = rng.normal(0.0, 0.25)
        side = np.array([-direction[1], direction[0]])
        middle = start + 0.5 * length * direction + 0.25 * bend * length * side
        end = start + length * direction + bend * length * side
        shade = float(rng.uniform(0.55, 1.6))
        bgr = tuple(float(min(255.0, c * shade)) for c in HAIR_BGR)
        line = np.round(np.vstack([start, middle, end]) * 16).astype(np.int32)
        cv2.polylines(canvas, [line], False, bgr, 1, cv2.LINE_AA, 4)


def beard(renderer: FaceRenderer, rng: np.random.Generator) -> Layer:
    """A full beard over the beard area, drawn as hair strokes (a texture layer)."""
    points = renderer.mesh.points_px
    width = renderer.mesh.face_width_px
    shape = renderer.texture.shape[:2]
    area = region_alpha(shape, points[list(BEARD_AREA), :2], 0.01 * width, [_lips(points)])
    colour = np.empty((*shape, 3), dtype=np.float32)
    colour[:] = HAIR_BGR
    ys, xs = np.nonzero(area > 0.05)
    count = int(len(xs) * 0.35)
    chosen = rng.choice(len(xs), size=count, replace=count > len(xs))
    starts = np.column_stack([xs[chosen], ys[chosen]]).astype(np.float64)
    _strokes(colour, starts, HeadFrame.of(renderer).down_2d(), width, rng)
    ragged = 1.0 - 0.3 * rng.random(shape).astype(np.float32) * (area < 0.9)
    return Layer(colour, (BEARD_ALPHA * area * ragged).astype(np.float32))


def under_jaw(
    renderer: FaceRenderer,
    drop_w: FloatArray,
    ahead: float,
    yaw_deg: float,
    pitch_deg: float,
    mouth_open: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """What hangs under the jaw, as the frame shows it: (N, 2) pixels of the turned (and
    opened) jaw line, of the line `drop_w` (per jaw point, in face widths) below it along the
    head, moved forward by `ahead` times the drop, and each jaw point's place along the line
    (0..1). Only the jaw points on the camera's side of the neck pivot are kept: the far side
    of the jaw hides behind the face when the head turns."""
    head = HeadFrame.of(renderer)
    jaw = renderer.jaw.open(renderer.mesh.points_px, mouth_open)[list(JAW_LINE)]
    offsets = np.column_stack([np.zeros_like(drop_w), -drop_w, ahead * drop_w])
    hanging = np.vstack(
        [head.at(point, row[None, :]) for point, row in zip(jaw, offsets, strict=True)]
    )
    top = turn(renderer, jaw, yaw_deg, pitch_deg)
    seen = top[:, 2] < renderer.mesh.pivot_px[2]
    along = np.linspace(0.0, 1.0, len(JAW_LINE))
    bottom = turn(renderer, hanging, yaw_deg, pitch_deg)[:, :2]
    return top[seen, :2], bottom[seen], along[seen]


class BeardBelowChin:
    """The part of a full beard hanging below the chin, drawn on the frame under the turned
    (and opened) jaw: `BEARD_DROP_W` deep at the chin, nothing at the jaw's corners."""

    def __init__(self, rng: np.random.Generator, count: int = 260) -> None:
        along = np.linspace(0.0, 1.0, len(JAW_LINE))
        self.drop_w = BEARD_DROP_W * np.sin(np.pi * along) ** 0.8
        # Strokes in the hanging part's own (along the jaw, down) coordinates, 0..1 each.
        self.strokes = rng.random((count, 2))
        self.lengths = rng.uniform(0.15, 0.45, count)
        self.shades = rng.uniform(0.55, 1.6, count)

    def __call__(
        self,
        frame: ImageBGR,
        renderer: FaceRenderer,
        yaw_deg: float,
        pitch_deg: float,
        mouth_open: float = 0.0,
    ) -> ImageBGR:
        import cv2

        top, bottom, along = under_jaw(renderer, self.drop_w, 0.2, yaw_deg, pitch_deg, mouth_open)
        if len(along) < 2:
            return frame
        out = frame.copy()
        polygon = np.round(np.vstack([top, bottom[::-1]]) * 16).astype(np.int32)
        cv2.fillPoly(out, [polygon], HAIR_BGR, cv2.LINE_AA, 4)

        def place(u: FloatArray, v: FloatArray) -> FloatArray:
            upper = np.column_stack([np.interp(u, along, top[:, i]) for i in (0, 1)])
            lower = np.column_stack([np.interp(u, along, bottom[:, i]) for i in (0, 1)])
            return np.asarray(upper + v[:, None] * (lower - upper), dtype=np.float64)

        shown = (self.strokes[:, 0] >= along[0]) & (self.strokes[:, 0] <= along[-1])
        u, v = self.strokes[shown, 0], self.strokes[shown, 1] * 0.85
        starts, ends = place(u, v), place(u, np.minimum(1.0, v + self.lengths[shown]))
        lines = np.round(np.stack([starts, ends], axis=1) * 16).astype(np.int32)
        tones = np.digitize(self.shades[shown], SHADE_STEPS)  # one drawing call per tone
        for tone in np.unique(tones):
            shade = float(np.r_[0.55, SHADE_STEPS][tone] + 0.25)
            bgr = tuple(min(255.0, c * shade) for c in HAIR_BGR)
            cv2.polylines(out, list(lines[tones == tone]), False, bgr, 1, cv2.LINE_AA, 4)
        return out
