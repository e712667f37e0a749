"""A head that leans: the rendered face moved and scaled as a camera sees a head displaced from
its driving place (`roadgaze.cabin.face_seen`), and a wider lens (`zoom`).

The renderer turns the head about its neck at the driving place; a lean moves the whole head.
Seen by a pinhole camera aimed at the head, a head displaced by `head_m` (driver's frame) moves
its face across the image by the displacement across the camera's view times the face's new
size, and grows by the camera's distance over the new depth (`roadgaze.cabin`); the picture is
scaled about the face's place at rest (the principal point: the renderer's face centre) and
shifted by that. The background moves with it (the cabin behind a real driver would not; the
landmarker reads the face).
"""

from __future__ import annotations

import numpy as np

from roadgaze.cabin import FACE_WIDTH_M, FacePlace, Vector3, camera_distance_m, face_seen
from roadgaze.mounting import CameraMounting
from roadgaze.synth.renderer import ImageBGR

__all__ = ["FACE_CENTRE_HEIGHT", "lean_affine", "leaned"]

FACE_CENTRE_HEIGHT = 0.45
"""The renderer puts the face's centre at half the width and this fraction of the height."""


def lean_affine(
    size: tuple[int, int],
    face_width_px: float,
    mounting: CameraMounting,
    head_m: Vector3,
    zoom: float = 1.0,
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The 2x3 affine taking the rendered picture (head at its driving place) to the picture of
    the head displaced by `head_m`, through a lens `zoom` times as narrow."""
    width, height = size
    centre = (0.5 * width, FACE_CENTRE_HEIGHT * height)
    reference = FacePlace(centre[0], centre[1], zoom * face_width_px / FACE_WIDTH_M)
    distance = camera_distance_m(mounting)
    seen = face_seen(mounting, distance, reference, head_m)
    scale = zoom * seen.k_px_per_m / reference.k_px_per_m
    return (
        (scale, 0.0, seen.u_px - scale * centre[0]),
        (0.0, scale, seen.v_px - scale * centre[1]),
    )


def leaned(
    frame: ImageBGR,
    face_width_px: float,
    mounting: CameraMounting,
    head_m: Vector3,
    zoom: float = 1.0,
) -> ImageBGR:
    """`frame` as the camera sees the head displaced by `head_m` (unchanged for no lean and no
    zoom)."""
    import cv2

    if zoom == 1.0 and head_m == (0.0, 0.0, 0.0):
        return frame
    height, width = frame.shape[:2]
    matrix = np.array(lean_affine((width, height), face_width_px, mounting, head_m, zoom))
    warped = cv2.warpAffine(
        frame, matrix, (width, height), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
    )
    return np.ascontiguousarray(warped, dtype=np.uint8)
