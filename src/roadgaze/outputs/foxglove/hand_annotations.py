"""The hands on the recording's camera annotations (`/roadgaze/annotations`): each hand found as
its 21-landmark skeleton in its side's colour (red for the hand the phone judgement says holds a
phone) with its label, as the annotated video draws them (`roadgaze.outputs.annotate_hands`)."""

from __future__ import annotations

from foxglove.messages import (
    Color,
    Point2,
    PointsAnnotation,
    PointsAnnotationType,
    TextAnnotation,
    Timestamp,
)

from roadgaze.outputs.annotate_hands import HAND_CONNECTIONS, drawn_hands
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
    points: list[PointsAnnotation] = []
    texts: list[TextAnnotation] = []
    for hand in drawn_hands(record):
        xy = hand.points_px * scale
        colour = _rgba(hand.colour_bgr)
        ends = [Point2(x=xy[i, 0], y=xy[i, 1]) for pair in HAND_CONNECTIONS for i in pair]
        line_list = PointsAnnotationType.LineList
        points.append(
            PointsAnnotation(
                timestamp=stamp, type=line_list, points=ends, outline_color=colour, thickness=2.0
            )
        )
        corner = Point2(x=float(xy[:, 0].min()), y=max(0.0, float(xy[:, 1].min()) - 16.0))
        texts.append(
            TextAnnotation(
                timestamp=stamp,
                position=corner,
                text=hand.label,
                font_size=12.0,
                text_color=colour,
                background_color=LABEL_BACKGROUND,
            )
        )
    return points, texts
