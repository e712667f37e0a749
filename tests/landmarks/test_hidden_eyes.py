"""The image checks of hidden eyes on rendered faces, through the real landmarker: a hair fringe
hides the eyes (strands across them); a cap's brim, eyelash makeup and clear sunglasses leave
them seen (no evaluation data needed)."""

from __future__ import annotations

import pytest

from roadgaze.config import Config
from roadgaze.landmarks import Landmarker
from roadgaze.landmarks.eyes import driver_eyes
from roadgaze.synth import EyeRenderer, EyeState, load_photo
from roadgaze.synth.outfit import Outfit
from roadgaze.types import EyesFeatures


@pytest.fixture(scope="module")
def measured() -> dict[str, EyesFeatures | None]:
    config = Config()
    renderer = EyeRenderer(load_photo(), (320, 320), eyeball_at_rest=True)
    worn = ((), ("fringe",), ("cap",), ("eyelash_makeup",), ("clear_sunglasses",))
    result: dict[str, EyesFeatures | None] = {}
    with Landmarker.from_config(config) as landmarker:
        for names in worn:
            image = Outfit(renderer, names).render(0.0, 0.0, EyeState())
            face = landmarker.detect(image).driver
            yaw = None if face is None else face.mediapipe_yaw_deg
            result[names[0] if names else "bare"] = driver_eyes(face, yaw, config.eyes)
    return result


@pytest.mark.slow
def test_a_fringe_hides_the_eyes_and_what_leaves_them_in_view_does_not(
    measured: dict[str, EyesFeatures | None],
) -> None:
    fringe = measured["fringe"]
    assert fringe is not None and fringe.occluded and fringe.occluded_by == "strands"
    for name in ("bare", "cap", "eyelash_makeup", "clear_sunglasses"):
        eyes = measured[name]
        assert eyes is not None and not eyes.occluded, name
        assert eyes.gaze_available, name
