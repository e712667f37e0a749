"""A phone held up in the driver's hand between the camera and the face: a hand drawn from a
21-point hand skeleton (MediaPipe's numbering: 0 the wrist, then four points per finger from
the thumb to the little finger) holding a phone.

The hand is the driver's outer one (the left in a left-hand-drive cabin: on the image's right
for a camera in front of the driver; mirrored in a right-hand-drive cabin), its fingers up
across the phone's back (dark, its rim lit by the screen), the thumb out toward the face. It
is drawn the way MediaPipe's hand landmark model reads it steadily: a drawing with the thumb
on the outer side (the back of the hand, as a camera would see a hand holding a phone toward
its driver) was found by the palm detector, but the model took its little finger for the thumb
and the tracked landmarks turned off the hand within a second. `PLACES` puts it where the
dossier's advanced phone rows hold it, in face widths W from the eyes with the head at the
road, drawn `SCALE` times its size next to the face (nearer the camera):

- `wheel` (9-11 o'clock): the hand lifted just off the rim (drawn behind it), the phone beside
  the chin; `windscreen`: higher, the phone beside the eyes, in view of the road; `cluster`:
  lower and nearer the middle, the phone over the wheel's centre in front of the instrument
  cluster.

The parts are painted far to near (the rim, the phone, the forearm in its sleeve, the back of
the hand, the fingers from the little one to the index, the thumb), each skin part shaded as a
rounded body (darker toward its edges, lit from above) with a darker outline, so the fingers
stand apart; knuckles and creases on each finger; all a little out of focus. The geometry, in
palm widths (the index base to the little finger's: 8 cm), is roadgaze's own drawing, not a
measured hand.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.synth.layers import Layer, out_of_focus
from roadgaze.synth.lean import FACE_CENTRE_HEIGHT
from roadgaze.synth.occluders import RIM_BGR, RIM_W, skin_bgr
from roadgaze.synth.renderer import FaceRenderer
from roadgaze.types import FloatArray

Plane = npt.NDArray[np.floating[Any]]
PALM_W = 8.0 / 14.0
"""A palm width (index base to little finger base, 8 cm) in face widths (14 cm)."""
SCALE = 1.5
"""The hand and phone are nearer the camera than the face: drawn this much larger."""
GRIP: tuple[tuple[float, float], ...] = (
    (0.0, 0.0),
    (-0.36, -0.22),
    (-0.66, -0.46),
    (-0.9, -0.68),
    (-1.08, -0.86),
    (-0.45, -1.02),
    (-0.52, -1.48),
    (-0.54, -1.74),
    (-0.53, -1.92),
    (-0.14, -1.08),
    (-0.16, -1.6),
    (-0.17, -1.88),
    (-0.16, -2.06),
    (0.17, -1.03),
    (0.2, -1.5),
    (0.21, -1.76),
    (0.2, -1.93),
    (0.46, -0.93),
    (0.52, -1.3),
    (0.54, -1.52),
    (0.54, -1.68),
)
"""The hand's 21 points in palm widths, the wrist at the origin, fingers up (y down), the thumb
out to the left (toward the face in a left-hand-drive cabin), the fingers a little curled
(shortened as the camera sees them)."""
FINGERS = ((1, 2, 3, 4), (5, 6, 7, 8), (9, 10, 11, 12), (13, 14, 15, 16), (17, 18, 19, 20))
FINGER_W = (0.26, 0.22, 0.23, 0.21, 0.18)
"""Each finger's width, thumb to little finger, in palm widths."""
FOREARM_W = 0.75
PHONE_W, PHONE_H = 0.92, 1.9
"""The phone (7.5 x 15 cm) in palm widths."""
PHONE_BGR = (40, 38, 42)
SCREEN_BGR = (235, 215, 190)
"""The screen's light on the phone's edge (cool white)."""
LENS_BGR = (15, 15, 15)
SLEEVE_BGR = (70, 55, 45)
BLUR_W = 0.012
RIM_BELOW_WRIST_W = 0.3
"""The wheel's rim runs this far (face widths) below the wrist: the hand is lifted off it."""


@dataclass(frozen=True, slots=True)
class HandPlace:
    """Where the wrist is (below the eye line and across, in W) and the hand's tilt (degrees,
    positive: the fingers lean toward the face)."""

    below_eyes_w: float
    across_w: float
    tilt_deg: float
    on_rim: bool = False
    """The wrist rests on the wheel's rim (drawn behind the hand, the wheel's centre straight
    below the eyes, the wrist at 10 o'clock: 2 in a right-hand-drive cabin)."""


PLACES: dict[str, HandPlace] = {
    "wheel": HandPlace(2.6, 1.35, 10.0, on_rim=True),
    "windscreen": HandPlace(1.9, 1.3, 10.0),
    "cluster": HandPlace(2.7, 1.05, 0.0),
}


def placed(place: HandPlace, eyes_px: FloatArray, face_w_px: float, mirror: float) -> FloatArray:
    """The 21 points in pixels: `GRIP` scaled, tilted and put at `place` from the eyes (x
    mirrored for a right-hand-drive cabin)."""
    unit = PALM_W * SCALE * face_w_px
    angle = np.radians(place.tilt_deg)
    turn = np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])
    points = np.asarray(GRIP) @ turn.T * unit
    wrist = eyes_px + np.array([place.across_w, place.below_eyes_w]) * face_w_px
    points = points + wrist
    points[:, 0] = eyes_px[0] + mirror * (points[:, 0] - eyes_px[0])
    return np.asarray(points, np.float64)


class _Canvas:
    """Parts painted over a frame-sized canvas, each over those painted before it."""

    def __init__(self, size: tuple[int, int], skin: Plane, light: Plane) -> None:
        columns, rows = size
        self.colour = np.zeros((rows, columns, 3), np.float32)
        self.alpha = np.zeros((rows, columns), np.float32)
        self.ys, self.xs = np.mgrid[0:rows, 0:columns].astype(np.float32)
        self.skin = skin
        self.light = light
        """Per row: brighter toward the top (light from above)."""

    def mask(self, polygon: FloatArray) -> Plane:
        import cv2

        mask = np.zeros(self.alpha.shape, np.uint8)
        cv2.fillPoly(mask, [np.round(polygon * 16).astype(np.int32)], 255, cv2.LINE_AA, 4)
        return mask.astype(np.float32) / 255.0

    def capsule(self, a: FloatArray, b: FloatArray, radius: float) -> Plane:
        """Each pixel's distance from the segment a-b over `radius` (<= 1 inside)."""
        ab = b - a
        t = ((self.xs - a[0]) * ab[0] + (self.ys - a[1]) * ab[1]) / max(float(ab @ ab), 1e-6)
        t = np.clip(t, 0.0, 1.0)
        dx, dy = self.xs - (a[0] + t * ab[0]), self.ys - (a[1] + t * ab[1])
        return np.asarray(np.sqrt(dx * dx + dy * dy) / radius)

    def paint(self, cover: Plane, bgr: Plane | tuple[int, int, int]) -> None:
        share = np.clip(cover, 0.0, 1.0).astype(np.float32)[..., None]
        colour = np.asarray(bgr, np.float32)
        self.colour[:] = self.colour * (1.0 - share) + colour * share
        self.alpha[:] = np.maximum(self.alpha, share[..., 0])

    def skin_part(self, distance: Plane, tone: float = 1.0) -> None:
        """A rounded skin part from its distance field (<= 1 inside): darker toward its edge,
        with a dark outline just inside it."""
        inside = np.clip((1.0 - distance) * 6.0 + 0.5, 0.0, 1.0)
        shade = 1.0 - 0.35 * np.clip(distance, 0.0, 1.0) ** 2
        outline = np.clip(1.0 - np.abs(distance - 0.93) * 12.0, 0.0, 1.0)
        colour = tone * self.skin * (shade * self.light * (1.0 - 0.45 * outline))[..., None]
        self.paint(inside, colour)


def _unit(vector: FloatArray) -> FloatArray:
    return np.asarray(vector / (float(np.linalg.norm(vector)) + 1e-6))


def _rim(canvas: _Canvas, wrist: FloatArray, eyes: FloatArray, face_w_px: float) -> None:
    """The wheel's rim (dark leather, `RIM_W` thick) through the wrist at 10 (or 2) o'clock, the
    wheel's centre below the eyes."""
    radius = abs(float(wrist[0] - eyes[0])) / np.sin(np.radians(60.0))
    centre = np.array([eyes[0], wrist[1] + 0.5 * radius + RIM_BELOW_WRIST_W * face_w_px])
    off_rim = np.abs(np.hypot(canvas.xs - centre[0], canvas.ys - centre[1]) - radius)
    canvas.paint(np.clip((0.5 * RIM_W * face_w_px - off_rim) + 0.5, 0.0, 1.0), RIM_BGR)


def _phone(canvas: _Canvas, points: FloatArray, unit: float) -> None:
    """The phone's back, its rim lit by the screen, held in the fingers: its middle a third of
    the way up the middle finger, its top above the finger tips."""
    up = _unit(points[12] - points[9])
    side = np.array([-up[1], up[0]])
    half_w, half_h = 0.5 * PHONE_W * unit, 0.5 * PHONE_H * unit
    centre = points[9] + (points[12] - points[9]) * 0.35 + up * 0.45 * half_h
    signs = ((-1, -1), (1, -1), (1, 1), (-1, 1))
    for grow, bgr in ((0.06 * unit, SCREEN_BGR), (0.0, PHONE_BGR)):
        corners = [centre + a * (half_w + grow) * side + b * (half_h + grow) * up for a, b in signs]
        canvas.paint(canvas.mask(np.array(corners)), bgr)
    lens = centre + up * 0.75 * half_h - side * 0.55 * half_w
    canvas.paint(np.clip(1.2 - canvas.capsule(lens, lens, 0.09 * unit), 0.0, 1.0), LENS_BGR)


def _forearm(canvas: _Canvas, points: FloatArray, unit: float) -> None:
    """The forearm from the wrist out of the picture, in a sleeve from a little above the
    wrist."""
    down = _unit(points[0] - points[9])
    elbow = points[0] + down * 4.0 * unit
    canvas.skin_part(canvas.capsule(points[0], elbow, 0.5 * FOREARM_W * unit), 0.92)
    cuff = points[0] + down * 0.45 * unit
    sleeve = canvas.capsule(cuff, elbow, 0.62 * FOREARM_W * unit)
    canvas.paint(np.clip((1.0 - sleeve) * 6.0, 0.0, 1.0), SLEEVE_BGR)


def _back_of_hand(canvas: _Canvas, points: FloatArray, unit: float) -> None:
    """The back of the hand from the wrist to the finger bases and the thumb's base, rounded
    (its distance from its own edge)."""
    import cv2

    side = _unit(points[5] - points[17])
    palm = np.array(
        [
            points[0] - side * 0.38 * unit,
            points[1] - side * 0.12 * unit,
            points[2] - side * 0.05 * unit,
            points[5] + side * 0.1 * unit,
            points[9],
            points[13],
            points[17] - side * 0.1 * unit,
            points[0] + side * 0.36 * unit,
        ]
    )
    inside = canvas.mask(palm) > 0.5
    depth = cv2.distanceTransform(inside.astype(np.uint8), cv2.DIST_L2, 5)
    distance = 0.9 * (1.0 - np.clip(depth / (0.35 * unit), 0.0, 1.0))
    canvas.skin_part(np.where(inside, distance, 2.0))


def _fingers(canvas: _Canvas, points: FloatArray, unit: float) -> None:
    """The fingers from the little one to the index, then the thumb: three tapering segments
    each, the knuckle at the base lighter, a crease at the two joints above it."""
    for finger in (4, 3, 2, 1, 0):
        joints = FINGERS[finger]
        radius = 0.5 * FINGER_W[finger] * unit
        chain = [points[j] for j in joints]
        if finger > 0:  # the finger's bone runs on into the back of the hand
            chain[0] = chain[0] + (points[0] - chain[0]) * 0.08
        field = np.min(
            [canvas.capsule(chain[i], chain[i + 1], radius * (1.0 - 0.08 * i)) for i in range(3)],
            axis=0,
        )
        canvas.skin_part(field)
        for joint in joints[1:3]:
            crease = canvas.capsule(points[joint], points[joint], 0.55 * radius)
            ring = np.clip(1.0 - np.abs(crease - 1.0) * 5.0, 0.0, 1.0) * (field < 0.8)
            canvas.colour[:] *= (1.0 - 0.18 * ring)[..., None]
        base = points[joints[0]]
        knuckle = np.clip(1.0 - canvas.capsule(base, base, radius), 0.0, 1.0)
        canvas.colour[:] *= (1.0 + 0.12 * knuckle * (canvas.alpha > 0.5))[..., None]


def phone_hand_layer(
    renderer: FaceRenderer,
    place: str,
    cabin: str = "lhd",
    rest_deg: tuple[float, float] = (0.0, 0.0),
    zoom: float = 1.0,
) -> Layer:
    """The hand holding a phone up at `place` (`PLACES`) in `cabin`, over the renderer's whole
    frame, placed from where the eyes are with the head at `rest_deg` (the road pose as the
    camera sees it, rendered), through a lens `zoom` times as narrow
    (`roadgaze.synth.lean`). Build it once and composite it on every frame."""
    columns, rows = renderer.size
    centre_px = np.array([0.5 * columns, FACE_CENTRE_HEIGHT * rows])
    width = zoom * renderer.mesh.face_width_px
    eyes = renderer.turned_points(*rest_deg)[[33, 263], :2].mean(axis=0)
    eyes = centre_px + zoom * (eyes - centre_px)
    points = placed(PLACES[place], eyes, width, -1.0 if cabin == "rhd" else 1.0)
    unit = PALM_W * SCALE * width
    top = float(points[:, 1].min())
    ys = np.arange(rows, dtype=np.float32)[:, None] * np.ones((1, columns), np.float32)
    light = np.clip(1.12 - 0.25 * (ys - top) / (2.5 * unit), 0.8, 1.12).astype(np.float32)
    canvas = _Canvas(renderer.size, skin_bgr(renderer).astype(np.float32), light)
    if PLACES[place].on_rim:
        _rim(canvas, points[0], eyes, width)
    _phone(canvas, points, unit)
    _forearm(canvas, points, unit)
    _back_of_hand(canvas, points, unit)
    _fingers(canvas, points, unit)
    return out_of_focus(canvas.colour, canvas.alpha, max(0.5, BLUR_W * width))
