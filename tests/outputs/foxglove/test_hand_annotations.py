"""The hands on the recording's camera annotations: each hand's skeleton where it is (scaled
with the image) in its side's colour, red with a PHONE label for the hand holding a phone,
nothing while the hand stage is off."""

from __future__ import annotations

from typing import Any

import numpy as np
from foxglove.messages import ImageAnnotations, PointsAnnotationType

from fakes import record_of
from roadgaze.capture.mcap_images import protobuf_class
from roadgaze.outputs.annotate_hands import HAND_CONNECTIONS
from roadgaze.outputs.foxglove.channels import face_annotations
from roadgaze.types import Hand, HandSide, PhoneJudgement, PhonePose, PoseSample

LANDMARKS = np.column_stack((100.0 + 2 * np.arange(21), 200.0 - 3 * np.arange(21), np.zeros(21)))
LEFT = Hand(HandSide.LEFT, 0.9, 0.95, LANDMARKS.astype(np.float32), (100.0, 140.0, 140.0, 200.0))
SHIFTED = LANDMARKS + np.array([200.0, 0.0, 0.0])
RIGHT = Hand(HandSide.RIGHT, 0.9, 0.88, SHIFTED.astype(np.float32), (300.0, 140.0, 340.0, 200.0))
PHONE = PhoneJudgement(True, 0.7, HandSide.RIGHT, PhonePose.HELD_UP)


def annotations_of(hands: tuple[Hand, ...] | None, phone: PhoneJudgement | None) -> Any:
    """The frame's annotations at half scale, decoded as a recording's reader decodes them."""
    sample = PoseSample(1.0, 30, False, None, None, None, None, None, 0, hands=hands, phone=phone)
    message = face_annotations(record_of(sample), 1_000_000_000, 0.5, with_landmarks=False)
    schema = ImageAnnotations.get_schema()
    return protobuf_class(schema.name, schema.data)(message.encode())


def test_each_hand_is_a_line_list_of_its_skeleton_with_its_label() -> None:
    annotations = annotations_of((LEFT, RIGHT), PHONE)
    skeletons = [p for p in annotations.points if p.type == PointsAnnotationType.LineList]
    assert len(skeletons) == 2
    left, right = skeletons
    expected = 0.5 * LANDMARKS[[i for pair in HAND_CONNECTIONS for i in pair], :2]
    assert np.allclose([(point.x, point.y) for point in left.points], expected)
    assert left.outline_color.b > 0.9 and left.outline_color.r < 0.2  # blue: the left hand
    assert right.outline_color.r > 0.85 and right.outline_color.g < 0.2  # red: holds the phone
    labels = [text.text for text in annotations.texts]
    assert "left hand 0.95" in labels and "right hand 0.88  PHONE" in labels


def test_nothing_of_the_hands_while_the_hand_stage_is_off() -> None:
    off = annotations_of(None, None)
    none_found = annotations_of((), PhoneJudgement(False, 0.1))
    for drawn in (off, none_found):
        assert not [p for p in drawn.points if p.type == PointsAnnotationType.LineList]
        assert not [t for t in drawn.texts if "hand" in t.text]
