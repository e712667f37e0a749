"""The phone step of the loop: the hand stage on the frame, then the judgement on the record.

`PhoneStage.from_config(config)` is None when `[hands] enabled` is false or the hand models are
missing (one warning: phone detection is off; the record's hand and phone fields stay null).
`apply(frame, sample)` adds the hands and the judgement to the pose sample; between the hand
stage's runs (`[hands] interval_s`) the last hands and judgement are carried over.
"""

from __future__ import annotations

from dataclasses import replace

from roadgaze.config import Config
from roadgaze.landmarks.hands.stage import HandStage
from roadgaze.phone.judge import judge
from roadgaze.phone.model import PhoneModel, load_model
from roadgaze.types import Frame, PhoneJudgement, PoseSample


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
        return replace(sample, hands=found.hands, phone=self._last)

    def close(self) -> None:
        self.hands.close()
