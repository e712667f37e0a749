"""Per-driver eye calibration: the resting eye direction and its noise, learned before the eyes
may move the gaze. Pure and time-based (reads time only from the samples' dt).

MediaPipe's eye direction on real faces is biased per person (the resting reading of one driver
looking ahead lies anywhere within about +-15 deg of yaw and -26..+15 deg of pitch) and noisy,
the vertical axis more than the horizontal (measured: docs/eyes.md, "Eye direction noise"). A
gaze built on uncalibrated eyes puts a driver who looks ahead into the lap. So:

- **Learning.** Open-eyed samples on the road with a steady head (the monitor decides which, see
  `roadgaze.monitor.eyes`) teach a time-weighted running mean (the resting direction) and mean
  square deviation (the driver's noise) of the eye-in-head yaw and pitch, each sample weighted by
  the time since the previous one (at most 1 s).
- **Calibrated** once `eye_calibration_s` of such time is learned. Then the noise is frozen (a
  noise still learning from on-road samples would grow with every small glance the threshold lets
  through) and the resting direction follows the driver slowly (first-order lag, 60 s).
- **Thresholds.** Per axis, max(`gaze_deadband_deg`, `eye_noise_sigmas` x the driver's measured
  standard deviation on that axis): only an eye movement beyond the measured noise (its size in
  thresholds over 1) moves the gaze, by a ramp up to all of it at `eye_full_shift_factor`
  thresholds (firm threshold), never nearer the road ahead than each axis's part beyond its
  threshold (soft threshold) would (`eye_shift_deg`).
- **Limits.** The resting direction used is clamped to +-`eye_neutral_limit_deg` (yaw) and
  +-`eye_neutral_pitch_limit_deg` (pitch).

Until calibrated the gaze is the head pose (`eye_shift_deg` returns None).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from roadgaze.config import MonitorConfig
from roadgaze.monitor.eye_rules import firm_threshold, soft_threshold
from roadgaze.types import EyeCalibrationStatus

__all__ = [
    "EyeCalibration",
    "eye_shift_deg",
    "fail_safe_shift",
    "iris_aside",
    "learn_calibration",
    "thresholds_deg",
]

_MAX_STEP_S = 1.0
"""A longer gap between samples teaches no more than one second would."""
_FOLLOW_TIME_CONSTANT_S = 60.0
"""Once calibrated, the resting direction follows the driver with this time constant."""


@dataclass(frozen=True, slots=True)
class EyeCalibration:
    """What is learned of one driver's eyes; replace, never mutate. Angles in degrees (yaw > 0 =
    toward the driver's own left, pitch > 0 = up), eye-in-head."""

    yaw_deg: float = 0.0
    """The resting eye yaw (unclamped running mean)."""
    pitch_deg: float = 0.0
    yaw_sq_deg2: float = 0.0
    """Time-weighted sum of squared deviations of the yaw from its running mean (deg^2 s)."""
    pitch_sq_deg2: float = 0.0
    learned_s: float = 0.0
    """Open-eyed on-road time learned from (the weight of the running means)."""
    calibrated: bool = False
    """Set once `learned_s` reached `eye_calibration_s`; never unset."""

    def status(self) -> EyeCalibrationStatus:
        if self.calibrated:
            return EyeCalibrationStatus.CALIBRATED
        return EyeCalibrationStatus.LEARNING if self.learned_s > 0 else EyeCalibrationStatus.NONE

    def noise_deg(self) -> tuple[float, float]:
        """The driver's standard deviation of eye yaw and pitch around the resting direction."""
        if self.learned_s <= 0:
            return 0.0, 0.0
        return (
            math.sqrt(max(0.0, self.yaw_sq_deg2) / self.learned_s),
            math.sqrt(max(0.0, self.pitch_sq_deg2) / self.learned_s),
        )

    def resting_deg(self, config: MonitorConfig) -> tuple[float, float]:
        """The resting direction as used, within the configured limits."""
        yaw_limit, pitch_limit = config.eye_neutral_limit_deg, config.eye_neutral_pitch_limit_deg
        return (
            max(-yaw_limit, min(yaw_limit, self.yaw_deg)),
            max(-pitch_limit, min(pitch_limit, self.pitch_deg)),
        )


def learn_calibration(
    config: MonitorConfig,
    calibration: EyeCalibration,
    eye_yaw_deg: float,
    eye_pitch_deg: float,
    dt_s: float,
) -> EyeCalibration:
    """One open-eyed, on-road, steady-head sample of the eye direction, `dt_s` after the last.

    While learning: West's weighted incremental mean and variance (weight = dt, at most 1 s).
    Once calibrated: the mean follows with a 60 s lag, the noise stays. A non-finite value or a
    non-positive dt teaches nothing.
    """
    weight = min(dt_s, _MAX_STEP_S)
    if not (weight > 0 and math.isfinite(eye_yaw_deg) and math.isfinite(eye_pitch_deg)):
        return calibration
    if calibration.calibrated:
        gain = 1.0 - math.exp(-weight / _FOLLOW_TIME_CONSTANT_S)
        return EyeCalibration(
            yaw_deg=calibration.yaw_deg + gain * (eye_yaw_deg - calibration.yaw_deg),
            pitch_deg=calibration.pitch_deg + gain * (eye_pitch_deg - calibration.pitch_deg),
            yaw_sq_deg2=calibration.yaw_sq_deg2,
            pitch_sq_deg2=calibration.pitch_sq_deg2,
            learned_s=calibration.learned_s,
            calibrated=True,
        )
    total = calibration.learned_s + weight
    d_yaw = eye_yaw_deg - calibration.yaw_deg
    d_pitch = eye_pitch_deg - calibration.pitch_deg
    yaw = calibration.yaw_deg + weight / total * d_yaw
    pitch = calibration.pitch_deg + weight / total * d_pitch
    return EyeCalibration(
        yaw_deg=yaw,
        pitch_deg=pitch,
        yaw_sq_deg2=calibration.yaw_sq_deg2 + weight * d_yaw * (eye_yaw_deg - yaw),
        pitch_sq_deg2=calibration.pitch_sq_deg2 + weight * d_pitch * (eye_pitch_deg - pitch),
        learned_s=total,
        calibrated=total >= config.eye_calibration_s - 1e-9,
    )


def thresholds_deg(config: MonitorConfig, calibration: EyeCalibration) -> tuple[float, float]:
    """The yaw and pitch deviation (degrees) an eye movement must exceed to move the gaze."""
    yaw_noise, pitch_noise = calibration.noise_deg()
    return (
        max(config.gaze_deadband_deg, config.eye_noise_sigmas * yaw_noise),
        max(config.gaze_deadband_deg, config.eye_noise_sigmas * pitch_noise),
    )


def iris_aside(
    config: MonitorConfig, calibration: EyeCalibration, eye_yaw_deg: float | None
) -> bool:
    """Whether the eyes read turned sideways beyond the driver's yaw threshold both from their
    resting yaw and from the eye's own centre (0): MediaPipe places a shut lid's iris near one
    of the two (the eye's middle, or where that driver's open eyes read at rest), so an iris
    read off both is seen, and lids that read closed are narrowed for a glance. False until
    calibrated, without a yaw, or with `closure_needs_centred_iris` off."""
    if not config.closure_needs_centred_iris or not calibration.calibrated:
        return False
    if eye_yaw_deg is None or not math.isfinite(eye_yaw_deg):
        return False
    threshold = thresholds_deg(config, calibration)[0]
    return abs(eye_yaw_deg - calibration.yaw_deg) > threshold and abs(eye_yaw_deg) > threshold


def eye_shift_deg(
    config: MonitorConfig,
    calibration: EyeCalibration,
    eye_yaw_deg: float | None,
    eye_pitch_deg: float | None,
    head_turn_deg: tuple[float, float] = (0.0, 0.0),
) -> tuple[float, float] | None:
    """How far the eyes move the gaze (yaw, pitch degrees). The deviation from the resting
    direction is one eye movement: its size in units of each axis's `thresholds_deg` (an ellipse)
    decides whether it is beyond the noise, and it is shrunk along its own direction, so an
    oblique glance is not cut to its larger component. Each axis then takes `fail_safe_shift`'s
    choice between that and the axis's own soft threshold. `head_turn_deg`: the head's yaw and
    pitch from the road ahead. None until calibrated or without a direction (the gaze is then
    the head pose)."""
    if not calibration.calibrated or eye_yaw_deg is None or eye_pitch_deg is None:
        return None
    if not (math.isfinite(eye_yaw_deg) and math.isfinite(eye_pitch_deg)):
        return None
    rest_yaw, rest_pitch = calibration.resting_deg(config)
    yaw_threshold, pitch_threshold = thresholds_deg(config, calibration)
    d_yaw, d_pitch = eye_yaw_deg - rest_yaw, eye_pitch_deg - rest_pitch
    size = math.hypot(d_yaw / max(yaw_threshold, 1e-9), d_pitch / max(pitch_threshold, 1e-9))
    if size <= 1.0:
        return 0.0, 0.0
    firm = firm_threshold(size, 1.0, config.eye_full_shift_factor) / size
    return (
        fail_safe_shift(d_yaw * firm, soft_threshold(d_yaw, yaw_threshold), head_turn_deg[0]),
        fail_safe_shift(d_pitch * firm, soft_threshold(d_pitch, pitch_threshold), head_turn_deg[1]),
    )


def fail_safe_shift(firm_deg: float, soft_deg: float, head_turn_deg: float) -> float:
    """One axis's eye shift: the firm threshold's (a large movement counts in full), unless that
    brings the gaze nearer the road ahead than the axis's soft threshold (every deviation
    shortened by the threshold: the rule before the firm one) does; then the soft one. With the
    head turned, MediaPipe reads still eyes as turned back toward the camera by up to 15-20 deg
    (docs/eyes.md): counted in full, that would pull the gaze of a head turned off the road back
    onto it."""
    if abs(head_turn_deg + firm_deg) >= abs(head_turn_deg + soft_deg):
        return firm_deg
    return soft_deg
