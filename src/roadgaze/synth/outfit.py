"""What the driver wears and what the camera meets, by name: the conditions a scenario renders.

A condition is one of `CONDITIONS`. Worn ones dress the face (`Outfit`): paint on the skin under
the eyes or over them (`roadgaze.synth.layers`) and things drawn on each frame from the turned
mesh (glasses, a cap, a beard's hanging part). `hand_at_12` is placed by camera mounting
(`roadgaze.synth.occluders`), a phone held up (`phone_wheel`, `phone_windscreen`,
`phone_cluster`) from the eyes (`roadgaze.synth.phone_hand`), `night` changes the whole picture
(`roadgaze.synth.effects.night`) and `talking` moves the jaw
(`roadgaze.synth.mouth.speech_track`); the conformance scenarios apply those
(`roadgaze.conformance.clips`). Everything is seeded: the same driver wears
the same beard in every scenario.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from roadgaze.errors import ConfigError
from roadgaze.synth.eyes import EyeRenderer, EyeState
from roadgaze.synth.face_cover import MaskBelowChin, face_mask, fringe, lash_makeup
from roadgaze.synth.facial_hair import BeardBelowChin, beard, stubble
from roadgaze.synth.layers import Layer, stack
from roadgaze.synth.renderer import FaceRenderer, ImageBGR
from roadgaze.synth.wearables import CAP, CLEAR, DARK, HAT, brim_shade, glasses, headwear


class FrameItem(Protocol):
    """Something drawn on a rendered frame from the turned mesh."""

    def __call__(
        self,
        frame: ImageBGR,
        renderer: FaceRenderer,
        yaw_deg: float,
        pitch_deg: float,
        mouth_open: float = 0.0,
    ) -> ImageBGR: ...


@dataclass(frozen=True, slots=True)
class Dress:
    """How one worn thing is rendered."""

    under: Layer | None = None
    """Painted on the skin the eyes are cut from (it closes with the lids)."""
    over: Layer | None = None
    """Painted over the drawn eyes."""
    item: FrameItem | None = None
    hides_mouth: bool = False


def _on_frame(draw: Callable[..., ImageBGR], **options: object) -> FrameItem:
    def item(
        frame: ImageBGR,
        renderer: FaceRenderer,
        yaw_deg: float,
        pitch_deg: float,
        mouth_open: float = 0.0,
    ) -> ImageBGR:
        return draw(frame, renderer, yaw_deg, pitch_deg, **options)

    return item


Dresser = Callable[[EyeRenderer, np.random.Generator], Dress]
WORN: dict[str, Dresser] = {
    "clear_sunglasses": lambda r, g: Dress(item=_on_frame(glasses, lenses=CLEAR)),
    "dark_sunglasses": lambda r, g: Dress(item=_on_frame(glasses, lenses=DARK)),
    "stubble": lambda r, g: Dress(over=stubble(r, g)),
    "beard": lambda r, g: Dress(over=beard(r, g), item=BeardBelowChin(g)),
    "mask": lambda r, g: Dress(over=face_mask(r, g), item=MaskBelowChin(), hides_mouth=True),
    "cap": lambda r, g: Dress(under=brim_shade(r), item=_on_frame(headwear, wear=CAP)),
    "hat": lambda r, g: Dress(under=brim_shade(r), item=_on_frame(headwear, wear=HAT)),
    "fringe": lambda r, g: Dress(over=fringe(r, g)),
    "eyelash_makeup": lambda r, g: Dress(under=lash_makeup(r, g)),
}
"""Worn things, each built once per face."""
CONDITIONS: dict[str, str] = {
    "night": "an infrared cabin camera at night: grey, flat, noisy",
    "clear_sunglasses": "light sunglasses (75 % transmission): the eyes visible through them",
    "dark_sunglasses": "dark sunglasses (6 % transmission): the eyes hidden",
    "stubble": "short facial hair: a few days' stubble on the jaw, chin and upper lip",
    "beard": "long facial hair: a full dark beard, hanging 4 cm below the chin",
    "mask": "a surgical face mask from the nose bridge to under the chin",
    "talking": "the mouth opening and closing at 3-5 syllables a second",
    "cap": "a cap worn low: a 7 cm brim above the brows",
    "hat": "a hat with a 6 cm brim all round",
    "fringe": "a hair fringe hanging over the eyes",
    "eyelash_makeup": "thick eyeliner and mascara on the lashes",
    "hand_at_12": "a hand gripping the top of the wheel, between the camera and the face",
    "phone_wheel": "a phone held up in the outer hand at the wheel (9-11 or 1-3 o'clock)",
    "phone_windscreen": "a phone held up in the outer hand beside the face, in view of the road",
    "phone_cluster": "a phone held up in the outer hand over the wheel's centre, in front of the "
    "instrument cluster",
}
"""Every condition a scenario can render, with what it shows."""
SEED = 11


def check_conditions(names: Sequence[str]) -> None:
    """Raise ConfigError naming the known conditions when one of `names` is unknown."""
    unknown = [name for name in names if name not in CONDITIONS]
    if unknown:
        raise ConfigError(
            f"unknown condition {', '.join(unknown)}; expected any of {', '.join(CONDITIONS)}"
        )


class Outfit:
    """A face dressed in the worn conditions of `names` (others are ignored here), rendered."""

    def __init__(self, renderer: EyeRenderer, names: Sequence[str], seed: int = SEED) -> None:
        check_conditions(names)
        dresses = [
            WORN[name](renderer, np.random.default_rng([seed, zlib.crc32(name.encode())]))
            for name in WORN
            if name in names
        ]
        under = stack(d.under for d in dresses if d.under is not None)
        over = stack(d.over for d in dresses if d.over is not None)
        self.renderer = renderer
        if under is not None or over is not None:
            texture = renderer.base_texture if under is None else under.over(renderer.base_texture)
            self.renderer = renderer.repainted(texture, over)
        self.renderer.show_mouth_inside = not any(d.hides_mouth for d in dresses)
        self.items = tuple(d.item for d in dresses if d.item is not None)

    def render(
        self, yaw_deg: float, pitch_deg: float, state: EyeState, mouth_open: float = 0.0
    ) -> ImageBGR:
        """The dressed face at this head pose, eyes and jaw."""
        frame = self.renderer.render_eyes(yaw_deg, pitch_deg, state, mouth_open)
        for item in self.items:
            frame = item(frame, self.renderer, yaw_deg, pitch_deg, mouth_open)
        return frame
