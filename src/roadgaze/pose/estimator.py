"""The pose stage: the configured yaw model on the driver's face, then the smoother."""

from __future__ import annotations

import math

from roadgaze.config import Config
from roadgaze.pose.geometry import YAW_MODELS, FaceModelConstants, YawModel
from roadgaze.pose.smoothing import YawSmoother
from roadgaze.types import Detection, FaceFeatures, PoseSample


class PoseEstimator:
    """Turns one stream's detections into `PoseSample`s; one instance per stream, in time order."""

    def __init__(
        self,
        smoother: YawSmoother | None = None,
        yaw_model: YawModel = YAW_MODELS["center_ce"],
        constants: FaceModelConstants | None = None,
    ) -> None:
        self.smoother = smoother if smoother is not None else YawSmoother()
        self.yaw_model = yaw_model
        self.constants = constants if constants is not None else FaceModelConstants()

    @classmethod
    def from_config(cls, config: Config) -> PoseEstimator:
        return cls(
            smoother=YawSmoother(config.smoothing),
            yaw_model=YAW_MODELS[config.geometry.model],
            constants=config.geometry.face_constants(),
        )

    def raw_yaw_deg(self, features: FaceFeatures | None) -> float | None:
        """The configured yaw model on one face; None without a face or for impossible geometry."""
        if features is None:
            return None
        yaw_deg = float(
            self.yaw_model(
                features.x_left_px, features.x_right_px, features.x_center_px, self.constants
            )
        )
        return yaw_deg if math.isfinite(yaw_deg) else None

    def smooth(
        self, t_s: float, frame: int, detection: Detection, yaw_raw_deg: float | None
    ) -> PoseSample:
        """Fold this frame's raw yaw into the smoother and return the frame's `PoseSample`."""
        smoothed = self.smoother.update(t_s, yaw_raw_deg)
        features = detection.driver
        return PoseSample(
            t_s=t_s,
            frame=frame,
            face=features is not None,
            yaw_raw_deg=yaw_raw_deg,
            yaw_deg=None if smoothed is None else smoothed.yaw_deg,
            yaw_rate_dps=None if smoothed is None else smoothed.yaw_rate_dps,
            yaw_std_deg=None if smoothed is None else smoothed.yaw_std_deg,
            features=features,
            n_faces=len(detection.faces),
        )
