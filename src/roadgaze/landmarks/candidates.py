"""The landmark choices compared in docs/landmarks.md (`roadgaze eval --compare-landmarks`)."""

from __future__ import annotations

from roadgaze.landmarks.features import DEFAULT_CHOICE, FACE_OVAL, NOSE_TIP, LandmarkChoice

_MIDLINE = (168, 6, 197, 195, 5, 4, 1)
CANDIDATE_CHOICES: tuple[LandmarkChoice, ...] = (
    LandmarkChoice("face oval, extreme x / nose tip 1", (NOSE_TIP,), FACE_OVAL),
    LandmarkChoice("face oval, extreme x / nose bridge 168", (168,), FACE_OVAL),
    LandmarkChoice("face oval, extreme x / nose bridge 6", (6,), FACE_OVAL),
    LandmarkChoice("face oval, extreme x / midline mean", _MIDLINE, FACE_OVAL),
    LandmarkChoice("cheeks 234/454 / nose tip 1", (NOSE_TIP,), (234, 454)),
    LandmarkChoice("cheeks 234/454 / nose bridge 168", (168,), (234, 454)),
    LandmarkChoice("temples 127/356 / nose tip 1", (NOSE_TIP,), (127, 356)),
    LandmarkChoice("temples 127/356 / nose bridge 6", (6,), (127, 356)),
    LandmarkChoice("cheeks 93/323 / nose tip 1", (NOSE_TIP,), (93, 323)),
    LandmarkChoice("face oval in band [0, 1] / nose 1+4", (NOSE_TIP, 4), FACE_OVAL, (0.0, 1.0)),
    LandmarkChoice("mesh silhouette, whole face / nose tip 1", (NOSE_TIP,)),
    LandmarkChoice("mesh silhouette in band [0, 1] / nose 1+4", (NOSE_TIP, 4), None, (0.0, 1.0)),
    LandmarkChoice(
        "mesh silhouette in band [0.1, 0.5] / nose tip 1", (NOSE_TIP,), None, (0.1, 0.5)
    ),
    LandmarkChoice(
        "mesh silhouette in band [0.1, 0.5] / nose bridge 168", (168,), None, (0.1, 0.5)
    ),
    LandmarkChoice("mesh silhouette in band [0.1, 0.5] / midline mean", _MIDLINE, None, (0.1, 0.5)),
    DEFAULT_CHOICE,
)
"""The alternatives compared in docs/landmarks.md (`roadgaze eval --compare-landmarks`)."""
