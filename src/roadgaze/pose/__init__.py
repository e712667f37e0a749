"""Head pose from face features: yaw (the paper's models, full range), pitch, roll, smoothing."""

from roadgaze.pose.estimator import FULL_RANGE, PoseEstimator, yaw_of_face_model
from roadgaze.pose.fullrange import (
    DEFAULT_FULL_RANGE,
    FullRangeConstants,
    blend_weight,
    clipped_cylinder_deg,
    full_range_yaw_deg,
)
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
from roadgaze.pose.offline import OfflinePose, offline_pose, rts_smooth
from roadgaze.pose.pitch import (
    CANONICAL_MIDLINE,
    DOWN_GAIN,
    MidlineConstants,
    ProjectedMidline,
    head_pitch_deg,
    midline_forward_model,
    midline_pitch_deg,
    naive_pitch_error_deg,
)
from roadgaze.pose.smoothing import (
    AngleSmoother,
    SmootherState,
    extrapolation_residuals,
    robust_noise_std_deg,
)

__all__ = [
    "CANONICAL_MIDLINE",
    "DEFAULT_FULL_RANGE",
    "DOWN_GAIN",
    "FULL_RANGE",
    "PAPER_CONSTANTS",
    "YAW_MODELS",
    "AngleSmoother",
    "FaceModelConstants",
    "FullRangeConstants",
    "MidlineConstants",
    "OfflinePose",
    "PoseEstimator",
    "ProjectedFace",
    "ProjectedMidline",
    "SmootherState",
    "YawModel",
    "blend_weight",
    "boundary_ce",
    "ce",
    "center_ce",
    "clipped_cylinder_deg",
    "cylindrical",
    "ellipsoidal",
    "expected_error_deg",
    "extrapolation_residuals",
    "forward_model",
    "full_range_yaw_deg",
    "head_pitch_deg",
    "midline_forward_model",
    "midline_pitch_deg",
    "naive_pitch_error_deg",
    "offline_pose",
    "robust_noise_std_deg",
    "rts_smooth",
    "yaw_of_face_model",
]
