"""Things worn in front of the face: glasses, a cap, a hat, placed along the head's axes and turned
with it, drawn on the rendered frame.

Each is a small 3-D model in face widths W (`roadgaze.synth.head`; W is about 14 cm), turned as
the mesh is and projected the same way, so it follows every yaw and nod, foreshortened:

- **Glasses** (`glasses`): a lens `LENS_HALF_W` wide each side of the eye's centre and
  `LENS_HALF_H` high (a 48 x 36 mm lens), a rounded rectangle `LENS_AHEAD_W` in front of the eye
  (the 12-15 mm vertex distance), a thin frame, a bridge and the temple on the side the head turns
  toward. `CLEAR` lenses pass 75 % of the light with a faint brown tint and a faint reflection
  (category 1 light sunglasses: 43-80 % transmission; the eyes stay visible), `DARK` lenses 6 %
  (category 3-4: the eyes are hidden).
- **A cap** (`cap`): a crown over the head from a band `BAND_ABOVE_EYES_W` above the eye line
  (the cap worn low, 2-3 cm above the brows) and a brim `CAP_BRIM_W` long in front (7 cm), drooping
  `BRIM_DROOP_DEG`. Looking ahead the brim is edge-on above the brows; as the head nods down it
  comes down in front of the eyes; a camera below the face (the steering column) sees under it.
  The brim's shade on the upper face is painted on the skin (`brim_shade`).
- **A hat** (`hat`): a taller crown and a brim `HAT_BRIM_W` wide all around (6 cm).

Every function takes the rendered frame and the turned mesh of that frame and returns a new frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.landmarks.eye_landmarks import EYES
from roadgaze.synth.head import HeadFrame, turn
from roadgaze.synth.layers import Layer, region_alpha
from roadgaze.synth.renderer import FaceRenderer, ImageBGR
from roadgaze.types import FloatArray

LENS_HALF_W, LENS_HALF_H = 0.17, 0.13
LENS_AHEAD_W = 0.09
TEMPLE_W = 0.7
"""A temple runs this far back from the lens to the ear."""


@dataclass(frozen=True, slots=True)
class Lenses:
    """How a pair of glasses looks: the light its lenses pass, their tint (BGR gains), the frame."""

    transmission: float
    tint: tuple[float, float, float]
    frame_w: float
    """The frame's thickness in face widths."""
    frame_bgr: tuple[int, int, int]
    reflection: float
    """Grey levels a soft reflection adds across the lens."""


CLEAR = Lenses(0.75, (0.88, 0.95, 1.0), 0.012, (35, 32, 30), 18.0)
DARK = Lenses(0.06, (1.0, 1.0, 1.0), 0.02, (22, 20, 18), 8.0)
BAND_ABOVE_EYES_W = 0.3
CROWN_DEPTH_W, CROWN_ACROSS_W = 0.68, 0.57
"""Half the head's length and breadth at the band, with the cloth (head 19.5 x 15.5 cm)."""
CAP_CROWN_W, HAT_CROWN_W = 0.5, 0.62
CAP_BRIM_W, HAT_BRIM_W = 0.5, 0.43
BRIM_DROOP_DEG = 12.0
CAP_BGR, HAT_BGR = (75, 45, 30), (70, 105, 135)
"""A navy cap, a tan felt hat."""
SHADE_DEPTH_W = 0.36
"""The brim's shade on the face reaches this far below the band (over the eyes)."""
SHADE_GAIN = 0.62
FOREHEAD = 151
"""The mid-forehead landmark (the band is placed on the mid line through it)."""


def _eye_centre(points: FloatArray, contour: tuple[int, ...]) -> FloatArray:
    return np.asarray(points[list(contour)].mean(axis=0), dtype=np.float64)


def _lens_outline(head: HeadFrame, centre: FloatArray, count: int = 36) -> FloatArray:
    """(count, 3) a rounded rectangle (a superellipse of power 4) in front of an eye."""
    angle = np.linspace(0.0, 2.0 * math.pi, count, endpoint=False)
    cos_a, sin_a = np.cos(angle), np.sin(angle)
    across = LENS_HALF_W * np.sign(cos_a) * np.abs(cos_a) ** 0.5
    up = LENS_HALF_H * np.sign(sin_a) * np.abs(sin_a) ** 0.5
    offsets = np.column_stack([across, up + 0.01, np.full(count, LENS_AHEAD_W)])
    return head.at(centre, offsets)


def glasses(
    frame: ImageBGR,
    renderer: FaceRenderer,
    yaw_deg: float,
    pitch_deg: float,
    lenses: Lenses = CLEAR,
) -> ImageBGR:
    """`frame` (the face at `yaw_deg`, `pitch_deg`) with glasses on: each lens lets
    `lenses.transmission` of the light through, tinted, with a soft reflection; the frame, the
    bridge and the temple on the side the camera sees drawn over. Glasses turned away from the
    camera (beyond about 78 deg) are not drawn."""
    import cv2

    head = HeadFrame.of(renderer)
    facing = turn(renderer, np.vstack([np.zeros(3), head.forward]), yaw_deg, pitch_deg)
    if facing[1, 2] - facing[0, 2] > -0.2:
        return frame
    out = frame.copy()
    outlines = [
        _lens_outline(head, _eye_centre(renderer.mesh.points_px, eye.contour)) for eye in EYES
    ]
    lines = [turn(renderer, outline, yaw_deg, pitch_deg)[:, :2] for outline in outlines]
    for shown in lines:
        _see_through(out, shown, lenses)
    lines.append(turn(renderer, np.vstack(_bridge(head, outlines)), yaw_deg, pitch_deg)[:, :2])
    thickness = max(1, round(lenses.frame_w * head.width_px))
    for index, line in enumerate(lines):
        polyline = np.round(line * 16).astype(np.int32)
        cv2.polylines(out, [polyline], index < 2, lenses.frame_bgr, thickness, cv2.LINE_AA, 4)
    for temple in _temples(head, outlines, renderer, yaw_deg, pitch_deg):
        polyline = np.round(temple * 16).astype(np.int32)
        cv2.polylines(out, [polyline], False, lenses.frame_bgr, thickness + 1, cv2.LINE_AA, 4)
    return out


def _see_through(frame: ImageBGR, lens_px: FloatArray, lenses: Lenses) -> None:
    """Dim and tint `frame` (in place) inside the lens outline, with a diagonal reflection."""
    height, width = frame.shape[:2]
    x0, y0 = np.maximum(np.floor(lens_px.min(axis=0)).astype(int) - 1, 0)
    x1 = min(width, int(np.ceil(lens_px[:, 0].max())) + 2)
    y1 = min(height, int(np.ceil(lens_px[:, 1].max())) + 2)
    if x1 <= x0 or y1 <= y0:
        return
    alpha = region_alpha((y1 - y0, x1 - x0), lens_px - (x0, y0), 0.0)[..., None]
    ys, xs = np.mgrid[0 : y1 - y0, 0 : x1 - x0]
    along = (xs + ys) / max(float((x1 - x0) + (y1 - y0)), 1.0)
    streak = lenses.reflection * np.exp(-(((along - 0.4) / 0.1) ** 2))[..., None]
    patch = frame[y0:y1, x0:x1].astype(np.float32)
    seen = patch * lenses.transmission * np.asarray(lenses.tint, np.float32) + streak
    mixed = patch * (1.0 - alpha) + seen * alpha
    frame[y0:y1, x0:x1] = np.clip(mixed + 0.5, 0, 255).astype(np.uint8)


def _bridge(head: HeadFrame, outlines: list[FloatArray]) -> list[FloatArray]:
    """The bridge: from the inner top of one lens over the nose to the other's."""
    ends = []
    for outline, side in zip(outlines, (1.0, -1.0), strict=True):
        across = (outline - outline.mean(axis=0)) @ head.right * side
        upper = (outline - outline.mean(axis=0)) @ head.up
        ends.append(outline[int(np.argmax(across + 0.5 * upper))])
    middle = 0.5 * (ends[0] + ends[1]) + head.up * 0.02 * head.width_px
    return [ends[0], middle, ends[1]]


def _temples(
    head: HeadFrame,
    outlines: list[FloatArray],
    renderer: FaceRenderer,
    yaw_deg: float,
    pitch_deg: float,
) -> list[FloatArray]:
    """The temple of each lens whose side of the head the camera sees."""
    temples = []
    for outline, side in zip(outlines, (-1.0, 1.0), strict=True):
        offset = outline - outline.mean(axis=0)
        start = outline[int(np.argmax(side * (offset @ head.right) + 0.3 * (offset @ head.up)))]
        if math.sin(math.radians(yaw_deg)) * side > -0.15:
            continue  # the camera does not see this side of the head
        path = np.array(
            [[0.0, 0.0, 0.0], [0.03 * side, -0.01, -0.3], [0.04 * side, -0.03, -TEMPLE_W]]
        )
        temples.append(turn(renderer, head.at(start, path), yaw_deg, pitch_deg)[:, :2])
    return temples


def _band_anchor(renderer: FaceRenderer, head: HeadFrame) -> FloatArray:
    """The front of the band on the forehead's mid line, `BAND_ABOVE_EYES_W` above the eyes."""
    points = renderer.mesh.points_px
    eyes = 0.5 * (_eye_centre(points, EYES[0].contour) + _eye_centre(points, EYES[1].contour))
    forehead = points[FOREHEAD]
    rise = BAND_ABOVE_EYES_W * head.width_px - float((forehead - eyes) @ head.up)
    return np.asarray(forehead + rise * head.up, dtype=np.float64)


def _ring(phi: FloatArray, reach_w: FloatArray, forward_only: bool) -> FloatArray:
    """(N, 3) offsets (across, up, forward; in W) from the crown's centre at the band: the
    band's ellipse at the angles `phi` (0 straight ahead), `reach_w` further out (straight
    ahead for a cap's brim, outward all round for a hat's), drooping `BRIM_DROOP_DEG` over it."""
    droop = math.radians(BRIM_DROOP_DEG)
    out = reach_w * math.cos(droop)
    across = CROWN_ACROSS_W * np.sin(phi) + (0.0 if forward_only else out * np.sin(phi))
    forward = CROWN_DEPTH_W * np.cos(phi) + (out if forward_only else out * np.cos(phi))
    return np.column_stack([across, -reach_w * math.sin(droop), forward])


def _crown(height_w: float) -> FloatArray:
    """(N, 3) offsets of the crown's surface: half an ellipsoid over the band."""
    rise, around = np.meshgrid(np.linspace(0.0, math.pi / 2, 7), np.linspace(0, 2 * math.pi, 25))
    return np.column_stack(
        [
            CROWN_ACROSS_W * (np.cos(rise) * np.sin(around)).ravel(),
            height_w * np.sin(rise).ravel(),
            CROWN_DEPTH_W * (np.cos(rise) * np.cos(around)).ravel(),
        ]
    )


@dataclass(frozen=True, slots=True)
class Headwear:
    """A crown `crown_w` high; a brim reaching `brim_w` straight ahead between the angles
    `brim_deg` around the band (a cap: a semi-ellipse in front), or outward all round (a hat)."""

    crown_w: float
    brim_w: float
    brim_deg: float
    """The brim spans +-this around the band (180: all round)."""
    bgr: tuple[int, int, int]


CAP = Headwear(CAP_CROWN_W, CAP_BRIM_W, 80.0, CAP_BGR)
HAT = Headwear(HAT_CROWN_W, HAT_BRIM_W, 180.0, HAT_BGR)


def headwear(
    frame: ImageBGR, renderer: FaceRenderer, yaw_deg: float, pitch_deg: float, wear: Headwear
) -> ImageBGR:
    """`frame` with a cap or a hat on: a hat's brim behind the head first (hidden where the
    face is), then the crown (lit from above), then the brim in front, its top lit, its
    underside in shade."""
    import cv2

    head = HeadFrame.of(renderer)
    centre = _band_anchor(renderer, head) - CROWN_DEPTH_W * head.width_px * head.forward

    def shown(offsets_w: FloatArray) -> npt.NDArray[np.int32]:
        points = turn(renderer, head.at(centre, offsets_w), yaw_deg, pitch_deg)
        return np.round(points[:, :2] * 16).astype(np.int32)

    def brim(low_deg: float, high_deg: float) -> npt.NDArray[np.int32]:
        phi = np.radians(np.linspace(low_deg, high_deg, 33))
        if wear.brim_deg >= 180.0:
            return np.vstack(
                [
                    shown(_ring(phi, 0.0 * phi, False)),
                    shown(_ring(phi, wear.brim_w + 0.0 * phi, False))[::-1],
                ]
            )
        reach = wear.brim_w * np.sqrt(
            np.clip(1.0 - (phi / math.radians(wear.brim_deg)) ** 2, 0.0, 1.0)
        )
        return np.vstack([shown(_ring(phi, 0.0 * phi, True)), shown(_ring(phi, reach, True))[::-1]])

    droop = math.radians(BRIM_DROOP_DEG)
    normal = math.cos(droop) * head.up + math.sin(droop) * head.forward
    ends = turn(renderer, np.vstack([np.zeros(3), normal]), yaw_deg, pitch_deg)
    top_seen = ends[1, 2] - ends[0, 2] < 0  # the camera looks at the brim from above
    brim_bgr = tuple(min(255, round(c * (1.15 if top_seen else 0.55))) for c in wear.bgr)
    edge_bgr = tuple(round(c * 0.6) for c in wear.bgr)
    out = frame.copy()
    if wear.brim_deg >= 180.0:
        behind = out.copy()
        cv2.fillPoly(behind, [brim(90.0, 270.0)], brim_bgr, cv2.LINE_AA, 4)
        face = np.zeros(out.shape[:2], dtype=np.uint8)
        mesh = np.round(renderer.turned_points(yaw_deg, pitch_deg)[:, :2]).astype(np.int32)
        cv2.fillConvexPoly(face, cv2.convexHull(mesh), 255)
        out = np.where(face[..., None] > 0, out, behind)
    crown = np.zeros(out.shape[:2], dtype=np.uint8)
    cv2.fillConvexPoly(crown, cv2.convexHull(shown(_crown(wear.crown_w))), 255, cv2.LINE_AA, 4)
    rows = np.flatnonzero(crown.any(axis=1))
    if rows.size:  # lit from above: 1.1 of its colour at the top to 0.75 at the band
        top, bottom = int(rows[0]), int(rows[-1]) + 1
        light = np.linspace(1.1, 0.75, bottom - top)
        lit = np.asarray(wear.bgr, np.float32)[None, None, :] * light[:, None, None]
        alpha = (crown[top:bottom].astype(np.float32) / 255.0)[..., None]
        band = out[top:bottom].astype(np.float32)
        out[top:bottom] = np.clip(band * (1.0 - alpha) + lit * alpha + 0.5, 0, 255)
    front = brim(-min(wear.brim_deg, 90.0), min(wear.brim_deg, 90.0))
    cv2.fillPoly(out, [front], brim_bgr, cv2.LINE_AA, 4)
    cv2.polylines(out, [front], True, edge_bgr, 1, cv2.LINE_AA, 4)
    return out


def brim_shade(renderer: FaceRenderer) -> Layer:
    """The brim's shade on the skin (a texture layer): `SHADE_GAIN` of the light from the band
    down to `SHADE_DEPTH_W` below it, fading over its last 0.08 W (the sun above the car)."""
    head = HeadFrame.of(renderer)
    anchor = _band_anchor(renderer, head)
    height, width = (
        renderer.base_texture.shape[:2]
        if hasattr(renderer, "base_texture")
        else renderer.texture.shape[:2]
    )
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
    up = -head.down_2d()
    below_w = -((xs - anchor[0]) * up[0] + (ys - anchor[1]) * up[1]) / head.width_px
    alpha = np.clip((SHADE_DEPTH_W - below_w) / 0.08, 0.0, 1.0).astype(np.float32)
    colour = renderer.texture.astype(np.float32) * SHADE_GAIN
    return Layer(colour, alpha)
