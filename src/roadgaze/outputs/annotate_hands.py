"""The hands and the phone judgement on the annotated video: each hand found as its 21-landmark
skeleton with its side (the driver's own) and presence score, and a line of the judgement.
Everything drawn comes from the frame's `FrameRecord`; nothing is drawn while the hand stage is
off (`sample.hands` None)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.config import MonitorConfig
from roadgaze.types import FrameRecord, Hand, HandSide

HAND_CONNECTIONS: tuple[tuple[int, int], ...] = (
    (0, 1), (1, 2), (2, 3), (3, 4),          # thumb
    (0, 5), (5, 6), (6, 7), (7, 8),          # index finger
    (5, 9), (9, 10), (10, 11), (11, 12),     # middle finger
    (9, 13), (13, 14), (14, 15), (15, 16),   # ring finger
    (13, 17), (0, 17), (17, 18), (18, 19), (19, 20),  # little finger, palm's edge
)  # fmt: skip
"""MediaPipe's hand skeleton: pairs of landmark indices (0 the wrist, 4 8 12 16 20 the tips)."""

HAND_COLOURS_BGR = {HandSide.LEFT: (255, 120, 40), HandSide.RIGHT: (40, 200, 255)}
"""Blue for the driver's left hand, amber for the right."""
PHONE_HAND_BGR = (60, 40, 230)
"""Red: the hand the phone judgement says holds a phone."""


def hand_label(hand: Hand, holds_phone: bool = False) -> str:
    """The text beside a hand: its side, its presence score, and PHONE when it holds one."""
    text = f"{hand.side.value} hand {hand.score:.2f}"
    return text + "  PHONE" if holds_phone else text


@dataclass(frozen=True, slots=True)
class DrawnHand:
    """A hand as the video and the recording's annotations draw it."""

    points_px: npt.NDArray[np.float64]
    """(21, 2) its landmarks in the image's pixels, all finite."""
    colour_bgr: tuple[int, int, int]
    """Its side's colour, or red for the hand holding a phone."""
    label: str


def drawn_hands(record: FrameRecord) -> list[DrawnHand]:
    """The hands of `record` to draw: those whose 21 landmarks are finite, each with its colour
    and `hand_label`; none while the hand stage is off or no hand is found."""
    sample = record.sample
    phone = sample.phone
    phone_hand = phone.hand if phone is not None and phone.phone_use else None
    drawn = []
    for hand in sample.hands or ():
        points = np.asarray(hand.landmarks_px, dtype=np.float64)[:, :2]
        if points.shape != (21, 2) or not np.isfinite(points).all():
            continue
        holds_phone = hand.side is phone_hand
        colour = PHONE_HAND_BGR if holds_phone else HAND_COLOURS_BGR[hand.side]
        drawn.append(DrawnHand(points, colour, hand_label(hand, holds_phone)))
    return drawn


def draw_hands(canvas: npt.NDArray[np.uint8], record: FrameRecord, scale: float) -> None:
    """Each hand of the record: its skeleton, its landmarks and its label above its box, in the
    colour of its side (red for the hand holding a phone)."""
    import cv2

    thickness = max(1, round(2 * scale))
    for hand in drawn_hands(record):
        pixels = [(round(x), round(y)) for x, y in hand.points_px]
        for start, end in HAND_CONNECTIONS:
            cv2.line(canvas, pixels[start], pixels[end], hand.colour_bgr, thickness, cv2.LINE_AA)
        for pixel in pixels:
            cv2.circle(canvas, pixel, thickness + 1, (255, 255, 255), -1, cv2.LINE_AA)
        x_min, y_min = hand.points_px.min(axis=0)
        corner = (round(x_min), round(y_min))
        _draw_label(canvas, hand.label, corner, hand.colour_bgr, scale)


def _draw_label(
    canvas: npt.NDArray[np.uint8],
    text: str,
    corner: tuple[int, int],
    colour: tuple[int, int, int],
    scale: float,
) -> None:
    """`text` in `colour` on a darkened strip ending just above `corner` (inside the image)."""
    import cv2

    font, font_scale, thickness = cv2.FONT_HERSHEY_SIMPLEX, 0.6 * scale, max(1, round(scale))
    (width, height), baseline = cv2.getTextSize(text, font, font_scale, thickness)
    pad = max(1, round(3 * scale))
    image_width = canvas.shape[1]
    left = max(0, min(corner[0], image_width - width - 2 * pad))
    bottom = max(height + baseline + 2 * pad, corner[1] - pad)
    top = bottom - height - baseline - 2 * pad
    strip = canvas[top:bottom, left : left + width + 2 * pad]
    strip[:] = (strip.astype(np.uint16) * 2 // 5).astype(np.uint8)
    cv2.putText(canvas, text, (left + pad, bottom - pad - baseline), font, font_scale, colour,
                thickness, cv2.LINE_AA)  # fmt: skip


def phone_line(record: FrameRecord, monitor: MonitorConfig | None = None) -> str:
    """One line: the hands found by side and the phone judgement (phone use YES / no / UNKNOWN,
    the classifier's score, the hand and where it is held: a hand held up in front is phone use
    whatever the score, `roadgaze.phone.held_up`); '' while the hand stage is off."""
    sample = record.sample
    if sample.hands is None and sample.phone is None:
        return ""
    hands = sample.hands or ()
    text = f"hands {len(hands)}"
    if hands:
        text += " (" + ", ".join(f"{h.side.value} {h.score:.2f}" for h in hands) + ")"
    phone = sample.phone
    if phone is None:
        return text + "  phone detection off"
    if phone.phone_use is None:
        return text + "  phone UNKNOWN"
    score = "" if phone.score is None else f"  score {phone.score:.2f}"
    if not phone.phone_use:
        return text + f"  phone no{score}"
    text += f"  phone YES{score}"
    held = [] if phone.hand is None else [f"{phone.hand.value} hand"]
    if phone.pose is not None:
        held.append(phone.pose.value.replace("_", " "))
    return text + (f"  {', '.join(held)}" if held else "")
