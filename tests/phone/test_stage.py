"""The phone step's hand check: a hand in front of both eyes hides them (the geometry, then a
rendered fist through the real landmarkers)."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from fakes import face_at
from roadgaze.config import Config
from roadgaze.conformance.clips import ScenarioRenderer
from roadgaze.conformance.notices import notice_scenarios
from roadgaze.landmarks import Landmarker
from roadgaze.landmarks.eye_landmarks import LEFT_EYE, RIGHT_EYE
from roadgaze.landmarks.hands.stage import HandStage
from roadgaze.phone.stage import HAND_REACH, hand_over_eyes
from roadgaze.synth import EyeRenderer, load_photo
from roadgaze.types import Hand, HandSide


def _face_with_irises(right: tuple[float, float], left: tuple[float, float]) -> object:
    points = np.zeros((478, 3), np.float32)
    points[RIGHT_EYE.iris_center, :2] = right
    points[LEFT_EYE.iris_center, :2] = left
    return dataclasses.replace(face_at(0.0), landmarks_px=points)


def _hand(box: tuple[float, float, float, float]) -> Hand:
    return Hand(HandSide.RIGHT, 0.9, 0.9, np.zeros((21, 3), np.float32), box)


def test_a_hand_hides_the_eyes_only_when_its_outline_holds_both() -> None:
    face = _face_with_irises((136.0, 99.0), (170.0, 99.0))
    # A fist gripping the wheel's top in front of the camera (as the hand model boxes the
    # rendered one): the joints' box starts just below the eyes the landmarker put on it.
    fist = _hand((118.0, 102.0, 191.0, 170.0))
    assert hand_over_eyes([fist], face)  # type: ignore[arg-type]
    assert HAND_REACH * (170.0 - 102.0) > 102.0 - 99.0
    # A hand at the ear, or one below the chin, leaves an eye free.
    at_ear = _hand((40.0, 60.0, 110.0, 160.0))
    below = _hand((110.0, 160.0, 200.0, 230.0))
    assert not hand_over_eyes([at_ear, below], face)  # type: ignore[arg-type]
    assert not hand_over_eyes([], face)  # type: ignore[arg-type]
    assert not hand_over_eyes([fist], None)
    assert not hand_over_eyes([fist], face_at(0.0))  # a source without MediaPipe's 478 points


@pytest.mark.slow
def test_a_rendered_fist_at_the_wheels_top_is_found_in_front_of_the_eyes() -> None:
    """The rendered hand of `notice_hand_at_12_70` (a camera on the steering column), through
    the real face landmarker and hand stage: the face found on the fist has both irises inside
    the hand; the bare face before it has no hand there."""
    config = Config()
    stage = HandStage.from_config(config)
    if stage is None:
        pytest.skip("the hand models are missing (roadgaze model fetch hands)")
    scenario = next(s for s in notice_scenarios(config.monitor) if "hand_at_12" in s.name)
    renderer = ScenarioRenderer(EyeRenderer(load_photo(), (320, 320), eyeball_at_rest=True), 15.0)
    frames = renderer.frames(scenario)
    bare = next(itertools.islice(frames, 15, None))  # 1 s: before the hand (from 3 s)
    fist = next(itertools.islice(frames, 75 - 16, None))  # 5 s
    try:
        with Landmarker.from_config(config) as landmarker:
            for image, expected in ((bare, False), (fist, True)):
                face = landmarker.detect(image).driver
                assert face is not None
                assert hand_over_eyes(stage.run(image, None).hands, face) is expected
    finally:
        stage.close()
