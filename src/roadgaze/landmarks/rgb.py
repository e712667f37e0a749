"""The image as the landmark engines take it: RGB from BGR, BGRA or grey, and the grey the eye
check measures."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt


def to_rgb(image: npt.NDArray[Any]) -> npt.NDArray[np.uint8]:
    """A contiguous RGB uint8 copy of a BGR, BGRA or grayscale image; ValueError otherwise."""
    import cv2

    array = np.asarray(image)
    if array.dtype != np.uint8:
        raise ValueError(f"expected a uint8 image, found dtype {array.dtype}")
    if array.ndim == 3 and array.shape[2] == 1:
        array = array[:, :, 0]
    if array.ndim in (2, 3) and (array.shape[0] < 1 or array.shape[1] < 1):
        raise ValueError(f"empty image of shape {array.shape}")
    if array.ndim == 2:
        rgb = cv2.cvtColor(array, cv2.COLOR_GRAY2RGB)
    elif array.ndim == 3 and array.shape[2] == 3:
        rgb = cv2.cvtColor(array, cv2.COLOR_BGR2RGB)
    elif array.ndim == 3 and array.shape[2] == 4:
        rgb = cv2.cvtColor(array, cv2.COLOR_BGRA2RGB)
    else:
        raise ValueError(f"expected a grayscale, BGR or BGRA image, found shape {array.shape}")
    return np.ascontiguousarray(rgb)


def rgb_to_gray(rgb: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
    """The grey image the eye check measures (OpenCV's luma weights)."""
    import cv2

    return np.asarray(cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY), dtype=np.uint8)
