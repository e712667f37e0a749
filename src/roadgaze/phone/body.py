"""The phone classifier's inputs from the driver's upper body (pure: numpy only).

MediaPipe's pose landmarks (`roadgaze.landmarks.pose`, image fractions) give the arms where the
hands themselves are not found: a wrist at the ear, a forearm raised in front of the chest, an
elbow bent over the lap. Per arm (`ARM_FEATURES`, the driver's own left arm: points 7, 11, 13,
15; right: 8, 12, 14, 16): the wrist's offset from the ear and its distance from the ear and
the nose, the wrist's and the elbow's offsets from the shoulder, the elbow's bend (the cosine
between upper arm and forearm) and the wrist's visibility. Distances are over the body's scale
(shoulder width plus the nose's height over the shoulders' centre), so they do not depend on
how far the driver sits from the camera. Then whether a body was found, the nose's height over
the shoulders and the shoulder width (how far the body is turned).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

NOSE = 0
ARMS = {"left": (7, 11, 13, 15), "right": (8, 12, 14, 16)}
"""(ear, shoulder, elbow, wrist) of each of the driver's own arms (MediaPipe's numbering)."""
ARM_FEATURES = (
    "wrist_ear_dx",
    "wrist_ear_dy",
    "wrist_ear",
    "wrist_nose",
    "wrist_shoulder_dx",
    "wrist_shoulder_dy",
    "elbow_shoulder_dx",
    "elbow_shoulder_dy",
    "elbow_bend",
    "wrist_visibility",
)
BODY_FEATURES = (
    *(f"body_{side}_{name}" for side in ARMS for name in ARM_FEATURES),
    "body",
    "body_nose_height",
    "body_shoulder_width",
)
"""The body's part of the classifier's input vector, in order (all zeros without a body)."""


def body_vector(
    points: npt.NDArray[np.floating] | None, visibility: npt.NDArray[np.floating] | None
) -> list[float]:
    """`BODY_FEATURES` of one body: (33, 2+) landmarks in image fractions and (33,)
    visibilities; None (or non-finite points): no body, all zeros."""
    if points is None or visibility is None or not np.isfinite(points[:, :2]).all():
        return [0.0] * len(BODY_FEATURES)
    xy = np.asarray(points, np.float64)[:, :2]
    shoulders = xy[ARMS["left"][1]], xy[ARMS["right"][1]]
    centre = (shoulders[0] + shoulders[1]) / 2
    width = float(np.linalg.norm(shoulders[0] - shoulders[1]))
    scale = width + float(np.linalg.norm(centre - xy[NOSE])) + 1e-6
    values: list[float] = []
    for ear, shoulder, elbow, wrist in ARMS.values():
        to_ear = (xy[wrist] - xy[ear]) / scale
        upper, fore = xy[shoulder] - xy[elbow], xy[wrist] - xy[elbow]
        bend = float(upper @ fore) / (float(np.linalg.norm(upper) * np.linalg.norm(fore)) + 1e-9)
        values += [
            float(to_ear[0]),
            float(to_ear[1]),
            float(np.linalg.norm(to_ear)),
            float(np.linalg.norm(xy[wrist] - xy[NOSE])) / scale,
            *((xy[wrist] - xy[shoulder]) / scale).tolist(),
            *((xy[elbow] - xy[shoulder]) / scale).tolist(),
            bend,
            float(visibility[wrist]),
        ]
    values += [1.0, float(xy[NOSE][1] - centre[1]) / scale, width / scale]
    return values
