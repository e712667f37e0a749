"""What a camera in a car sees besides a face: sensor noise, sunglasses, a covered lens, no one.

Used by the conformance scenarios (`roadgaze.conformance`) on top of `FaceRenderer` frames:

- `sensor_noise`: Gaussian noise on every pixel (a real sensor never repeats a frame exactly, so
  a held pose must not read as a frozen camera; sigma 2 grey levels by default);
- `sunglasses`: two dark lenses over the eyes of the turned mesh and a bridge between them (the
  eyes cannot be judged; the head still can);
- `covered_frame`: a lens covered by a hand or a cloth: dark and flat;
- `background_frame` (`FaceRenderer.background`): the cabin without the driver (no face).

A frozen camera is the same frame delivered again: the caller repeats a frame without noise.
"""

from __future__ import annotations

import numpy as np

from roadgaze.landmarks.eye_landmarks import EYES
from roadgaze.synth.renderer import FaceRenderer, ImageBGR

NOISE_SIGMA = 2.0
"""Sensor noise, grey levels (a camera's read noise in daylight is 1-3 levels)."""
COVERED_GREY = 6
"""The mean grey level of a covered lens (a little light leaks in)."""
LENS_WIDTH_EYE_WIDTHS = 1.7
"""A lens is this many eye widths wide (a typical lens is 50-55 mm for a 30 mm eye)."""
LENS_BGR = (22, 20, 18)


def sensor_noise(frame: ImageBGR, rng: np.random.Generator, sigma: float = NOISE_SIGMA) -> ImageBGR:
    """`frame` with Gaussian noise of `sigma` grey levels added per pixel, clipped to 0-255."""
    noisy = frame.astype(np.float32) + rng.normal(0.0, sigma, frame.shape).astype(np.float32)
    out: ImageBGR = np.clip(noisy + 0.5, 0, 255).astype(np.uint8)
    return out


class NoiseBank:
    """Sensor noise at the cost of two saturating adds: `count` noise frames drawn once and
    taken in turn (two consecutive frames never share one; `count` >= 2)."""

    def __init__(
        self,
        size: tuple[int, int],
        rng: np.random.Generator,
        sigma: float = NOISE_SIGMA,
        count: int = 8,
    ) -> None:
        width, height = size
        self._up: list[ImageBGR] = []
        self._down: list[ImageBGR] = []
        for _ in range(max(2, count)):
            noise = np.rint(rng.normal(0.0, sigma, (height, width, 3)))
            self._up.append(np.clip(noise, 0, 255).astype(np.uint8))
            self._down.append(np.clip(-noise, 0, 255).astype(np.uint8))
        self._next = 0

    def __call__(self, frame: ImageBGR) -> ImageBGR:
        """`frame` with the next noise frame added (clipped to 0-255)."""
        import cv2

        index = self._next
        self._next = (index + 1) % len(self._up)
        return np.asarray(
            cv2.subtract(cv2.add(frame, self._up[index]), self._down[index]), dtype=np.uint8
        )


def covered_frame(size: tuple[int, int], rng: np.random.Generator) -> ImageBGR:
    """A covered lens: `COVERED_GREY` with a little noise, (height, width, 3) for `size` (w, h)."""
    width, height = size
    flat = np.full((height, width, 3), COVERED_GREY, dtype=np.uint8)
    return sensor_noise(flat, rng, 1.0)


def sunglasses(
    frame: ImageBGR, renderer: FaceRenderer, yaw_deg: float, pitch_deg: float
) -> ImageBGR:
    """`frame` (the face rendered at `yaw_deg`, `pitch_deg`) with dark lenses over both eyes.

    Each lens is an ellipse around the eye's contour as the turned mesh places it,
    `LENS_WIDTH_EYE_WIDTHS` eye widths wide and 0.8 of that tall (foreshortened with the eye);
    a bridge joins the inner corners. An eye turned away from the camera gets no lens.
    """
    import cv2

    points = renderer.turned_points(yaw_deg, pitch_deg)
    out = frame.copy()
    inner: list[tuple[int, int]] = []
    for eye in EYES:
        contour = points[list(eye.contour), :2]
        width_px = float(np.hypot(*(points[eye.outer, :2] - points[eye.inner, :2])))
        if width_px < 2.0:
            continue
        centre = contour.mean(axis=0)
        axes = (
            round(0.5 * LENS_WIDTH_EYE_WIDTHS * width_px),
            round(0.4 * LENS_WIDTH_EYE_WIDTHS * width_px),
        )
        dx, dy = points[eye.outer, :2] - points[eye.inner, :2]
        angle = float(np.degrees(np.arctan2(dy, dx)))
        cv2.ellipse(out, (round(centre[0]), round(centre[1])), axes, angle, 0, 360, LENS_BGR, -1)
        inner.append((round(points[eye.inner, 0]), round(points[eye.inner, 1])))
    if len(inner) == 2:
        thickness = max(2, round(0.02 * renderer.mesh.face_width_px))
        cv2.line(out, inner[0], inner[1], LENS_BGR, thickness)
    return out
