"""The hand stage's front end: a flat frame (near-infrared, a dark cabin) made fit for the hand
and body models.

The face's front end (`roadgaze.landmarks.front_end`) decides which frames are hard (dark or
flat, as a near-infrared camera's or a night cabin's) and how to lift them; the hand stage takes
its flat frames (`assess`) and the same tone curve (`tone_curve`), with two differences, each
measured on the State Farm cabin photographs put under the condition suite's `ir_grey` and
`dark` (docs/phone.md, "At night"):

- the smoothing before the curve is the face's `strong` bilateral filter applied
  `SMOOTHING_PASSES` times: MediaPipe's palm detector and hand landmark model lose a hand in
  sensor noise long before the face detector loses a face, and a Gaussian blur, the face's
  first look, takes the fingers' edges with the noise;
- a colour frame keeps its colour (each pixel's colour scaled to its lifted luminance): the
  palm detector reads skin colour, and a dark cabin's frame still has it. A frame without
  colour (grey, or three equal channels, as a grey camera's picture often comes) is handled as
  one grey channel.

Which frames: the face's flat ones (spread under `FLAT_SPREAD`), not its dark ones of full
spread. A dark cabin is flat as well (the condition suite's `dark`: spread about 40), but a
dark frame whose levels still span the range needs no stretch: of the 1,670 State Farm
development images three are dark by the face's rule (mean 63-69, spread 238-248), and
lifting them changed the hands found in all three and lost one texting image's phone use
(chosen after seeing them, said plainly). Every other frame goes to the models untouched
(`[hands] enhance` `auto`).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import numpy.typing as npt

from roadgaze.landmarks.front_end import (
    FLAT_SPREAD,
    GRID_STEP,
    NOISY_LEVELS,
    SMOOTHING_KERNEL_PX,
    STRONG_COLOUR_SIGMA,
    STRONG_DIAMETER_PX,
    STRONG_SPACE_SIGMA_PX,
    assess,
    tone_curve,
)

HandEnhanceMode = Literal["auto", "off", "always"]
SMOOTHING_PASSES = 2
"""The face's `strong` bilateral filter is applied this many times to a noisy hard frame before
the hand models see it. Chosen on every 10th State Farm development image under `ir_grey`
(167 images; hands found per image): one pass 0.41, two passes 0.57 (clean colour 1.04, the
same images in grey without noise 0.58), a 13 px filter once 0.55, the face's `wide` look 0.49,
its `coarse` look 0.44, its Gaussian 0.29 (docs/phone.md)."""


def _colourless(image: npt.NDArray[np.uint8]) -> bool:
    """Whether the frame has no colour: grey, or its channels equal on the decision's grid."""
    if image.ndim == 2 or image.shape[2] == 1:
        return True
    grid = image[::GRID_STEP, ::GRID_STEP, :3].astype(np.int16)
    return bool(np.all(grid[:, :, 0] == grid[:, :, 1]) and np.all(grid[:, :, 1] == grid[:, :, 2]))


def enhance_for_hands(image: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
    """`image` (grey, BGR or BGRA uint8) lifted for the hand models: its luminance smoothed by
    `SMOOTHING_PASSES` of the face's `strong` filter when its noise is `NOISY_LEVELS` or more,
    through the face's tone curve. A frame without colour comes back grey (one channel); a colour
    frame comes back BGR, each pixel's colour (from the frame smoothed by the face's Gaussian when
    noisy: colour is coarse in a camera's picture anyway) scaled to the lifted luminance."""
    import cv2

    colourless = _colourless(image)
    if colourless:
        grey = image if image.ndim == 2 else np.ascontiguousarray(image[:, :, 0])
    else:
        colour = np.ascontiguousarray(image[:, :, :3])
        grey = np.asarray(cv2.cvtColor(colour, cv2.COLOR_BGR2GRAY), np.uint8)
    levels = assess(grey, noise=True)
    noisy = levels.noise >= NOISY_LEVELS
    smoothed = grey
    for _ in range(SMOOTHING_PASSES if noisy else 0):
        sigma_colour = STRONG_COLOUR_SIGMA * levels.noise
        smoothed = np.asarray(
            cv2.bilateralFilter(smoothed, STRONG_DIAMETER_PX, sigma_colour, STRONG_SPACE_SIGMA_PX),
            np.uint8,
        )
    lifted = np.asarray(cv2.LUT(smoothed, tone_curve(levels)), np.uint8)
    if colourless:
        return lifted
    if noisy:
        kernel = (SMOOTHING_KERNEL_PX, SMOOTHING_KERNEL_PX)
        colour = np.asarray(cv2.GaussianBlur(colour, kernel, 0), np.uint8)
    base = cv2.cvtColor(colour, cv2.COLOR_BGR2GRAY).astype(np.float32)
    gain = (lifted.astype(np.float32) + 1.0) / (base + 1.0)
    return np.asarray(np.clip(np.rint(colour * gain[:, :, None]), 0, 255), np.uint8)


def for_hands(image: npt.NDArray[np.uint8], mode: HandEnhanceMode) -> npt.NDArray[np.uint8]:
    """The frame the hand and body models see: `image` as it is (`off`, or in `auto` a frame
    whose spread is `FLAT_SPREAD` or more), else `enhance_for_hands(image)`."""
    if mode == "off" or (mode == "auto" and assess(image).spread >= FLAT_SPREAD):
        return image
    return enhance_for_hands(image)
