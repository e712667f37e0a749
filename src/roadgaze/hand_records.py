"""The hand and phone records carried inside the per-frame records: the hands the hand stage found
(`roadgaze.landmarks.hands`) and the phone judgement made of them (`roadgaze.phone`).

Part of the per-frame vocabulary: `roadgaze.types` re-exports these names (import them from
there). The file sits beside types.py, like eye_records.py, because every stage folder's
`__init__` imports `roadgaze.types`.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np
import numpy.typing as npt


class HandSide(StrEnum):
    """Which of the driver's own hands (not the image side)."""

    LEFT = "left"
    RIGHT = "right"


@dataclass(frozen=True, slots=True)
class Hand:
    """One hand the hand stage found (`roadgaze.landmarks.hands`)."""

    side: HandSide
    """The person's own left or right hand, from MediaPipe's handedness model read for an
    unmirrored camera."""
    side_score: float
    """0..1: how sure the model is of `side` (0.5: no idea)."""
    score: float
    """0..1: the landmark model's hand-presence score."""
    landmarks_px: npt.NDArray[np.float32]
    """(21, 3) MediaPipe hand landmarks: x, y in image pixels, z (depth, wrist-relative) in the
    scale of x. 0 wrist, 4 thumb tip, 8 index tip, 12 middle tip, 16 ring tip, 20 pinky tip."""
    box_px: tuple[float, float, float, float]
    """Bounding box of the landmarks: x_min, y_min, x_max, y_max."""


class PhonePose(StrEnum):
    """Where a phone is held (`PhoneJudgement.pose`)."""

    EAR = "ear"
    """At the head: a call."""
    HELD_UP = "held_up"
    """In front of the body, above the lap: read or typed on at the wheel or in view."""
    LAP = "lap"
    """Low, at the lap or the knee."""


@dataclass(frozen=True, slots=True)
class PhoneJudgement:
    """The per-frame phone judgement (`roadgaze.phone`): from the hands, the face and the head
    pose of one frame, no model of its own beyond a small classifier over those."""

    phone_use: bool | None
    """A phone in hand; None when it cannot be judged (no hand found and no face)."""
    score: float | None
    """The classifier's 0..1: `phone_use` is `score >= threshold`, or a hand held up in front of
    a camera facing the driver (`roadgaze.phone.held_up`); None when it cannot be judged."""
    hand: HandSide | None = None
    """The hand that holds it (the one scoring highest); None without a phone."""
    pose: PhonePose | None = None
    """Where it is held; None without a phone."""
