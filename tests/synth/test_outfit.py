"""What the driver wears, rendered: each worn thing changes the part of the face it covers and
leaves the rest, follows the turned head, and is the same every time (seeded)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from roadgaze.errors import ConfigError
from roadgaze.landmarks.eye_contrast import polygon_mask
from roadgaze.landmarks.eye_landmarks import EYES
from roadgaze.synth import EyeRenderer, EyeState
from roadgaze.synth.facial_hair import BEARD_AREA, LIPS
from roadgaze.synth.outfit import CONDITIONS, WORN, Outfit, check_conditions

AHEAD = EyeState()


@pytest.fixture(scope="module")
def renderer() -> EyeRenderer:
    from roadgaze.synth import load_photo

    return EyeRenderer(load_photo(), (320, 320), eyeball_at_rest=True)


def grey(frame: Any) -> Any:
    return frame.astype(np.float64).mean(axis=2)


def region(renderer: EyeRenderer, indices: Any, yaw: float = 0.0, pitch: float = 0.0) -> Any:
    points = renderer.turned_points(yaw, pitch)[list(indices), :2]
    return polygon_mask(points, renderer.background.shape[:2])


def eyes_region(renderer: EyeRenderer, yaw: float = 0.0, pitch: float = 0.0) -> Any:
    return region(renderer, EYES[0].contour, yaw, pitch) | region(
        renderer, EYES[1].contour, yaw, pitch
    )


def worn(renderer: EyeRenderer, name: str, yaw: float = 0.0, pitch: float = 0.0) -> Any:
    return grey(Outfit(renderer, (name,)).render(yaw, pitch, AHEAD))


def test_every_condition_is_known_and_an_unknown_one_is_one_line() -> None:
    assert set(WORN) <= set(CONDITIONS)
    placed = {"night", "talking", "hand_at_12", "phone_wheel", "phone_windscreen", "phone_cluster"}
    assert placed == set(CONDITIONS) - set(WORN)
    with pytest.raises(ConfigError, match="unknown condition hood; expected any of night,"):
        check_conditions(("mask", "hood"))


@pytest.mark.parametrize("name", ["mask", "beard", "stubble"])
def test_the_lower_face_is_covered_and_the_eyes_untouched(renderer: EyeRenderer, name: str) -> None:
    plain, dressed = grey(renderer.render(0.0, 0.0)), worn(renderer, name)
    eyes = eyes_region(renderer)
    assert np.array_equal(plain[eyes], dressed[eyes])
    area = region(renderer, BEARD_AREA) & ~region(renderer, LIPS)
    changed = np.abs(plain - dressed) > 3.0
    assert changed[area].mean() > 0.85
    assert dressed[area].mean() < plain[area].mean() - 10.0 or name == "mask"


def test_a_mask_hides_the_mouth_a_beard_does_not(renderer: EyeRenderer) -> None:
    plain = grey(renderer.render(0.0, 0.0))
    lips = region(renderer, LIPS)
    bearded = worn(renderer, "beard")
    mask_bgr = Outfit(renderer, ("mask",)).render(0.0, 0.0, AHEAD).astype(np.int32)
    assert (mask_bgr[..., 0] > mask_bgr[..., 2] + 20)[lips].mean() > 0.95  # light blue, not lips
    assert (np.abs(bearded - plain) > 10.0)[lips].mean() < 0.2
    below_chin = np.zeros_like(lips)
    chin = renderer.mesh.points_px[152]
    below_chin[
        round(chin[1]) + 2 : round(chin[1]) + 12, round(chin[0]) - 3 : round(chin[0]) + 4
    ] = True
    assert bearded[below_chin].mean() < 80.0  # the beard hangs below the chin
    under = np.zeros_like(lips)
    under[round(chin[1]) + 1 : round(chin[1]) + 3, round(chin[0]) - 3 : round(chin[0]) + 4] = True
    assert (mask_bgr[..., 0] > mask_bgr[..., 2] + 20)[under].mean() > 0.9  # the mask goes under


@pytest.mark.parametrize(
    ("name", "kept", "behind"),
    [
        ("clear_sunglasses", (0.55, 1.2), 0.9),
        ("dark_sunglasses", (0.0, 0.25), 0.9),
        ("fringe", (0.0, 0.7), 0.75),
    ],
)
def test_what_covers_the_eyes_keeps_as_much_of_them_as_it_should(
    renderer: EyeRenderer, name: str, kept: tuple[float, float], behind: float
) -> None:
    """The contrast left inside the eye openings, as a share of the bare eyes': light lenses
    keep the eyes visible, dark ones and a fringe (with gaps between its strands) hide them;
    the mouth is left as it is."""
    plain, dressed = grey(renderer.render(0.0, 0.0)), worn(renderer, name)
    eyes = eyes_region(renderer)
    share = dressed[eyes].std() / plain[eyes].std()
    assert kept[0] <= share <= kept[1]
    assert (np.abs(dressed - plain) > 1.0)[eyes].mean() > behind
    lips = region(renderer, LIPS)
    assert np.array_equal(plain[lips], dressed[lips])


def test_glasses_follow_the_turned_head(renderer: EyeRenderer) -> None:
    for yaw, pitch in ((30.0, 0.0), (-25.0, -20.0)):
        plain = grey(renderer.render(yaw, pitch))
        dressed = worn(renderer, "clear_sunglasses", yaw, pitch)
        changed = np.abs(dressed - plain) > 3.0
        assert changed[eyes_region(renderer, yaw, pitch)].mean() > 0.9
        assert changed[region(renderer, LIPS, yaw, pitch)].mean() == 0.0


def test_eyelash_makeup_darkens_the_lids_and_closes_with_them(renderer: EyeRenderer) -> None:
    outfit = Outfit(renderer, ("eyelash_makeup",))
    plain, dressed = grey(renderer.render(0.0, 0.0)), grey(outfit.render(0.0, 0.0, AHEAD))
    upper_lid = np.zeros(plain.shape, dtype=bool)
    for eye in EYES:
        for x, y in renderer.mesh.points_px[list(eye.contour[2:7]), :2]:
            upper_lid[round(y) - 1 : round(y) + 1, round(x)] = True
    assert dressed[upper_lid].mean() < plain[upper_lid].mean() - 30.0
    assert dressed[upper_lid].mean() < 60.0
    lips = region(renderer, LIPS)
    assert np.array_equal(plain[lips], dressed[lips])
    closed = EyeState.both(openness=0.0)
    shut, shut_dressed = grey(renderer.render_eyes(0, 0, closed)), grey(outfit.render(0, 0, closed))
    assert shut_dressed[upper_lid].mean() > dressed[upper_lid].mean() + 20.0  # the line moved down
    assert np.abs(shut_dressed - shut)[eyes_region(renderer)].mean() > 5.0


@pytest.mark.parametrize("name", ["cap", "hat"])
def test_a_brim_shades_the_eyes_ahead_and_hides_them_looking_down(
    renderer: EyeRenderer, name: str
) -> None:
    plain, dressed = grey(renderer.render(0.0, 0.0)), worn(renderer, name)
    eyes = eyes_region(renderer)
    ratio = dressed[eyes].mean() / plain[eyes].mean()
    assert 0.5 < ratio < 0.8  # in the brim's shade
    assert dressed[eyes].std() / plain[eyes].std() > 0.4  # but seen
    down = (0.0, -30.0)
    plain_down, dressed_down = grey(renderer.render(*down)), worn(renderer, name, *down)
    eyes_down = eyes_region(renderer, *down)
    assert dressed_down[eyes_down].std() < 0.25 * plain_down[eyes_down].std()  # the brim


def test_outfits_are_the_same_every_time_and_follow_their_seed(renderer: EyeRenderer) -> None:
    names = ("beard", "fringe", "mask", "stubble")
    first = Outfit(renderer, names).render(10.0, -5.0, AHEAD)
    assert np.array_equal(first, Outfit(renderer, names).render(10.0, -5.0, AHEAD))
    assert not np.array_equal(first, Outfit(renderer, names, seed=3).render(10.0, -5.0, AHEAD))
    assert np.array_equal(Outfit(renderer, ()).render(0.0, 0.0, AHEAD), renderer.render(0.0, 0.0))
