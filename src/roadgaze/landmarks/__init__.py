"""Landmarks: MediaPipe FaceLandmarker, the model file, and face features with roll removed."""

from roadgaze.landmarks.candidates import CANDIDATE_CHOICES
from roadgaze.landmarks.driver import choose_driver, merge_mirrored, unmirror
from roadgaze.landmarks.features import (
    DEFAULT_CHOICE,
    FACE_OVAL,
    LEFT_EYE_OUTER,
    MIDLINE_BOTTOM,
    MIDLINE_TOP,
    MOUTH_CORNERS,
    NOSE_TIP,
    NUM_LANDMARKS,
    RIGHT_EYE_OUTER,
    LandmarkChoice,
    angles_from_matrix_deg,
    boundaries_and_center,
    features_from_landmarks,
    remove_roll,
    roll_from_eyes_deg,
)
from roadgaze.landmarks.landmarker import MediaPipeLandmarker, to_rgb

__all__ = [
    "CANDIDATE_CHOICES",
    "DEFAULT_CHOICE",
    "FACE_OVAL",
    "LEFT_EYE_OUTER",
    "MIDLINE_BOTTOM",
    "MIDLINE_TOP",
    "MOUTH_CORNERS",
    "NOSE_TIP",
    "NUM_LANDMARKS",
    "RIGHT_EYE_OUTER",
    "LandmarkChoice",
    "MediaPipeLandmarker",
    "angles_from_matrix_deg",
    "boundaries_and_center",
    "choose_driver",
    "features_from_landmarks",
    "merge_mirrored",
    "remove_roll",
    "roll_from_eyes_deg",
    "to_rgb",
    "unmirror",
]
