"""The per-frame phone judgement from the record: the hands, the driver's face (pure).

`judge(hands, face, size, model, threshold)` scores the frame with the shipped classifier
(`roadgaze.phone.model`) and, when it judges phone use, names the hand (the one that alone
scores higher) and where it is held: at the `ear` (within `EAR_FACE_WIDTHS` face widths of the
face's centre), in the `lap` (its centre in the image's lowest `LAP_IMAGE_FRACTION`, a camera in
front of the driver seeing the lap at the bottom) or `held_up` (in front, above the lap). Without
hands, a face and a body it cannot judge (`phone_use` None); judged from the body alone, the
hand and the place are not named. A hand held up in front of a camera that faces the driver
(`roadgaze.phone.held_up`, roadgaze's own rule) is phone use `held_up` whatever the score: the
classifier learnt from a camera at the side.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from roadgaze.phone.features import Body, FaceBox, frame_vector, slots
from roadgaze.phone.held_up import held_up_slots
from roadgaze.phone.model import PhoneModel
from roadgaze.types import FaceFeatures, Hand, PhoneJudgement, PhonePose

EAR_FACE_WIDTHS = 1.5
LAP_IMAGE_FRACTION = 0.2


def face_box(face: FaceFeatures | None) -> FaceBox | None:
    """The face's bounding box in pixels, None without a face or with a degenerate box."""
    if face is None:
        return None
    box = tuple(float(value) for value in face.box_px)
    if len(box) != 4 or not all(np.isfinite(box)) or box[2] <= box[0] or box[3] <= box[1]:
        return None
    return (box[0], box[1], box[2], box[3])


def phone_pose(hand: Hand, face: FaceBox | None, size: tuple[int, int]) -> PhonePose:
    """Where the phone hand holds it (see the module docstring)."""
    x_min, y_min, x_max, y_max = hand.box_px
    centre_x, centre_y = (x_min + x_max) / 2, (y_min + y_max) / 2
    if face is not None:
        face_width = max(face[2] - face[0], 1.0)
        apart = np.hypot(centre_x - (face[0] + face[2]) / 2, centre_y - (face[1] + face[3]) / 2)
        if apart <= EAR_FACE_WIDTHS * face_width:
            return PhonePose.EAR
    if centre_y >= (1.0 - LAP_IMAGE_FRACTION) * size[1]:
        return PhonePose.LAP
    return PhonePose.HELD_UP


def judge(
    hands: Sequence[Hand],
    face: FaceFeatures | None,
    size: tuple[int, int],
    model: PhoneModel,
    threshold: float | None = None,
    body: Body | None = None,
) -> PhoneJudgement:
    """The frame's phone judgement; `threshold` None is the model's own operating point;
    `body` the upper body (None: none found)."""
    head = (None, None) if face is None else (face.mediapipe_yaw_deg, face.mediapipe_pitch_deg)
    return judge_box(hands, face_box(face), size, model, threshold, head, body)


def judge_box(
    hands: Sequence[Hand],
    box: FaceBox | None,
    size: tuple[int, int],
    model: PhoneModel,
    threshold: float | None = None,
    head_deg: tuple[float | None, float | None] = (None, None),
    body: Body | None = None,
) -> PhoneJudgement:
    """`judge` with the face as its box in pixels (None: no face) and the head's MediaPipe
    (yaw, pitch) in degrees."""
    if not hands and box is None and body is None:
        return PhoneJudgement(phone_use=None, score=None)
    cut = model.threshold if threshold is None else threshold
    vector = frame_vector(hands, box, size, head_deg, body)
    score = model.score(vector)
    raised = held_up_slots(vector)
    if raised and score < cut:
        left, right = slots(hands)
        holder = left if raised[0] == "left" else right
        side = None if holder is None else holder.side
        return PhoneJudgement(phone_use=True, score=score, hand=side, pose=PhonePose.HELD_UP)
    if score < cut or not hands:
        return PhoneJudgement(phone_use=score >= cut, score=score)
    holder = max(
        hands, key=lambda hand: model.score(frame_vector([hand], box, size, head_deg, body))
    )
    return PhoneJudgement(
        phone_use=True, score=score, hand=holder.side, pose=phone_pose(holder, box, size)
    )
