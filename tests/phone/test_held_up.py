"""The held-up rule on the classifier's vector: a hand raised beside or below a face seen from the
front is phone use; not from the side, not pointing down, not on the face, not too low."""

from __future__ import annotations

import numpy as np
import pytest

from roadgaze.phone.features import FEATURES
from roadgaze.phone.held_up import held_up, held_up_rows, held_up_slots
from roadgaze.phone.judge import judge_box
from roadgaze.phone.model import PhoneModel
from roadgaze.types import Hand, HandSide, PhonePose


def vector(**values: float) -> np.ndarray:
    """A frame with a face and one left hand held up beside its chin, `values` changed."""
    start = {
        "face": 1.0,
        "head_yaw_deg": 5.0,
        "left_present": 1.0,
        "left_face_known": 1.0,
        "left_direction_y": -0.97,
        "left_middle_reach": 2.4,
        "left_face_dx": 1.1,
        "left_face_dy": 1.3,
    }
    x = np.zeros(len(FEATURES))
    for name, value in (start | values).items():
        x[FEATURES.index(name)] = value
    return x


def test_a_hand_held_up_beside_the_face_seen_from_the_front() -> None:
    assert held_up_slots(vector()) == ("left",)
    assert held_up(vector(left_face_dx=-1.1))  # either side of the face


@pytest.mark.parametrize(
    "change",
    [
        {"face": 0.0},  # no face: where "beside the face" is, is not known
        {"head_yaw_deg": -40.0},  # a camera at the side: the classifier judges alone
        {"left_direction_y": -0.5},  # the fingers to the side
        {"left_middle_reach": 0.9},  # a fist
        {"left_face_dx": 0.3},  # on the face (a cup at the mouth, a hand at the eyes)
        {"left_face_dy": 0.0},  # at the eyes' height (hair, a hand at the ear)
        {"left_face_dy": 3.5},  # in the lap
        {"left_present": 0.0},
    ],
)
def test_not_held_up(change: dict[str, float]) -> None:
    assert not held_up(vector(**change))


def test_rows_with_nan_are_not_held_up() -> None:
    rows = np.vstack([vector(), np.full(len(FEATURES), np.nan), vector(head_yaw_deg=60.0)])
    assert held_up_rows(rows).tolist() == [True, False, False]


def _upright_hand(wrist_x: float, wrist_y: float, size: float) -> Hand:
    """21 points of an open hand, fingers straight up from the wrist (image pixels)."""
    points = np.zeros((21, 3), np.float32)
    points[0, :2] = (wrist_x, wrist_y)
    for finger, dx in enumerate((-0.5, -0.25, 0.0, 0.25, 0.5)):
        for joint in range(4):
            points[1 + 4 * finger + joint, :2] = (
                wrist_x + dx * size,
                wrist_y - (1.0 + 0.3 * joint) * size * (0.6 if finger == 0 else 1.0),
            )
    box = (
        float(points[:, 0].min()),
        float(points[:, 1].min()),
        float(points[:, 0].max()),
        float(points[:, 1].max()),
    )
    return Hand(HandSide.LEFT, 0.9, 0.95, points, box)


def test_the_judgement_says_held_up_whatever_the_classifier_scores() -> None:
    face = (280.0, 100.0, 360.0, 200.0)  # 80 px wide, centre (320, 150)
    hand = _upright_hand(420.0, 330.0, 40.0)  # beside and below the face, fingers up
    document = {"version": "test", "features": list(FEATURES), "threshold": 0.5, "trees": []}
    never = PhoneModel.from_document(document | {"baseline": -5.0}, "test")  # scores 0.007
    size = (640, 480)
    verdict = judge_box([hand], face, size, never, head_deg=(3.0, 0.0))
    assert verdict.phone_use is True and verdict.pose is PhonePose.HELD_UP
    assert verdict.hand is HandSide.LEFT and verdict.score is not None and verdict.score < 0.5
    from_the_side = judge_box([hand], face, size, never, head_deg=(50.0, 0.0))
    assert from_the_side.phone_use is False and from_the_side.pose is None
