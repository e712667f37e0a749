"""The hands on the recording's camera annotations (`/roadgaze/annotations`): each hand found as
its 21-landmark skeleton in its side's colour (red for the hand the phone judgement says holds a
phone) with its label, as the annotated video draws them (`roadgaze.outputs.annotate_hands`)."""

from __future__ import annotations

import numpy as np
from foxglove.messages import (
    Color,
    Point2,
    PointsAnnotation,
    PointsAnnotationType,
    TextAnnotation,
    Timestamp,
)

from roadgaze.outputs.annotate_hands import (
    HAND_COLOURS_BGR,
    HAND_CONNECTIONS,
    PHONE_HAND_BGR,
    hand_label,
)
from roadgaze.types import FrameRecord

LABEL_BACKGROUND = Color(r=0.0, g=0.0, b=0.0, a=0.55)


def _rgba(bgr: tuple[int, int, int]) -> Color:
    blue, green, red = bgr
    return Color(r=red / 255, g=green / 255, b=blue / 255, a=1.0)


def hand_annotations(
    record: FrameRecord, stamp: Timestamp, scale: float
) -> tuple[list[PointsAnnotation], list[TextAnnotation]]:
    """The skeleton (a line list) and the label of each hand of `record`, in the pixels of the
    image scaled by `scale`; nothing while the hand stage is off or no hand is found."""
    sample = record.sample
    phone = sample.phone
    phone_hand = phone.hand if phone is not None and phone.phone_use else None
    points: list[PointsAnnotation] = []
    texts: list[TextAnnotation] = []
    for hand in sample.hands or ():
        xy = np.asarray(hand.landmarks_px, dtype=np.float64)[:, :2] * scale
        if xy.shape != (21, 2) or not np.isfinite(xy).all():
            continue
        holds_phone = hand.side is phone_hand
        colour = _rgba(PHONE_HAND_BGR if holds_phone else HAND_COLOURS_BGR[hand.side])
        ends = [Point2(x=xy[i, 0], y=xy[i, 1]) for pair in HAND_CONNECTIONS for i in pair]
        line_list = PointsAnnotationType.LineList
        points.append(
            PointsAnnotation(
                timestamp=stamp, type=line_list, points=ends, outline_color=colour, thickness=2.0
            )
        )
        corner = Point2(x=float(xy[:, 0].min()), y=max(0.0, float(xy[:, 1].min()) - 16.0))
        label = hand_label(hand, holds_phone)
        texts.append(
            TextAnnotation(
                timestamp=stamp,
                position=corner,
                text=label,
                font_size=12.0,
                text_color=colour,
                background_color=LABEL_BACKGROUND,
            )
        )
    return points, texts
