"""Head pose from face features: the paper's yaw models (pure numpy) and the Kalman smoother."""

from roadgaze.pose.estimator import PoseEstimator
from roadgaze.pose.geometry import (
    PAPER_CONSTANTS,
    YAW_MODELS,
    FaceModelConstants,
    ProjectedFace,
    YawModel,
    boundary_ce,
    ce,
    center_ce,
    cylindrical,
    ellipsoidal,
    expected_error_deg,
    forward_model,
)
from roadgaze.pose.smoothing import SmootherState, YawSmoother

__all__ = [
    "PAPER_CONSTANTS",
    "YAW_MODELS",
    "FaceModelConstants",
    "PoseEstimator",
    "ProjectedFace",
    "SmootherState",
    "YawModel",
    "YawSmoother",
    "boundary_ce",
    "ce",
    "center_ce",
    "cylindrical",
    "ellipsoidal",
    "expected_error_deg",
    "forward_model",
]
