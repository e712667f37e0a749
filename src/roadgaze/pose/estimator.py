"""The pose stage: the configured yaw and pitch models on the driver's face, then the smoothers."""

from __future__ import annotations

import math
from collections.abc import Callable

from roadgaze.config import Config, PoseConfig, SmoothingConfig
from roadgaze.pose.fullrange import DEFAULT_FULL_RANGE, FullRangeConstants, full_range_yaw_deg
from roadgaze.pose.geometry import YAW_MODELS, FaceModelConstants
from roadgaze.pose.pitch import head_pitch_deg, midline_pitch_deg
from roadgaze.pose.smoothing import AngleSmoother
from roadgaze.types import Detection, FaceFeatures, PoseSample

YawOfFace = Callable[[FaceFeatures, FaceModelConstants], float]
"""One face's yaw in degrees (NaN where the model cannot explain it)."""

FULL_RANGE = "full_range"
"""`geometry.model` value of the service's blended yaw (`roadgaze.pose.fullrange`)."""


def _finite_or_none(value: float | None) -> float | None:
    return value if value is not None and math.isfinite(value) else None


def yaw_of_face_model(name: str, full_range: FullRangeConstants = DEFAULT_FULL_RANGE) -> YawOfFace:
    """The yaw model `geometry.model` names, as a function of one face: `full_range` (F1), or one
    of the paper's five models on the boundaries and centre. Raises KeyError for another name."""
    if name == FULL_RANGE:

        def blended(face: FaceFeatures, constants: FaceModelConstants) -> float:
            return float(
                full_range_yaw_deg(
                    face.x_left_px,
                    face.x_right_px,
                    face.x_center_px,
                    face.mediapipe_yaw_deg,
                    full_range,
                    constants,
                )
            )

        return blended
    model = YAW_MODELS[name]

    def single(face: FaceFeatures, constants: FaceModelConstants) -> float:
        return float(model(face.x_left_px, face.x_right_px, face.x_center_px, constants))

    return single


class PoseEstimator:
    """Turns one stream's detections into `PoseSample`s; one instance per stream, in time order.

    Yaw: `geometry.model` (default the full-range blend). Pitch: `pose.pitch_model`, by default
    MediaPipe's matrix pitch stretched by `pose.pitch_down_gain` below the neutral pitch the
    caller passes (the monitor's learned one in a stream, 0 for stills). Roll: the eye line's.
    Each angle has its own online smoother.
    """

    def __init__(
        self,
        smoothing: SmoothingConfig | None = None,
        yaw_model: str = FULL_RANGE,
        constants: FaceModelConstants | None = None,
        pose: PoseConfig | None = None,
        full_range: FullRangeConstants = DEFAULT_FULL_RANGE,
    ) -> None:
        self.yaw_smoother = AngleSmoother(smoothing)
        self.pitch_smoother = AngleSmoother(smoothing)
        self.yaw_model_name = yaw_model
        self._yaw_of_face = yaw_of_face_model(yaw_model, full_range)
        self.constants = constants if constants is not None else FaceModelConstants()
        self.pose_config = pose if pose is not None else PoseConfig()

    @classmethod
    def from_config(cls, config: Config) -> PoseEstimator:
        return cls(
            smoothing=config.smoothing,
            yaw_model=config.geometry.model,
            constants=FaceModelConstants.from_config(config.geometry),
            pose=config.pose,
            full_range=FullRangeConstants(*config.geometry.full_range_cue_deg),
        )

    def raw_yaw_deg(self, features: FaceFeatures | None) -> float | None:
        """The configured yaw model on one face; None without a face or for impossible geometry."""
        if features is None:
            return None
        return _finite_or_none(self._yaw_of_face(features, self.constants))

    def raw_pitch_deg(
        self, features: FaceFeatures | None, neutral_pitch_deg: float = 0.0
    ) -> float | None:
        """The configured pitch model on one face (degrees, > 0 = up); None without a face or a
        usable pitch (no transformation matrix for `matrix`, impossible geometry for
        `geometric`). `neutral_pitch_deg` is where the matrix pitch's down gain starts."""
        if features is None:
            return None
        if self.pose_config.pitch_model == "geometric":
            return _finite_or_none(
                float(
                    midline_pitch_deg(features.y_top_px, features.y_bottom_px, features.y_center_px)
                )
                if features.y_top_px is not None
                and features.y_bottom_px is not None
                and features.y_center_px is not None
                else None
            )
        if features.mediapipe_pitch_deg is None:
            return None
        return _finite_or_none(
            float(
                head_pitch_deg(
                    features.mediapipe_pitch_deg,
                    neutral_pitch_deg,
                    self.pose_config.pitch_down_gain,
                )
            )
        )

    def smooth(
        self,
        t_s: float,
        frame: int,
        detection: Detection,
        yaw_raw_deg: float | None,
        pitch_raw_deg: float | None = None,
    ) -> PoseSample:
        """Fold this frame's raw yaw and pitch into the smoothers and return its `PoseSample`."""
        yaw = self.yaw_smoother.update(t_s, yaw_raw_deg)
        pitch = self.pitch_smoother.update(t_s, pitch_raw_deg)
        features = detection.driver
        return PoseSample(
            t_s=t_s,
            frame=frame,
            face=features is not None,
            yaw_raw_deg=yaw_raw_deg,
            yaw_deg=None if yaw is None else yaw.angle_deg,
            yaw_rate_dps=None if yaw is None else yaw.rate_dps,
            yaw_std_deg=None if yaw is None else yaw.std_deg,
            features=features,
            n_faces=len(detection.faces),
            driver_ambiguous=detection.driver_ambiguous,
            pitch_raw_deg=pitch_raw_deg,
            pitch_deg=None if pitch is None else pitch.angle_deg,
            roll_deg=None if features is None else features.roll_deg,
        )

    def estimate(
        self, t_s: float, frame: int, detection: Detection, neutral_pitch_deg: float = 0.0
    ) -> PoseSample:
        """Raw models and smoothers in one call (what the pipeline does in two timed steps)."""
        driver = detection.driver
        return self.smooth(
            t_s,
            frame,
            detection,
            self.raw_yaw_deg(driver),
            self.raw_pitch_deg(driver, neutral_pitch_deg),
        )
