"""Landmarks: the face landmarker and its engines, the model file, face and eye features."""

from roadgaze.landmarks.candidates import CANDIDATE_CHOICES
from roadgaze.landmarks.driver import choose_driver, merge_mirrored, unmirror
from roadgaze.landmarks.eye_contrast import eye_contrast
from roadgaze.landmarks.eyes import (
    EYES,
    LEFT_EYE,
    RIGHT_EYE,
    EyeIndices,
    driver_eyes,
    eye_features,
    swap_sides,
)
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
from roadgaze.landmarks.landmarker import Landmarker, MediaPipeLandmarker, to_rgb

__all__ = [
    "CANDIDATE_CHOICES",
    "DEFAULT_CHOICE",
    "EYES",
    "FACE_OVAL",
    "LEFT_EYE",
    "LEFT_EYE_OUTER",
    "MIDLINE_BOTTOM",
    "MIDLINE_TOP",
    "MOUTH_CORNERS",
    "NOSE_TIP",
    "NUM_LANDMARKS",
    "RIGHT_EYE",
    "RIGHT_EYE_OUTER",
    "EyeIndices",
    "LandmarkChoice",
    "Landmarker",
    "MediaPipeLandmarker",
    "angles_from_matrix_deg",
    "boundaries_and_center",
    "choose_driver",
    "driver_eyes",
    "eye_contrast",
    "eye_features",
    "features_from_landmarks",
    "merge_mirrored",
    "remove_roll",
    "roll_from_eyes_deg",
    "swap_sides",
    "to_rgb",
    "unmirror",
]
