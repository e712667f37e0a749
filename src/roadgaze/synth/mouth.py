"""A mouth that opens: the jaw turned about its hinge, the inside of the mouth drawn, speech.

**The jaw.** `Jaw.open(points, fraction)` deforms the (unturned) mesh as a jaw opens: the lower
lip, the chin and the jaw below the mouth turn about a lateral axis through the jaw's hinge (the
temporomandibular joint, in front of the ear: halfway between the eye line and the nose tip in
height, `HINGE_BEHIND_W` behind the nose tip), so the chin drops and moves back as a real jaw
does; beyond `MAX_TURN_DEG` the hinge also slides down (a wide opening is a turn and a glide of
the joint). Each vertex turns with a weight: the lower lips 1, the upper lips 0, the mouth corners
`CORNER_WEIGHT`, other vertices by their height below the line through the mouth corners (0 on
it, 1 from `RAMP_W` below), so the cheeks stretch between the two. The turn is solved so the
inner lips part by `fraction * FULL_GAP_W` face widths: 1 is a wide yawn (lips 5-6 cm apart on a
14 cm wide face), speech is 0.05-0.3. The renderer maps the photo onto the deformed mesh, so the
lips and the skin stretch with it.

**The inside.** The mesh closes the mouth with a strip of triangles between the inner lips; once
the jaw opens those pixels show the inside of the mouth (`paint_inside`): a dark cavity, the
upper teeth under the upper lip (they belong to the skull, so they stay with it), a little of
the lower teeth above the lower lip and the tongue at the bottom. Only the strip's pixels are
painted, so what the turned face hides stays hidden.

**Speech** (`speech_track`): syllables at 3-5 per second (conversational speech), each one an
opening and closing of irregular size, in phrases of 3-10 syllables with pauses between them,
seeded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.landmarks.features import MOUTH_CORNERS, NOSE_TIP
from roadgaze.types import FloatArray

UPPER_INNER = (78, 191, 80, 81, 82, 13, 312, 311, 310, 415, 308)
LOWER_INNER = (78, 95, 88, 178, 87, 14, 317, 402, 318, 324, 308)
UPPER_OUTER = (61, 185, 40, 39, 37, 0, 267, 269, 270, 409, 291)
LOWER_OUTER = (61, 146, 91, 181, 84, 17, 314, 405, 321, 375, 291)
"""MediaPipe's lip contours (FACE_LANDMARKS_LIPS), from the person's right corner to the left."""
EYE_LINE = (33, 263)
FULL_GAP_W = 0.38
"""The inner lips' gap at `fraction` 1, in face widths: a wide yawn (5-6 cm on a 14 cm face)."""
HINGE_BEHIND_W = 0.75
"""The jaw's hinge behind the nose tip, in face widths (the condyle, in front of the ear)."""
RAMP_W = 0.1
"""Below the mouth corners' line the jaw's share grows from 0 to 1 over this many face widths."""
MAX_TURN_DEG = 30.0
"""The jaw turns this far at most; the rest of a wide opening is the hinge sliding down."""
CORNER_WEIGHT = 0.35
"""The mouth corners move a third as far as the lower lip (they stretch, they do not drop)."""
SPEECH_HZ = (3.0, 5.0)
"""Syllables per second in conversational speech."""
SPEECH_OPENING = (0.06, 0.3)
"""A syllable's opening, as a fraction of `FULL_GAP_W` (lips 0.3-1.6 cm apart)."""
PHRASE_SYLLABLES = (3, 10)
PAUSE_S = (0.25, 0.7)
CAVITY_BGR = (28, 26, 52)
TONGUE_BGR = (70, 80, 150)


@dataclass(frozen=True, slots=True)
class Jaw:
    """How the mesh's vertices follow an opening jaw (built once per mesh, `jaw_of`)."""

    weights: FloatArray
    """(478,) 0 (stays) to 1 (turns fully with the jaw)."""
    hinge_px: FloatArray
    """(3,) the hinge, in mesh pixels."""
    face_width_px: float

    def motion_for(self, points_px: FloatArray, fraction: float) -> tuple[float, float]:
        """(turn in radians, slide down in pixels) that move the lower inner lip down by the
        asked gap: a turn up to `MAX_TURN_DEG`, the rest a slide."""
        gap = max(0.0, fraction) * FULL_GAP_W * self.face_width_px
        dy, dz = points_px[14, 1] - self.hinge_px[1], points_px[14, 2] - self.hinge_px[2]
        radius, phase = math.hypot(dy, dz), math.atan2(-dz, dy)
        wanted = phase - math.acos(min(1.0, (dy + gap) / max(radius, 1e-9)))
        angle = min(wanted, math.radians(MAX_TURN_DEG))
        return angle, dy + gap - radius * math.cos(phase - angle)

    def open(self, points_px: FloatArray, fraction: float) -> FloatArray:
        """(478, 3) the mesh with the jaw opened by `fraction` (0 closed as photographed)."""
        if fraction <= 0.0:
            return points_px
        angle, slide = self.motion_for(points_px, fraction)
        cos_a, sin_a = math.cos(angle), math.sin(angle)
        dy = points_px[:, 1] - self.hinge_px[1]
        dz = points_px[:, 2] - self.hinge_px[2]
        moved = points_px.copy()
        moved[:, 1] += self.weights * (dy * cos_a - dz * sin_a - dy + slide)
        moved[:, 2] += self.weights * (dy * sin_a + dz * cos_a - dz)
        return moved


def jaw_of(points_px: FloatArray, face_width_px: float) -> Jaw:
    """The jaw of a (478, 3) mesh in pixels."""
    left, right = points_px[MOUTH_CORNERS[0]], points_px[MOUTH_CORNERS[1]]
    slope = (right[1] - left[1]) / max(right[0] - left[0], 1e-9)
    line_y = left[1] + slope * (points_px[:, 0] - left[0])
    below_w = (points_px[:, 1] - line_y) / face_width_px
    weights = np.clip(below_w / RAMP_W, 0.0, 1.0)
    weights = weights * weights * (3.0 - 2.0 * weights)  # smooth start and end
    weights[list(UPPER_INNER) + list(UPPER_OUTER)] = 0.0
    weights[list(LOWER_INNER) + list(LOWER_OUTER)] = 1.0
    weights[[*MOUTH_CORNERS, 78, 308]] = CORNER_WEIGHT
    eyes_y = float(points_px[list(EYE_LINE), 1].mean())
    hinge = np.array(
        [
            float(points_px[:, 0].mean()),
            eyes_y + 0.5 * (points_px[NOSE_TIP, 1] - eyes_y),
            points_px[NOSE_TIP, 2] + HINGE_BEHIND_W * face_width_px,
        ]
    )
    return Jaw(np.asarray(weights, dtype=np.float64), hinge, face_width_px)


def inside_triangles(triangles: npt.NDArray[np.int32]) -> npt.NDArray[np.int64]:
    """Indices of the triangles closing the mouth (all three corners on the inner lips)."""
    inner = np.asarray(sorted(set(UPPER_INNER) | set(LOWER_INNER)))
    return np.flatnonzero(np.isin(triangles, inner).all(axis=1))


def paint_inside(
    frame: npt.NDArray[np.uint8],
    inside: npt.NDArray[np.bool_],
    turned_px: FloatArray,
    teeth_bgr: FloatArray,
    face_width_px: float,
) -> None:
    """Paint the inside of the mouth on the `inside` pixels of `frame` (in place): the cavity,
    the upper teeth under the upper lip, the lower teeth's edge and the tongue."""
    import cv2

    if not inside.any():
        return
    upper = np.round(turned_px[list(UPPER_INNER), :2] * 16).astype(np.int32)
    lower = np.round(turned_px[list(LOWER_INNER), :2] * 16).astype(np.int32)
    gap = float(np.median(turned_px[list(LOWER_INNER), 1] - turned_px[list(UPPER_INNER), 1]))
    ys, xs = np.nonzero(inside)
    y0, y1 = max(0, ys.min() - 2), min(frame.shape[0], ys.max() + 3)
    x0, x1 = max(0, xs.min() - 2), min(frame.shape[1], xs.max() + 3)
    shift = np.array([x0, y0]) * 16
    painted = np.empty((y1 - y0, x1 - x0, 3), dtype=np.uint8)
    painted[:] = CAVITY_BGR
    tongue_x, tongue_y = (lower[5] - shift) / 16 - (0.0, 0.2 * gap)
    tongue_axes = (max(1, round(0.09 * face_width_px)), max(1, round(0.25 * gap)))
    centre = (round(tongue_x), round(tongue_y))
    cv2.ellipse(painted, centre, tongue_axes, 0, 180, 360, TONGUE_BGR, -1)
    teeth = tuple(int(v) for v in teeth_bgr)
    upper_drop = np.array([0, round(min(0.05 * face_width_px, 0.4 * gap) * 16)])
    band = np.vstack([upper, upper[::-1] + upper_drop]) - shift
    cv2.fillPoly(painted, [band], teeth, cv2.LINE_AA, 4)
    lower_rise = np.array([0, round(min(0.025 * face_width_px, 0.15 * gap) * 16)])
    band = np.vstack([lower, lower[::-1] - lower_rise]) - shift
    cv2.fillPoly(painted, [band], teeth, cv2.LINE_AA, 4)
    painted = cv2.GaussianBlur(painted, (0, 0), 0.6)
    region = inside[y0:y1, x0:x1]
    frame[y0:y1, x0:x1][region] = painted[region]


def speech_track(t_s: FloatArray, seed: int) -> FloatArray:
    """The mouth's opening (fraction of `FULL_GAP_W`) at each time of `t_s` while talking:
    syllables at 3-5 Hz of irregular size in phrases with pauses (seeded, deterministic)."""
    rng = np.random.default_rng(seed)
    times = np.asarray(t_s, dtype=np.float64)
    opening = np.zeros_like(times)
    end = float(times.max()) if times.size else 0.0
    start = float(rng.uniform(0.0, PAUSE_S[1]))
    while start <= end:
        for _ in range(int(rng.integers(PHRASE_SYLLABLES[0], PHRASE_SYLLABLES[1] + 1))):
            length = 1.0 / float(rng.uniform(*SPEECH_HZ))
            size = float(rng.uniform(*SPEECH_OPENING))
            phase = (times - start) / length
            inside = (phase >= 0.0) & (phase < 1.0)
            opening[inside] = size * np.sin(np.pi * phase[inside]) ** 2
            start += length
        start += float(rng.uniform(*PAUSE_S))
    return opening
