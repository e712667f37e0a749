"""The held-up rule on the classifier's vector: a hand raised beside or below a face seen from the
front is phone use; not from the side, not pointing down, not on the face, not too low."""

from __future__ import annotations

import numpy as np
import pytest

from roadgaze.phone.features import FEATURES
from roadgaze.phone.held_up import held_up, held_up_rows, held_up_slots


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
