"""The phone classifier's inputs from one frame's record: the hands, the driver's face box and the
image size (pure: numpy only).

Per hand (`HAND_FEATURES`): the centre of its 21 landmarks in image fractions, its size (the
largest side of the wrist / index-base / pinky-base triangle, as MediaPipe's de-duplication
measures a hand) over the image height, each finger tip's distance from the wrist and the thumb
tip's from the index tip over that size (open or curled fingers, a pinch), the direction of the
wrist -> middle-finger base line, and, when the face is known, the hand's centre from the face's
in face widths. The frame's vector (`FEATURES`) has a slot for the driver's own left hand, then
one for the right (the more confident hand of a side; a second hand of the same side takes the
empty slot), each with a presence flag, then whether a face was found, how many hands, and the
head's yaw and pitch as MediaPipe's face matrix gives them (0 without: a driver reading a phone
looks down at it), then the upper body's arms (`roadgaze.phone.body.BODY_FEATURES`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from roadgaze.phone.body import BODY_FEATURES, body_vector
from roadgaze.types import Hand, HandSide

FINGER_TIPS = (4, 8, 12, 16, 20)
HAND_FEATURES = (
    "x",
    "y",
    "size",
    "thumb_reach",
    "index_reach",
    "middle_reach",
    "ring_reach",
    "pinky_reach",
    "pinch",
    "direction_x",
    "direction_y",
    "face_dx",
    "face_dy",
    "face_known",
    "present",
)
FEATURES = (
    *(f"left_{name}" for name in HAND_FEATURES),
    *(f"right_{name}" for name in HAND_FEATURES),
    "face",
    "hands",
    "head_yaw_deg",
    "head_pitch_deg",
    *BODY_FEATURES,
)
"""The classifier's input vector, in order."""

FaceBox = tuple[float, float, float, float]
Body = tuple[npt.NDArray[np.floating], npt.NDArray[np.floating]]
"""The upper body: (33, 2+) pose landmarks in image fractions and their (33,) visibilities."""


def hand_size_px(points: npt.NDArray[np.floating]) -> float:
    """The largest side of the wrist / index-base / pinky-base triangle, pixels."""
    wrist, index, pinky = points[0, :2], points[5, :2], points[17, :2]
    return float(
        max(
            np.linalg.norm(wrist - index),
            np.linalg.norm(index - pinky),
            np.linalg.norm(pinky - wrist),
        )
    )


def hand_vector(hand: Hand, face: FaceBox | None, size: tuple[int, int]) -> list[float]:
    """`HAND_FEATURES` of one hand."""
    points = np.asarray(hand.landmarks_px, np.float64)[:, :2]
    width, height = size
    scale = hand_size_px(points) + 1e-6
    centre = points.mean(axis=0)
    reach = [float(np.linalg.norm(points[tip] - points[0])) / scale for tip in FINGER_TIPS]
    pinch = float(np.linalg.norm(points[4] - points[8])) / scale
    direction = points[9] - points[0]
    direction = direction / (float(np.linalg.norm(direction)) + 1e-6)
    if face is None:
        relative = [0.0, 0.0, 0.0]
    else:
        face_width = max(face[2] - face[0], 1.0)
        relative = [
            (centre[0] - (face[0] + face[2]) / 2) / face_width,
            (centre[1] - (face[1] + face[3]) / 2) / face_width,
            1.0,
        ]
    return [
        centre[0] / width,
        centre[1] / height,
        scale / height,
        *reach,
        pinch,
        float(direction[0]),
        float(direction[1]),
        *relative,
        1.0,
    ]


def slots(hands: Sequence[Hand]) -> tuple[Hand | None, Hand | None]:
    """The hands in the (own left, own right) slots: per side the most confident, a second
    hand of a side in the other slot when that is empty."""
    left: Hand | None = None
    right: Hand | None = None
    for hand in sorted(hands, key=lambda found: -found.score):
        if hand.side is HandSide.LEFT:
            if left is None:
                left = hand
            elif right is None:
                right = hand
        elif right is None:
            right = hand
        elif left is None:
            left = hand
    return left, right


def frame_vector(
    hands: Sequence[Hand],
    face: FaceBox | None,
    size: tuple[int, int],
    head_deg: tuple[float | None, float | None] = (None, None),
    body: Body | None = None,
) -> npt.NDArray[np.float64]:
    """`FEATURES` of one frame (an empty slot is all zeros); `head_deg` is the face's (yaw,
    pitch) from MediaPipe's matrix (yaw > 0: turned to the driver's left; pitch > 0: up);
    `body` the upper body (`roadgaze.phone.body`; None: none found)."""
    empty = [0.0] * len(HAND_FEATURES)
    values: list[float] = []
    for hand in slots(hands):
        values += empty if hand is None else hand_vector(hand, face, size)
    yaw, pitch = head_deg
    values += [float(face is not None), float(len(hands)), _finite(yaw), _finite(pitch)]
    values += body_vector(*body) if body is not None else body_vector(None, None)
    return np.asarray(values, np.float64)


def _finite(value: float | None) -> float:
    return 0.0 if value is None or not np.isfinite(value) else float(value)
