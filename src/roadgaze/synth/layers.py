"""Paint on the photo's texture: what is painted there is turned with the face by the renderer.

A `Layer` is a colour and an alpha over the whole texture (the unturned photo in output
pixels). Layers are composited once, when a renderer is dressed; the renderer's per-triangle warp
then carries them with every turn, nod and opened jaw, foreshortened and hidden as the skin under
them is. Two places to paint (`EyeRenderer.repainted`): *under* the eyes (the texture the lids
and irises are cut from: eyelash makeup, which must close with the lid) and *over* them (composited
after the eyes are drawn: a fringe, a mask, a beard, which the lids never move).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.types import FloatArray

ImageBGR = npt.NDArray[np.uint8]


@dataclass(frozen=True, slots=True)
class Layer:
    """A colour (H, W, 3, BGR, 0-255) with an alpha (H, W, 0 clear to 1 opaque)."""

    colour: npt.NDArray[np.float32]
    alpha: npt.NDArray[np.float32]

    def over(self, image: ImageBGR) -> ImageBGR:
        """`image` with this layer composited on top."""
        alpha = self.alpha[..., None]
        mixed = image.astype(np.float32) * (1.0 - alpha) + self.colour * alpha
        return np.asarray(np.clip(mixed + 0.5, 0, 255), dtype=np.uint8)

    @property
    def covered(self) -> npt.NDArray[np.bool_]:
        """Where the layer shows at all."""
        return np.asarray(self.alpha > 0.02)


def stack(layers: Iterable[Layer]) -> Layer | None:
    """The layers composited in order (the last on top) as one layer; None for none."""
    result: Layer | None = None
    for layer in layers:
        if result is None:
            result = layer
            continue
        alpha = layer.alpha + result.alpha * (1.0 - layer.alpha)
        weight = np.where(alpha > 1e-6, layer.alpha / np.maximum(alpha, 1e-6), 0.0)[..., None]
        colour = layer.colour * weight + result.colour * (1.0 - weight)
        result = Layer(colour.astype(np.float32), alpha.astype(np.float32))
    return result


def region_alpha(
    shape: tuple[int, int],
    polygon_px: FloatArray,
    feather_px: float,
    holes: Iterable[FloatArray] = (),
) -> npt.NDArray[np.float32]:
    """An alpha of 1 inside `polygon_px` ((N, 2) pixels) but for its `holes`, its edge softened
    by a Gaussian of `feather_px`."""
    import cv2

    mask = np.zeros(shape, dtype=np.uint8)
    cv2.fillPoly(mask, [np.round(polygon_px * 16).astype(np.int32)], 255, cv2.LINE_AA, 4)
    for hole in holes:
        cv2.fillPoly(mask, [np.round(hole * 16).astype(np.int32)], 0, cv2.LINE_AA, 4)
    alpha = mask.astype(np.float32) / 255.0
    if feather_px > 0:
        return np.asarray(cv2.GaussianBlur(alpha, (0, 0), feather_px), dtype=np.float32)
    return alpha


def out_of_focus(
    colour: npt.NDArray[np.float32], alpha: npt.NDArray[np.float32], blur_px: float
) -> Layer:
    """A layer painted sharp (`colour`, `alpha`) seen out of focus: colour and alpha spread by a
    Gaussian of `blur_px`, the colour weighted by the alpha (no dark fringe at the edges)."""
    import cv2

    spread = np.asarray(cv2.GaussianBlur(colour * alpha[..., None], (0, 0), blur_px))
    soft = np.asarray(cv2.GaussianBlur(alpha, (0, 0), blur_px))[..., None]
    shown = np.where(soft > 1e-3, spread / np.maximum(soft, 1e-3), 0.0)
    return Layer(shown.astype(np.float32), soft[..., 0].astype(np.float32))
