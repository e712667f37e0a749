"""The hands and the phone judgement on the annotated video: drawn where the hand is, in its
side's colour (red when it holds the phone), named in the text panel, absent while the hand stage
is off."""

from __future__ import annotations

import dataclasses

import numpy as np
import numpy.typing as npt

from fakes import record_of
from roadgaze.outputs import PANEL_LINES, annotate
from roadgaze.outputs.annotate_hands import (
    HAND_COLOURS_BGR,
    PHONE_HAND_BGR,
    hand_label,
    phone_line,
)
from roadgaze.types import FrameRecord, Hand, HandSide, PhoneJudgement, PhonePose, PoseSample


def hand_at(wrist_x: float, wrist_y: float, side: HandSide, score: float = 0.93) -> Hand:
    """An open hand, fingers up: the wrist, then four joints per finger (thumb to little finger),
    fingers 12 px apart, each joint 10 px above the last."""
    points = [(wrist_x, wrist_y, 0.0)]
    for finger in range(5):
        x = wrist_x - 24.0 + 12.0 * finger
        points += [(x, wrist_y - 20.0 - 10.0 * joint, -1.0) for joint in range(4)]
    landmarks = np.asarray(points, np.float32)
    box = (*landmarks[:, :2].min(axis=0).tolist(), *landmarks[:, :2].max(axis=0).tolist())
    return Hand(side, 0.97, score, landmarks, (box[0], box[1], box[2], box[3]))


LEFT = hand_at(100.0, 150.0, HandSide.LEFT)
RIGHT = hand_at(250.0, 150.0, HandSide.RIGHT, 0.88)
PHONE = PhoneJudgement(True, 0.82, HandSide.RIGHT, PhonePose.HELD_UP)
NO_PHONE = PhoneJudgement(False, 0.07)


def frame_record(hands: tuple[Hand, ...] | None, phone: PhoneJudgement | None) -> FrameRecord:
    sample = PoseSample(1.0, 30, False, None, None, None, None, None, 0, hands=hands, phone=phone)
    return record_of(sample)


def share_of(region: npt.NDArray[np.uint8], colour: tuple[int, int, int]) -> float:
    """The share of `region`'s pixels within 40 of `colour` in every channel."""
    close = np.abs(region.astype(int) - np.asarray(colour)).max(axis=2) <= 40
    return float(close.mean())


def test_each_hand_is_drawn_where_it_is_in_its_sides_colour_and_the_phone_hand_in_red() -> None:
    image = np.full((240, 320, 3), 60, np.uint8)
    canvas = annotate(image, frame_record((LEFT, RIGHT), PHONE))
    for hand, colour in ((LEFT, HAND_COLOURS_BGR[HandSide.LEFT]), (RIGHT, PHONE_HAND_BGR)):
        x_min, y_min, x_max, y_max = (round(v) for v in hand.box_px)
        inside = canvas[y_min : y_max + 1, x_min : x_max + 1]
        assert share_of(inside, colour) > 0.04  # the skeleton's lines (1 px at this size)
        assert share_of(inside, (255, 255, 255)) > 0.05  # the landmarks' dots
        label = canvas[y_min - 12 : y_min, x_min:x_max]  # the side's label above the box
        assert (label != 60).any(axis=2).mean() > 0.15
        assert share_of(label, colour) > 0.0
    between = canvas[100:155, 150:200]  # between the hands, above the text panel
    assert (between == 60).all()
    assert share_of(canvas, HAND_COLOURS_BGR[HandSide.RIGHT]) == 0.0  # the right hand is red


def test_nothing_of_the_hands_is_drawn_while_the_hand_stage_is_off() -> None:
    image = np.full((240, 320, 3), 60, np.uint8)
    off = annotate(image, frame_record(None, None))
    none_found = annotate(image, frame_record((), NO_PHONE))
    assert (off[40:150] == 60).all()  # no hands, no labels (below the gauge, above the panel)
    assert (none_found[40:150] == 60).all()
    assert not (off == none_found).all()  # the panel says the stage ran and found none


def test_the_panel_line_says_the_hands_and_the_phone_judgement() -> None:
    lines = [line(frame_record((LEFT, RIGHT), PHONE), None) for line in PANEL_LINES]
    assert (
        lines[-1] == "hands 2 (left 0.93, right 0.88)  phone YES  score 0.82  right hand, held up"
    )
    assert phone_line(frame_record((), NO_PHONE)) == "hands 0  phone no  score 0.07"
    unknown = PhoneJudgement(None, None)
    assert phone_line(frame_record((), unknown)) == "hands 0  phone UNKNOWN"
    assert phone_line(frame_record(None, None)) == ""
    record = frame_record((RIGHT,), PHONE)
    assert hand_label(RIGHT, True) == "right hand 0.88  PHONE"
    assert hand_label(LEFT) == "left hand 0.93"
    no_hand = dataclasses.replace(record.sample, phone=PhoneJudgement(True, 0.9))
    assert phone_line(record_of(no_hand)) == "hands 1 (right 0.88)  phone YES  score 0.90"
