"""What a camera in a car sees besides a face: sensor noise, sunglasses, a covered lens, no one,
the night.

Used by the conformance scenarios (`roadgaze.conformance`) on top of `FaceRenderer` frames:

- `sensor_noise`: Gaussian noise on every pixel (a real sensor never repeats a frame exactly, so
  a held pose must not read as a frozen camera; sigma 2 grey levels by default);
- `sunglasses`: dark glasses on the turned head (`roadgaze.synth.wearables`; the eyes cannot be
  judged, the head still can);
- `covered_frame`: a lens covered by a hand or a cloth: dark and flat;
- `background_frame` (`FaceRenderer.background`): the cabin without the driver (no face);
- `night`: the picture of an infrared cabin camera at night (the condition suite's `ir_grey`).

A frozen camera is the same frame delivered again: the caller repeats a frame without noise.
"""

from __future__ import annotations

import numpy as np

from roadgaze.synth.renderer import FaceRenderer, ImageBGR

NOISE_SIGMA = 2.0
"""Sensor noise, grey levels (a camera's read noise in daylight is 1-3 levels)."""
COVERED_GREY = 6
"""The mean grey level of a covered lens (a little light leaks in)."""


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
    """`frame` (the face rendered at `yaw_deg`, `pitch_deg`) with dark sunglasses on
    (`roadgaze.synth.wearables.glasses` with `DARK` lenses: the eyes cannot be judged; the head
    still can)."""
    from roadgaze.synth.wearables import DARK, glasses

    return glasses(frame, renderer, yaw_deg, pitch_deg, DARK)


def night(frame: ImageBGR, rng: np.random.Generator) -> ImageBGR:
    """`frame` as an infrared cabin camera sees it at night: the condition suite's `ir_grey`
    (`roadgaze.evaluation.conditions`: one grey channel, contrast 0.4 about a mean of 120, sensor
    noise of 6 levels), as three equal channels."""
    import cv2

    from roadgaze.evaluation.conditions import ir_grey

    return np.asarray(cv2.cvtColor(ir_grey(frame, rng), cv2.COLOR_GRAY2BGR), dtype=np.uint8)
