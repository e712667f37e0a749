"""Cabin conditions for the condition suite: one seeded image transform per condition.

`roadgaze eval DATASET --condition NAME` applies one of these to every image before the service
sees it (docs/conditions.md). Each transform takes a uint8 image (BGR or single-channel grey), a
`numpy.random.Generator` and, for the ones that draw on the face, the face's (478, 3) landmarks
in pixels from the clean image (None: a fixed face box in the middle of the image stands in);
it returns a new uint8 image and never changes its input. The parameters are keyword arguments
with the suite's values as defaults, so a figure in the docs names its transform exactly.

`apply_condition` seeds the generator from the suite's seed, the condition and the file name, so
an image gets the same noise whichever worker process runs it and in whatever order.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.landmarks.eye_landmarks import LEFT_EYE, RIGHT_EYE
from roadgaze.landmarks.features import FACE_OVAL, NOSE_TIP

Image = npt.NDArray[np.uint8]
Landmarks = npt.NDArray[np.float32] | None

CLEAN = "clean"
SEED = 23
"""The suite's seed (`apply_condition`)."""
NOSE_RIDGE = 195
"""The nose-ridge landmark about halfway between the eyes and the nose tip: a mask's top edge."""


def _gray(image: Image) -> npt.NDArray[np.float32]:
    import cv2

    if image.ndim == 2:
        return image.astype(np.float32)
    return np.asarray(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), dtype=np.float32)


def _to_uint8(values: npt.NDArray[Any]) -> Image:
    return np.asarray(np.clip(np.rint(values), 0, 255), np.uint8)


def ir_grey(
    image: Image,
    rng: np.random.Generator,
    *,
    contrast: float = 0.4,
    mean_level: float = 120.0,
    noise_std: float = 6.0,
) -> Image:
    """A near-infrared camera's picture: one grey channel, flat contrast, sensor noise.

    The grey image's deviations from its mean are scaled by `contrast`, the mean moved to
    `mean_level` (an active illuminator's even haze), then Gaussian noise of `noise_std` grey
    levels is added. Returns a 2-D image (as a V4L2 GREY camera delivers).
    """
    gray = _gray(image)
    flat = mean_level + contrast * (gray - gray.mean())
    return _to_uint8(flat + rng.normal(0.0, noise_std, gray.shape))


def dark_cabin(
    image: Image,
    rng: np.random.Generator,
    *,
    gain: float = 0.15,
    noise_std: float = 3.0,
) -> Image:
    """A dark cabin at night: every level times `gain`, then Gaussian noise of `noise_std`
    levels (per pixel and channel); same shape as the input."""
    dark = image.astype(np.float32) * gain
    return _to_uint8(dark + rng.normal(0.0, noise_std, image.shape))


def bright_glare(
    image: Image,
    rng: np.random.Generator,
    *,
    gain: float = 1.3,
    offset: float = 40.0,
    spot_radius: float = 0.3,
    spot_level: float = 120.0,
) -> Image:
    """Low sun in the cabin: levels times `gain` plus `offset` (clipped: the bright half of the
    face saturates), and a glare spot, a Gaussian of `spot_level` levels and a standard deviation
    of `spot_radius` times the image width, centred at a random point of the image's upper half."""
    height, width = image.shape[:2]
    centre_x, centre_y = rng.uniform(0.2, 0.8) * width, rng.uniform(0.0, 0.5) * height
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    spread = (spot_radius * width) ** 2
    spot = spot_level * np.exp(-((xs - centre_x) ** 2 + (ys - centre_y) ** 2) / (2.0 * spread))
    if image.ndim == 3:
        spot = spot[:, :, None]
    return _to_uint8(image.astype(np.float32) * gain + offset + spot)


def motion_blur(
    image: Image, rng: np.random.Generator, *, length_px: int = 15, max_angle_deg: float = 30.0
) -> Image:
    """A head moving during the exposure: a line kernel `length_px` long at a random angle
    within +-`max_angle_deg` of horizontal."""
    import cv2

    angle = np.deg2rad(rng.uniform(-max_angle_deg, max_angle_deg))
    kernel = np.zeros((length_px, length_px), np.float32)
    centre = (length_px - 1) / 2.0
    offset = np.linspace(-centre, centre, 4 * length_px)
    xs = np.rint(centre + offset * np.cos(angle)).astype(int)
    ys = np.rint(centre + offset * np.sin(angle)).astype(int)
    kernel[ys, xs] = 1.0
    kernel /= kernel.sum()
    return np.asarray(cv2.filter2D(image, -1, kernel, borderType=cv2.BORDER_REFLECT), np.uint8)


def jpeg_compression(image: Image, rng: np.random.Generator, *, quality: int = 10) -> Image:
    """A starved video link: JPEG encoding at `quality` (0-100) and back (`rng` unused)."""
    import cv2

    ok, encoded = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise ValueError("JPEG encoding failed")
    flag = cv2.IMREAD_GRAYSCALE if image.ndim == 2 else cv2.IMREAD_COLOR
    return np.asarray(cv2.imdecode(encoded, flag), np.uint8)


def _face_box(image: Image, landmarks: Landmarks) -> tuple[float, float, float, float]:
    """(x_min, y_min, x_max, y_max): the landmarks' box, or the fixed box (the middle third of
    the width, from 0.2 to 0.75 of the height) without landmarks."""
    height, width = image.shape[:2]
    if landmarks is None:
        return width / 3.0, 0.2 * height, 2.0 * width / 3.0, 0.75 * height
    low, high = landmarks[:, :2].min(axis=0), landmarks[:, :2].max(axis=0)
    return float(low[0]), float(low[1]), float(high[0]), float(high[1])


def low_resolution(
    image: Image,
    rng: np.random.Generator,
    landmarks: Landmarks = None,
    *,
    face_width_px: float = 60.0,
) -> Image:
    """A far or cheap camera: the whole image scaled down (area averaging) so that the face's
    box is `face_width_px` wide (`rng` unused). Never scaled up."""
    import cv2

    x_min, _, x_max, _ = _face_box(image, landmarks)
    scale = min(1.0, face_width_px / max(x_max - x_min, 1.0))
    height, width = image.shape[:2]
    size = (max(1, round(width * scale)), max(1, round(height * scale)))
    return np.asarray(cv2.resize(image, size, interpolation=cv2.INTER_AREA), np.uint8)


def _eye_lenses(image: Image, landmarks: Landmarks) -> list[tuple[tuple[float, float], float]]:
    """(centre, half width) of each eye: between its corners, or fixed in the fixed face box."""
    if landmarks is None:
        x_min, y_min, x_max, y_max = _face_box(image, None)
        width = x_max - x_min
        y_eye = y_min + 0.4 * (y_max - y_min)
        return [((x_min + f * width, y_eye), 0.16 * width) for f in (0.3, 0.7)]
    lenses = []
    for eye in (RIGHT_EYE, LEFT_EYE):
        outer, inner = landmarks[eye.outer, :2], landmarks[eye.inner, :2]
        centre = (outer + inner) / 2.0
        lenses.append(((float(centre[0]), float(centre[1])), float(np.hypot(*(outer - inner)))))
    return lenses


def sunglasses(
    image: Image,
    rng: np.random.Generator,
    landmarks: Landmarks = None,
    *,
    lens_level: float = 25.0,
    lens_scale: float = 0.8,
    lens_aspect: float = 0.7,
) -> Image:
    """Dark sunglasses: over each eye a filled ellipse of grey `lens_level` (+-5 levels of noise)
    centred between the eye's corners, half as wide as `lens_scale` times the corner distance
    (twice that, about a lens, across) and `lens_aspect` as high, along the eye line; a bridge
    joins them."""
    import cv2

    lenses = _eye_lenses(image, landmarks)
    (x0, y0), _ = lenses[0]
    (x1, y1), _ = lenses[1]
    angle = float(np.degrees(np.arctan2(y1 - y0, x1 - x0)))
    region = np.zeros(image.shape[:2], np.uint8)
    for (x, y), corner_distance in lenses:
        axes = (
            max(1, round(lens_scale * corner_distance)),
            max(1, round(lens_scale * lens_aspect * corner_distance)),
        )
        cv2.ellipse(region, (round(x), round(y)), axes, angle, 0, 360, 255, -1, cv2.LINE_AA)
    bridge = max(1, round(0.1 * lenses[0][1]))
    cv2.line(region, (round(x0), round(y0)), (round(x1), round(y1)), 255, bridge, cv2.LINE_AA)
    return _cover(image, region, lens_level, 5.0, rng)


def _cover(
    image: Image, region: Image, level: float, noise_std: float, rng: np.random.Generator
) -> Image:
    """`image` with `region` (0-255, anti-aliased edges) covered by grey `level` plus Gaussian
    noise of `noise_std` levels."""
    cover = level + rng.normal(0.0, noise_std, image.shape)
    weight = region.astype(np.float32) / 255.0
    if image.ndim == 3:
        weight = weight[:, :, None]
    return _to_uint8(weight * cover + (1.0 - weight) * image)


def face_mask(
    image: Image,
    rng: np.random.Generator,
    landmarks: Landmarks = None,
    *,
    mask_level: float = 215.0,
    texture_std: float = 6.0,
) -> Image:
    """A medical mask (or a hand) over the lower face: the convex hull of the face-oval
    landmarks below the nose ridge (landmark 195) and the nose tip, filled with grey
    `mask_level` plus Gaussian texture of `texture_std` levels; in the fixed face box, its lower
    45 %."""
    import cv2

    if landmarks is None:
        x_min, y_min, x_max, y_max = _face_box(image, None)
        top = y_min + 0.55 * (y_max - y_min)
        corners = [(x_min, top), (x_max, top), (x_max, y_max), (x_min, y_max)]
        points = np.array(corners, np.float32)
    else:
        ridge_y = landmarks[NOSE_RIDGE, 1]
        oval = landmarks[list(FACE_OVAL), :2]
        below = oval[oval[:, 1] >= ridge_y]
        points = np.vstack([below, landmarks[[NOSE_RIDGE, NOSE_TIP], :2]]).astype(np.float32)
    hull = cv2.convexHull(np.rint(points).astype(np.int32))
    region = np.zeros(image.shape[:2], np.uint8)
    cv2.fillConvexPoly(region, hull, 255, cv2.LINE_AA)
    return _cover(image, region, mask_level, texture_std, rng)


Transform = Callable[..., Image]
"""`transform(image, rng, landmarks, **parameters)`: a condition with its keyword parameters."""


def _plain(function: Callable[..., Image]) -> Transform:
    def transform(
        image: Image, rng: np.random.Generator, landmarks: Landmarks, **parameters: Any
    ) -> Image:
        return function(image, rng, **parameters)

    transform.__doc__ = function.__doc__
    return transform


_FUNCTIONS: dict[str, Callable[..., Image]] = {
    "ir_grey": ir_grey,
    "dark": dark_cabin,
    "glare": bright_glare,
    "motion_blur": motion_blur,
    "jpeg": jpeg_compression,
    "low_res": low_resolution,
    "sunglasses": sunglasses,
    "mask": face_mask,
}
NEEDS_LANDMARKS = frozenset({"low_res", "sunglasses", "mask"})
"""Conditions drawn from the clean image's face."""
CONDITIONS: dict[str, Transform] = {
    name: function if name in NEEDS_LANDMARKS else _plain(function)
    for name, function in _FUNCTIONS.items()
}
"""The suite's conditions by name, in the table's order (`clean` is the image as it is)."""


def condition_parameters(name: str) -> dict[str, float | int]:
    """The keyword parameters of condition `name` and their defaults (the suite's values)."""
    import inspect

    signature = inspect.signature(_FUNCTIONS[name])
    return {
        parameter.name: parameter.default
        for parameter in signature.parameters.values()
        if parameter.kind is inspect.Parameter.KEYWORD_ONLY
    }


def parse_condition(text: str) -> tuple[str, dict[str, float | int]]:
    """A condition's name and the parameters it sets: `ir_grey` or, with other values than the
    suite's, `ir_grey:noise_std=9,contrast=0.3` (a parameter whose default is a whole number
    takes a whole number).

    Raises ValueError naming what is known for an unknown condition or parameter or a bad value.
    """
    name, _, settings = text.partition(":")
    if name not in CONDITIONS:
        known = ", ".join([CLEAN, *CONDITIONS])
        raise ValueError(f"unknown condition {name!r}; expected one of {known}, all")
    defaults = condition_parameters(name)
    parameters: dict[str, float | int] = {}
    for setting in filter(None, settings.split(",")):
        key, equals, value = setting.partition("=")
        if key not in defaults or not equals:
            raise ValueError(
                f"condition {name}: expected PARAMETER=VALUE with a parameter among "
                f"{', '.join(defaults)}, found {setting!r}"
            )
        try:
            number = float(value)
            whole = isinstance(defaults[key], int)
            if whole and not number.is_integer():
                raise ValueError
            parameters[key] = int(number) if whole else number
        except ValueError:
            kind = "a whole number" if isinstance(defaults[key], int) else "a number"
            raise ValueError(f"condition {name}: {key} must be {kind}, found {value!r}") from None
    return name, parameters


def condition_names(requested: list[str]) -> list[str]:
    """The conditions to run, in the suite's order, `clean` first: `all` means every one; a
    condition with parameters (`parse_condition`) after the plain one.

    Raises ValueError (`parse_condition`'s) for an unknown condition or parameter.
    """
    known = [CLEAN, *CONDITIONS]
    chosen: set[str] = {CLEAN}
    for text in requested:
        if text == "all":
            chosen.update(known)
        elif text != CLEAN:
            parse_condition(text)
            chosen.add(text)
    return sorted(chosen, key=lambda text: (known.index(text.partition(":")[0]), text))


def apply_condition(
    name: str, image: Image, landmarks: Landmarks, file: str, seed: int = SEED
) -> Image:
    """`image` under condition `name` (`clean`: unchanged; parameters as `parse_condition`
    reads them), with the generator seeded from `seed`, the condition's plain name and `file`
    (a stable name of the image): the same noise whatever the parameters."""
    if name == CLEAN:
        return image
    condition, parameters = parse_condition(name)
    key = zlib.crc32(f"{condition}\0{file}".encode())
    generator = np.random.default_rng([seed, key])
    return CONDITIONS[condition](image, generator, landmarks, **parameters)
