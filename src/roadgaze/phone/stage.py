"""The phone step of the loop: the hand stage on the frame, then the judgement on the record.

`PhoneStage.from_config(config)` is None when `[hands] enabled` is false or the hand models are
missing (one warning: phone detection is off; the record's hand and phone fields stay null).
`apply(frame, sample)` adds the hands and the judgement to the pose sample; between the hand
stage's runs (`[hands] interval_s`) the last hands and judgement are carried over.

A hand found in front of both eyes hides them (`hand_over_eyes`): the face landmarker still
places a face, eyes and lids on a fist gripping the top of the wheel in front of the camera
(read as closed eyes), so the sample's eyes are marked hidden by a hand (unavailable, never
closed): the monitor then tells the driver it cannot see them (`non_functional`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from roadgaze.config import Config
from roadgaze.landmarks.eye_landmarks import EYES
from roadgaze.landmarks.hands.stage import HandStage
from roadgaze.phone.judge import judge
from roadgaze.phone.model import PhoneModel, load_model
from roadgaze.types import FaceFeatures, Frame, Hand, PhoneJudgement, PoseSample

HAND_REACH = 0.25
"""A hand's outline reaches this fraction of its landmarks' box beyond the box on every side:
the landmarks are the joints, inside the hand, and a fist seen knuckles-first hides much more
than they span. roadgaze's choice: with it the eyes placed on a rendered fist at the top of the
wheel lie inside the hand in 195 of 205 frames (the rest before the hand stage first ran),
with none of the State Farm drivers' faces, phones at the ear and hands in the hair included
(docs/monitor.md, "Non-functional notices")."""


def hand_over_eyes(hands: Sequence[Hand], face: FaceFeatures | None) -> bool:
    """Whether one hand's outline (its box grown by `HAND_REACH`) holds both iris centres."""
    if face is None or face.landmarks_px.shape[0] <= max(e.iris_center for e in EYES):
        return False
    irises = [face.landmarks_px[e.iris_center] for e in EYES]
    for hand in hands:
        x0, y0, x1, y1 = hand.box_px
        grow_x, grow_y = HAND_REACH * (x1 - x0), HAND_REACH * (y1 - y0)
        if all(
            x0 - grow_x <= float(x) <= x1 + grow_x and y0 - grow_y <= float(y) <= y1 + grow_y
            for x, y, *_ in irises
        ):
            return True
    return False


class PhoneStage:
    """Hands and the phone judgement for one stream (see the module docstring)."""

    def __init__(self, hands: HandStage, model: PhoneModel, threshold: float | None) -> None:
        self.hands = hands
        self._model = model
        self._threshold = threshold
        self._last: PhoneJudgement | None = None

    @classmethod
    def from_config(cls, config: Config) -> PhoneStage | None:
        hands = HandStage.from_config(config)
        if hands is None:
            return None
        return cls(hands, load_model(), config.hands.phone_threshold)

    def apply(self, frame: Frame, sample: PoseSample) -> PoseSample:
        """`sample` with this frame's hands and phone judgement."""
        found = self.hands.run(frame.image, frame.t_s)
        if found.fresh or self._last is None:
            body = found.body_arrays
            self._last = judge(
                found.hands, sample.features, found.size, self._model, self._threshold, body
            )
        eyes = sample.eyes
        if eyes is not None and hand_over_eyes(found.hands, sample.features):
            eyes = replace(eyes, occluded=True, occluded_by="hand")
        return replace(sample, hands=found.hands, phone=self._last, eyes=eyes)

    def close(self) -> None:
        self.hands.close()
