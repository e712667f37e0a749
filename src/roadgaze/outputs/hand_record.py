"""The hand part of the per-frame record: the hands the hand stage found, each with its side and
its 21 landmarks, and the phone judgement (`roadgaze.outputs.records` re-exports `HAND_SCHEMA`
and `hand_fields`: import them from there)."""

from __future__ import annotations

from typing import Any

import numpy as np

from roadgaze.outputs.field_types import FieldType, rounded
from roadgaze.types import Hand, HandSide, PhoneJudgement

HAND_SCHEMA: tuple[tuple[str, FieldType], ...] = (
    ("n_hands", FieldType.INT),
    ("hand_left_score", FieldType.FLOAT),
    ("hand_left_x", FieldType.FLOAT),
    ("hand_left_y", FieldType.FLOAT),
    ("hand_right_score", FieldType.FLOAT),
    ("hand_right_x", FieldType.FLOAT),
    ("hand_right_y", FieldType.FLOAT),
    ("phone_use", FieldType.BOOL),
    ("phone_score", FieldType.FLOAT),
    ("phone_hand", FieldType.STR),
    ("phone_pose", FieldType.STR),
    ("hands", FieldType.HANDS),
)
"""The hands and the phone judgement (`hand_fields`): null while the hand stage is off; per
side (the driver's own) the best hand's presence score and the centre of its box in pixels;
`hands` every hand found with its landmarks (`hand_landmarks`), [] when none is."""

HAND_JSON_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "side": {"enum": [side.value for side in HandSide]},
        "side_score": {"type": ["number", "null"]},
        "score": {"type": ["number", "null"]},
        "landmarks_px": {
            "type": ["array", "null"],
            "items": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
        },
    },
    "required": ["side", "side_score", "score", "landmarks_px"],
}
"""The JSON Schema of one hand of `hands` (`hand_landmarks`)."""


def hand_fields(hands: tuple[Hand, ...] | None, phone: PhoneJudgement | None) -> dict[str, Any]:
    """The hand part of the record (`HAND_SCHEMA`); all null while the hand stage is off."""
    fields: dict[str, Any] = {"n_hands": None if hands is None else len(hands)}
    for side in HandSide:
        best = max(
            (hand for hand in hands or () if hand.side is side),
            key=lambda hand: hand.score,
            default=None,
        )
        box = None if best is None else best.box_px
        fields[f"hand_{side.value}_score"] = None if best is None else rounded(best.score, 3)
        fields[f"hand_{side.value}_x"] = None if box is None else rounded((box[0] + box[2]) / 2, 1)
        fields[f"hand_{side.value}_y"] = None if box is None else rounded((box[1] + box[3]) / 2, 1)
    fields["phone_use"] = None if phone is None else phone.phone_use
    fields["phone_score"] = None if phone is None else rounded(phone.score, 3)
    fields["phone_hand"] = None if phone is None or phone.hand is None else phone.hand.value
    fields["phone_pose"] = None if phone is None or phone.pose is None else phone.pose.value
    fields["hands"] = None if hands is None else [hand_landmarks(hand) for hand in hands]
    return fields


def hand_landmarks(hand: Hand) -> dict[str, Any]:
    """One hand of the record's `hands`: `side` (the driver's own), `side_score`, `score`
    (presence) and `landmarks_px`, the 21 MediaPipe landmarks as [x, y, z] in pixels to 0.1 px
    (null if any is not finite)."""
    landmarks = np.asarray(hand.landmarks_px, dtype=np.float64)
    finite = bool(np.isfinite(landmarks).all())
    points = (np.round(landmarks, 1) + 0.0).tolist() if finite else None  # + 0.0: no -0.0
    return {
        "side": hand.side.value,
        "side_score": rounded(hand.side_score, 3),
        "score": rounded(hand.score, 3),
        "landmarks_px": points,
    }
