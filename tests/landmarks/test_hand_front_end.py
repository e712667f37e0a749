"""The hand stage's front end: which frames it lifts and how (closed forms on made-up frames),
then the real hand models on the near-infrared picture: a rendered phone hand at night and State
Farm drivers put under the condition suite's `ir_grey`."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from repo_paths import STATEFARM
from roadgaze.config import Config
from roadgaze.landmarks.front_end import FLAT_SPREAD, NOISY_LEVELS, assess
from roadgaze.landmarks.hands.front_end import enhance_for_hands, for_hands
from roadgaze.landmarks.hands.stage import HandStage


def _scene(rng: np.random.Generator, contrast: float, noise: float) -> np.ndarray:
    """A grey 240x320 frame: a bright block and a dark bar on mid grey, flattened by
    `contrast` about 120, with Gaussian noise of `noise` levels."""
    frame = np.full((240, 320), 128.0)
    frame[60:180, 80:160] = 230.0
    frame[100:140, 200:300] = 20.0
    flat = 120.0 + contrast * (frame - frame.mean()) + rng.normal(0.0, noise, frame.shape)
    return np.asarray(np.clip(np.rint(flat), 0, 255), np.uint8)


def test_a_frame_of_full_spread_goes_to_the_models_as_it_came() -> None:
    rng = np.random.default_rng(1)
    sharp = _scene(rng, 1.0, 2.0)
    assert assess(sharp).spread >= FLAT_SPREAD
    assert for_hands(sharp, "auto") is sharp
    # A dark frame of full spread (the face's front end would curve it) is left alone too.
    dark = np.asarray(np.clip(sharp.astype(np.int16) - 75, 0, 255), np.uint8)
    dark[0, :] = 255
    assert assess(dark).needs_curve and assess(dark).spread >= FLAT_SPREAD
    assert for_hands(dark, "auto") is dark
    flat = _scene(rng, 0.4, 6.0)
    assert for_hands(flat, "off") is flat
    assert for_hands(sharp, "always") is not sharp


def test_a_flat_noisy_grey_frame_is_stretched_and_smoothed() -> None:
    flat = _scene(np.random.default_rng(2), 0.4, 6.0)
    before = assess(flat, noise=True)
    assert before.spread < FLAT_SPREAD and before.noise >= NOISY_LEVELS
    lifted = for_hands(flat, "auto")
    assert lifted.ndim == 2 and lifted.shape == flat.shape
    after = assess(lifted, noise=True)
    assert after.spread > 200.0  # the 1st-99th percentile range stretched to 0-255
    # two passes of the bilateral filter: the noise falls, relative to the contrast, by more
    # than half, and the block's edge stays a step (not a ramp)
    assert after.relative_noise < 0.5 * before.relative_noise
    row = lifted[120].astype(float)
    assert row[84] - row[76] > 0.6 * (row[120] - row[40])


def test_a_grey_picture_in_three_equal_channels_is_lifted_as_one_grey_channel() -> None:
    grey = _scene(np.random.default_rng(3), 0.4, 6.0)
    three = np.repeat(grey[:, :, None], 3, axis=2)
    np.testing.assert_array_equal(enhance_for_hands(three), enhance_for_hands(grey))


def test_a_flat_colour_frame_keeps_its_colour() -> None:
    """A skin-coloured block on a dark cabin (the suite's `dark`: a flat, noisy colour frame)
    comes back brighter, in colour, with its channels in the same proportions (a channel lifted
    beyond 255 would clip: here the window is the brightest part)."""
    rng = np.random.default_rng(4)
    frame = np.full((240, 320, 3), (40.0, 50.0, 60.0))
    frame[60:180, 80:160] = (90.0, 130.0, 190.0)  # BGR: a light skin
    frame[20:60, 200:300] = 250.0  # a window, the brightest part
    dark = np.asarray(np.clip(np.rint(0.15 * frame + rng.normal(0, 3, frame.shape)), 0, 255))
    dark = dark.astype(np.uint8)
    lifted = for_hands(dark, "auto")
    assert lifted.shape == dark.shape
    skin = lifted[80:160, 100:140].reshape(-1, 3).mean(axis=0)
    assert skin.mean() > 3 * dark[80:160, 100:140].mean()
    np.testing.assert_allclose(skin / skin[2], np.array([90, 130, 190]) / 190, atol=0.06)


# --- the real hand models ---------------------------------------------------------------------


@pytest.fixture(scope="module")
def stages() -> dict[str, HandStage]:
    """The hand stage without and with its front end (the body off: hands only)."""
    built = {}
    for mode in ("off", "auto"):
        config = Config()
        hands = config.hands.model_copy(update={"enhance": mode, "body": False})
        stage = HandStage.from_config(config.model_copy(update={"hands": hands}))
        if stage is None:
            pytest.skip("the hand models are missing (roadgaze model fetch hands)")
        built[mode] = stage
    yield built
    for stage in built.values():
        stage.close()


@pytest.mark.slow
def test_the_rendered_phone_hand_is_found_at_night(stages: dict[str, HandStage]) -> None:
    """`phone_wheel_70` under `night` (the suite's `ir_grey`): without the front end the palm
    detector finds the hand held up in none of the stage's runs; with it, in every run from the
    first after the phone comes up (3.3 s) until it goes down (7 s)."""
    from roadgaze.conformance.clips import ScenarioRenderer
    from roadgaze.conformance.dossier_general import under
    from roadgaze.conformance.matrix import scenario_matrix
    from roadgaze.synth import EyeRenderer, load_photo

    config = Config()
    monitor = config.monitor.model_copy(update={"protocol": "euroncap"})
    scenario = next(s for s in scenario_matrix(monitor) if s.name == "phone_wheel_70")
    renderer = ScenarioRenderer(EyeRenderer(load_photo(), (320, 320), eyeball_at_rest=True), 15.0)
    frames = list(itertools.islice(renderer.frames(under("night")(scenario)), 0, 120, 5))
    found = {}
    for mode, stage in stages.items():
        found[mode] = [bool(stage.run(frame, i / 3.0).hands) for i, frame in enumerate(frames)]
    assert not any(found["off"])
    assert all(found["auto"][10:21])  # 3.33-6.67 s, the stage's runs every 1/3 s here


@pytest.mark.slow
def test_state_farm_drivers_under_ir_grey_have_their_hands_found(
    stages: dict[str, HandStage],
) -> None:
    """Every 40th development image under `ir_grey` (42 images): hands in none or almost none
    as they come, in most with the front end (docs/phone.md, "At night")."""
    if not (STATEFARM / "ground_truth.csv").is_file():
        pytest.skip(f"no State Farm development images at {STATEFARM}")
    from roadgaze.evaluation.conditions import apply_condition
    from roadgaze.evaluation.images import read_image
    from roadgaze.evaluation.phone import load_phone_truth

    truths = load_phone_truth(STATEFARM)[::40]
    counts = dict.fromkeys(stages, 0)
    for truth in truths:
        image = apply_condition("ir_grey", read_image(STATEFARM / truth.file), None, truth.file)
        for mode, stage in stages.items():
            counts[mode] += len(stage.run(image, None).hands)
    assert counts["off"] <= 1
    assert counts["auto"] >= 0.4 * len(truths)
