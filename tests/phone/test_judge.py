"""The per-frame phone judgement from the record's hands and face."""

from __future__ import annotations

import numpy as np
import pytest

from roadgaze.phone.features import FEATURES, HAND_FEATURES, frame_vector, slots
from roadgaze.phone.judge import judge_box, phone_pose
from roadgaze.phone.model import PhoneModel
from roadgaze.types import Hand, HandSide, PhonePose

SIZE = (640, 480)


def _hand(side: HandSide, x_px: float, y_px: float, score: float = 0.9) -> Hand:
    points = np.zeros((21, 3), np.float32)
    rng = np.random.default_rng(int(x_px + y_px))
    points[:, :2] = rng.normal(0, 15, (21, 2)) + np.array([x_px, y_px])
    box = (
        float(points[:, 0].min()),
        float(points[:, 1].min()),
        float(points[:, 0].max()),
        float(points[:, 1].max()),
    )
    return Hand(side, 0.9, score, points, box)


def _model_reading(feature: str, above: float) -> PhoneModel:
    """A one-split model: phone use when `feature` > `above`."""
    index = FEATURES.index(feature)
    return PhoneModel.from_document(
        {
            "version": "test",
            "features": list(FEATURES),
            "threshold": 0.5,
            "baseline": 0.0,
            "trees": [
                {
                    "feature": [index, -1, -1],
                    "threshold": [above, 0, 0],
                    "left": [1, -1, -1],
                    "right": [2, -1, -1],
                    "value": [0, -5.0, 5.0],
                    "missing_left": [True, True, True],
                }
            ],
        },
        "test",
    )


def test_no_hand_and_no_face_cannot_be_judged() -> None:
    verdict = judge_box([], None, SIZE, _model_reading("hands", 0.5))
    assert verdict.phone_use is None and verdict.score is None


def test_a_face_without_hands_is_judged_and_names_no_hand() -> None:
    verdict = judge_box([], (300, 100, 380, 200), SIZE, _model_reading("hands", 0.5))
    assert verdict.phone_use is False and verdict.hand is None


def test_the_phone_hand_and_where_it_is_held() -> None:
    face = (300.0, 100.0, 380.0, 200.0)
    at_ear = _hand(HandSide.RIGHT, 400, 150)
    on_wheel = _hand(HandSide.LEFT, 150, 350)
    model = _model_reading("right_face_known", 0.5)  # fires on the right hand only
    verdict = judge_box([on_wheel, at_ear], face, SIZE, model)
    assert verdict.phone_use is True and verdict.score == pytest.approx(1 / (1 + np.exp(-5)))
    assert verdict.hand is HandSide.RIGHT and verdict.pose is PhonePose.EAR
    assert phone_pose(_hand(HandSide.LEFT, 320, 440), face, SIZE) is PhonePose.LAP
    assert phone_pose(_hand(HandSide.LEFT, 320, 300), face, SIZE) is PhonePose.HELD_UP
    assert phone_pose(_hand(HandSide.LEFT, 320, 300), None, SIZE) is PhonePose.HELD_UP


def test_slots_and_the_vector_layout() -> None:
    left, right = _hand(HandSide.LEFT, 100, 100), _hand(HandSide.LEFT, 500, 300, score=0.6)
    assert slots([right, left]) == (left, right)  # a second left hand takes the empty slot
    vector = frame_vector([left], None, SIZE)
    assert vector.shape == (len(FEATURES),)
    width = len(HAND_FEATURES)
    assert vector[width - 1] == 1.0 and not vector[width : 2 * width].any()  # right slot empty
    assert vector[0] == pytest.approx(left.landmarks_px[:, 0].mean() / 640, rel=1e-6)
    frame = vector[2 * width : 2 * width + 4].tolist()
    assert frame == [0.0, 1.0, 0.0, 0.0]  # no face: no head angles
    assert not vector[2 * width + 4 :].any()  # no body
