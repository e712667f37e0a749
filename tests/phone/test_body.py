"""The upper body's part of the phone classifier's input, against closed forms, and a body
without hands judged by the classifier."""

from __future__ import annotations

import numpy as np
import pytest

from roadgaze.phone.body import ARM_FEATURES, ARMS, BODY_FEATURES, body_vector
from roadgaze.phone.features import FEATURES, frame_vector
from roadgaze.phone.judge import judge_box
from roadgaze.phone.model import PhoneModel

SIZE = (640, 480)


def _body(left_wrist: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """A body facing the camera: shoulders 0.2 apart at y 0.6, the nose 0.2 above their
    centre, ears beside the nose, elbows below the shoulders, the right wrist on the lap."""
    points = np.zeros((33, 3))
    points[0, :2] = (0.5, 0.4)  # nose
    points[7, :2], points[8, :2] = (0.55, 0.4), (0.45, 0.4)  # own left ear, right ear
    points[11, :2], points[12, :2] = (0.6, 0.6), (0.4, 0.6)  # shoulders
    points[13, :2], points[14, :2] = (0.6, 0.8), (0.4, 0.8)  # elbows
    points[15, :2], points[16, :2] = left_wrist, (0.4, 1.0)  # wrists
    return points, np.full(33, 0.9)


def _arm(vector: list[float], side: str) -> dict[str, float]:
    start = list(ARMS).index(side) * len(ARM_FEATURES)
    return dict(zip(ARM_FEATURES, vector[start : start + len(ARM_FEATURES)], strict=True))


def test_a_wrist_at_the_ear_is_near_it_and_the_arm_folded_in_the_bodys_scale() -> None:
    vector = body_vector(*_body(left_wrist=(0.6, 0.4)))  # the wrist just beside the left ear
    assert len(vector) == len(BODY_FEATURES)
    scale = 0.2 + 0.2 + 1e-6  # shoulder width plus the nose over the shoulders' centre
    left, right = _arm(vector, "left"), _arm(vector, "right")
    assert left["wrist_ear"] == pytest.approx(0.05 / scale)
    wrist = (left["wrist_shoulder_dx"], left["wrist_shoulder_dy"])
    assert wrist == pytest.approx((0, -0.2 / scale))
    assert left["elbow_bend"] == pytest.approx(1.0)  # forearm back along the upper arm
    assert right["elbow_bend"] == pytest.approx(-1.0)  # arm straight down to the lap
    assert right["wrist_ear"] == pytest.approx(np.hypot(0.05, 0.6) / scale)
    assert vector[-3:] == pytest.approx([1.0, -0.2 / scale, 0.2 / scale])


def test_no_body_or_a_broken_one_is_all_zeros() -> None:
    assert body_vector(None, None) == [0.0] * len(BODY_FEATURES)
    points, visibility = _body((0.6, 0.4))
    points[15, 0] = np.nan
    assert body_vector(points, visibility) == [0.0] * len(BODY_FEATURES)


def test_the_frame_vector_ends_with_the_body() -> None:
    body = _body((0.6, 0.4))
    vector = frame_vector([], None, SIZE, body=body)
    assert len(vector) == len(FEATURES)
    assert list(vector[-len(BODY_FEATURES) :]) == pytest.approx(body_vector(*body))
    assert not frame_vector([], None, SIZE)[-len(BODY_FEATURES) :].any()


def test_a_body_alone_is_judged_without_naming_a_hand() -> None:
    index = FEATURES.index("body_left_wrist_ear")
    model = PhoneModel.from_document(
        {
            "version": "test",
            "features": list(FEATURES),
            "threshold": 0.5,
            "baseline": 0.0,
            "trees": [
                {  # phone use when the left wrist is within 0.3 body scales of the ear
                    "feature": [index, -1, -1],
                    "threshold": [0.3, 0, 0],
                    "left": [1, -1, -1],
                    "right": [2, -1, -1],
                    "value": [0, 5.0, -5.0],
                    "missing_left": [True, True, True],
                }
            ],
        },
        "test",
    )
    at_ear = judge_box([], None, SIZE, model, body=_body((0.6, 0.4)))
    assert at_ear.phone_use is True and at_ear.hand is None and at_ear.pose is None
    on_wheel = judge_box([], None, SIZE, model, body=_body((0.6, 0.75)))
    assert on_wheel.phone_use is False
