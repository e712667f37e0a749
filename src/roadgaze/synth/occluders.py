"""Things between the camera and the face that do not move with the head: a hand on the wheel.

**A hand at 12 o'clock** (`hand_at_12`): the driver grips the top of the steering wheel. The hand
and forearm stay where the wheel is while the head turns, so they are placed in the camera's
image, relative to where the eyes are when the driver looks at the road, by camera mounting.
How much of the face they hide depends on where the camera sits (roadgaze's own estimates for
the presets of `roadgaze.mounting`, in face widths W below the eye line; the fist is drawn
at 1.2 times its size next to the face, being nearer the camera):

- `steering_column`: the hand hangs from the rim into the wheel's opening right in front of the
  lens: the fist over the nose (0.25 W below the eyes), the forearm on to the elbow, below and
  to the driver's outer side: eyes, nose and mouth hidden;
- `front` (ahead at eye height): the fist on the rim just below the line of sight (0.8 W below
  the eyes), the forearm straight down: the chin and the mouth hidden;
- `centre_console`: the forearm to the wheel crosses the jaw on the camera's side (the fist
  1.1 W below the eyes, 0.3 W toward the camera);
- `a_pillar`: the top of the wheel is out of the line from the pillar to the face: nothing.

The fist is skin-coloured (the photo's own cheek), with four knuckles, the creases between the
fingers and the rim of the wheel (dark leather) running under them; light from above.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.synth.layers import Layer, out_of_focus
from roadgaze.synth.renderer import FaceRenderer, ImageBGR
from roadgaze.types import FloatArray

FIST_W, FIST_H = 0.78, 0.52
"""The fist seen from the front (9 x 6 cm at 1.2 times: nearer the camera than the face)."""
FOREARM_W = 0.6
RIM_W = 0.2
RIM_BGR = (38, 36, 36)
BLUR_W = 0.015
"""The hand's blur (a Gaussian, in face widths): it is nearer the lens than the face."""
CHEEKS = (50, 280)
"""Cheek landmarks whose skin colours the hand."""


@dataclass(frozen=True, slots=True)
class HandPlacement:
    """Where the fist sits (below the eye line and across, in W) and where the forearm goes."""

    below_eyes_w: float
    across_w: float
    forearm: tuple[float, float]
    """The forearm's direction in the image (x right, y down), toward the elbow."""


PLACEMENTS: dict[str, HandPlacement | None] = {
    "steering_column": HandPlacement(0.25, 0.0, (0.45, 1.0)),
    "front": HandPlacement(0.8, 0.0, (0.0, 1.0)),
    "centre_console": HandPlacement(1.1, 0.3, (0.35, 1.0)),
    "a_pillar": None,
}
"""Left-hand drive, as the camera sees it (x toward the image right); mirrored in a
right-hand-drive cabin."""


def skin_bgr(renderer: FaceRenderer) -> FloatArray:
    """The face's skin colour (BGR): the median of two cheek patches of the photo."""
    points = renderer.mesh.points_px
    half = max(2, round(0.03 * renderer.mesh.face_width_px))
    patches = [
        renderer.texture[round(y) - half : round(y) + half, round(x) - half : round(x) + half]
        for x, y in points[list(CHEEKS), :2]
    ]
    return np.asarray(np.median(np.vstack([p.reshape(-1, 3) for p in patches]), axis=0))


def hand_at_12(
    frame: ImageBGR,
    renderer: FaceRenderer,
    mounting: str,
    cabin: str = "lhd",
    rest_deg: tuple[float, float] = (0.0, 0.0),
) -> ImageBGR:
    """`frame` with a hand gripping the top of the wheel as a camera at `mounting` sees it
    (`hand_layer`; the frame as it is where the camera does not see the hand)."""
    layer = hand_layer(renderer, mounting, cabin, rest_deg)
    return frame if layer is None else layer.over(frame)


def hand_layer(
    renderer: FaceRenderer,
    mounting: str,
    cabin: str = "lhd",
    rest_deg: tuple[float, float] = (0.0, 0.0),
) -> Layer | None:
    """The hand gripping the top of the wheel as a camera at `mounting` sees it (in `cabin`),
    over the renderer's whole frame, placed from where the eyes are with the head at `rest_deg`
    (the yaw and pitch of the road pose as that camera sees it, rendered): the forearm (rounded:
    darker at its edges) from the fist to the image's edge, the rim either side of the fist,
    the fist over both (lit from above, the creases between the fingers), all a little out of
    focus (`BLUR_W`: nearer the lens than the face it focuses on). None where the camera does
    not see it. Build it once per camera and composite it on every frame."""
    import cv2

    placement = PLACEMENTS.get(mounting)
    if placement is None:
        return None
    width = renderer.mesh.face_width_px
    mirror = -1.0 if cabin == "rhd" else 1.0
    eyes = renderer.turned_points(*rest_deg)[[33, 263], :2].mean(axis=0)
    centre = eyes + np.array([mirror * placement.across_w, placement.below_eyes_w]) * width
    forearm = np.array([mirror * placement.forearm[0], placement.forearm[1]])
    forearm /= np.linalg.norm(forearm)
    skin = skin_bgr(renderer).astype(np.float32)
    columns, height = renderer.size
    colour = np.zeros((height, columns, 3), dtype=np.float32)
    alpha = np.zeros((height, columns), dtype=np.float32)
    ys, xs = np.mgrid[0:height, 0:columns].astype(np.float32)

    def shape(points: FloatArray) -> npt.NDArray[np.uint8]:
        mask = np.zeros((height, columns), dtype=np.uint8)
        cv2.fillPoly(mask, [np.round(points * 16).astype(np.int32)], 255, cv2.LINE_AA, 4)
        return mask

    def paint(mask: npt.NDArray[np.uint8], bgr: npt.NDArray[np.floating[Any]]) -> None:
        cover = (mask.astype(np.float32) / 255.0)[..., None]
        colour[:] = colour * (1.0 - cover) + bgr * cover
        alpha[:] = np.maximum(alpha, cover[..., 0])

    # The forearm: rounded, so darker toward its edges.
    across = np.array([-forearm[1], forearm[0]])
    off_axis = np.abs((xs - centre[0]) * across[0] + (ys - centre[1]) * across[1])
    rounded = np.clip(1.0 - 0.35 * (off_axis / (0.5 * FOREARM_W * width)) ** 2, 0.6, 1.0)
    reach = (height - centre[1]) / max(float(forearm[1]), 0.2) + width
    side, end = across * 0.5 * FOREARM_W * width, centre + reach * forearm
    arm = shape(np.vstack([centre + side, centre - side, end - side, end + side]))
    paint(arm, 0.85 * skin * rounded[..., None])
    # The rim either side of the fist.
    half_w, half_h = 0.5 * FIST_W * width, 0.5 * FIST_H * width
    left, right, top = centre[0] - half_w, centre[0] + half_w, centre[1] - half_h
    rim_top, rim_bottom = top + 0.2 * width, top + (0.2 + RIM_W) * width
    far_left, far_right = left - 0.7 * width, right + 0.7 * width
    rim = [
        [far_left, rim_top],
        [far_right, rim_top],
        [far_right, rim_bottom],
        [far_left, rim_bottom],
    ]
    paint(shape(np.array(rim)), np.asarray(RIM_BGR, dtype=np.float32))
    # The fist: four knuckles along its top, lit from above, creases between the fingers.
    bottom = top + 2 * half_h
    fist = shape(np.array([[left, top], [right, top], [right, bottom], [left, bottom]]))
    knuckle = 0.25 * FIST_W * width / 2
    for index in range(4):
        at = (round((left + (2 * index + 1) * knuckle) * 16), round(top * 16))
        cv2.circle(fist, at, round(knuckle * 16), 255, -1, cv2.LINE_AA, 4)
    light = np.clip(1.1 - 0.4 * (ys - top) / (2 * half_h), 0.7, 1.1)[..., None]
    paint(fist, skin * light)
    crease = tuple(float(c) * 0.6 for c in skin)
    for index in range(1, 4):
        x = left + 2 * index * knuckle
        line = np.round(np.array([[x, top], [x, top + 1.2 * half_h]]) * 16).astype(np.int32)
        cv2.polylines(colour, [line], False, crease, 1, cv2.LINE_AA, 4)
    return out_of_focus(colour, alpha, max(0.5, BLUR_W * width))
