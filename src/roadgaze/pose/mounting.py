"""The camera mounting's old path: `roadgaze.mounting` holds it now (it is shared vocabulary: the
landmarks choose the driver by seat from it, the pose and the monitor map angles with it)."""

from roadgaze.mounting import (
    CABINS,
    FRONT,
    MOUNTING_PRESETS,
    Cabin,
    CameraMounting,
    Matrix3,
    angles_of,
    gaze_to_camera,
    gaze_to_driver,
    head_to_camera,
    head_to_driver,
    mounting_for,
    rotation,
)

__all__ = [
    "CABINS",
    "FRONT",
    "MOUNTING_PRESETS",
    "Cabin",
    "CameraMounting",
    "Matrix3",
    "angles_of",
    "gaze_to_camera",
    "gaze_to_driver",
    "head_to_camera",
    "head_to_driver",
    "mounting_for",
    "rotation",
]
