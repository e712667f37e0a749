"""The neutral (road-ahead) head pose, learned from samples that look roughly ahead. Pure."""

from __future__ import annotations

import math
from dataclasses import dataclass

from roadgaze.config import MonitorConfig

__all__ = ["NeutralPose", "learn_neutral"]

_MAX_LEARNING_STEP_S = 1.0
"""A longer gap between samples teaches the neutral pose no more than one second would."""
SETTLE_S = 1.0
"""For its first second of learning the neutral also learns from samples judged off the road, and
(the pitch's own second) from a pitch outside the road's entry band of the neutral."""


@dataclass(frozen=True, slots=True)
class NeutralPose:
    """The road-ahead head pose in the driver's frame (degrees), fixed or learned, and the road
    time each angle has learned from (its running mean's weight)."""

    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    yaw_learned_s: float = 0.0
    pitch_learned_s: float = 0.0

    @classmethod
    def from_config(cls, config: MonitorConfig) -> NeutralPose:
        """Before the first sample: the configured values, or 0 where they are learned."""
        return cls(
            yaw_deg=0.0 if config.neutral_yaw_deg is None else config.neutral_yaw_deg,
            pitch_deg=0.0 if config.neutral_pitch_deg is None else config.neutral_pitch_deg,
        )


def _learn(value: float, neutral: float, gain: float, limit: float) -> float:
    return max(-limit, min(limit, neutral + gain * (value - neutral)))


def learn_neutral(
    config: MonitorConfig,
    neutral: NeutralPose,
    previous_t_s: float | None,
    yaw_deg: float | None,
    pitch_deg: float | None,
    t_s: float,
    yaw_rate_dps: float | None = None,
    judged_on_road: bool = True,
) -> NeutralPose:
    """The neutral pose after this sample (`previous_t_s`: the last sample's time; None: this is
    the first, which teaches nothing).

    A sample teaches when the head looks ahead: its yaw within the road's entry bound
    (`road_half_width_deg - hysteresis_deg`) of the neutral yaw, and its pitch within
    +-`neutral_pitch_limit_deg` (where a neutral pitch may lie). The pitch test is wider than the
    road zone, so a camera above or below the line of sight, whose road pose reads outside the
    road zone at first, is still learned. The yaw test is not: a sample in the hysteresis band
    may be a glance held just past the road's edge, and learning from it would walk the neutral
    after the glance until the glance reads as road (fail-safe: an alert is never learned
    away). Nor does a head turning faster than `neutral_max_rate_dps` (`yaw_rate_dps`, None:
    unknown) teach: it sweeps through the road on its way elsewhere (a single such sample would
    otherwise set the neutral at the start of a drive). Once it has learned `SETTLE_S`, only a
    sample the monitor judged on the road (`judged_on_road`) teaches: a held glance into the
    cluster or the lap, level enough to pass the pitch test (a real 30 deg look down reads 10-15
    deg), would otherwise walk the neutral pitch after it until the glance reads as road
    (Pointing'04 subject 8: 4 deg in 2 s, alert lost; scripts/held-out-check.py). The gain is the
    larger of the first-order filter's (time constant `neutral_time_constant_s`) and a running
    mean's (dt over the time learned so far): the neutral settles on the driver's road pose
    within seconds of the start and then follows it slowly.
    """
    yaw, pitch = neutral.yaw_deg, neutral.pitch_deg
    yaw_s, pitch_s = neutral.yaw_learned_s, neutral.pitch_learned_s
    if yaw_deg is None or previous_t_s is None:
        return neutral
    ahead = abs(yaw_deg - yaw) <= config.road_half_width_deg - config.hysteresis_deg
    level = pitch_deg is None or abs(pitch_deg) <= config.neutral_pitch_limit_deg
    if pitch_deg is not None and pitch_s >= SETTLE_S:
        # Settled: a look into the lap (Pointing'04 tilt -60 reads -19 at first) held for
        # seconds would otherwise walk the neutral down after it until the lap read as road
        # (subjects 7 and 8, scripts/held-out-check.py's lap60 case: no warning in 4 s).
        low_deg, high_deg = config.road_pitch_deg
        level = level and low_deg <= pitch_deg - pitch <= high_deg
    limit = config.neutral_max_rate_dps
    steady = (
        yaw_rate_dps is None
        or limit is None
        or not math.isfinite(yaw_rate_dps)
        or abs(yaw_rate_dps) <= limit
    )
    settled = max(yaw_s, pitch_s) >= SETTLE_S
    if not (ahead and level and steady) or (settled and not judged_on_road):
        return neutral
    dt_s = min(t_s - previous_t_s, _MAX_LEARNING_STEP_S)
    slow_gain = 1.0 - math.exp(-dt_s / config.neutral_time_constant_s)
    if config.neutral_yaw_deg is None:
        gain = max(slow_gain, dt_s / (yaw_s + dt_s))
        yaw, yaw_s = _learn(yaw_deg, yaw, gain, config.neutral_limit_deg), yaw_s + dt_s
    if config.neutral_pitch_deg is None and pitch_deg is not None:
        gain = max(slow_gain, dt_s / (pitch_s + dt_s))
        pitch = _learn(pitch_deg, pitch, gain, config.neutral_pitch_limit_deg)
        pitch_s += dt_s
    return NeutralPose(yaw, pitch, yaw_s, pitch_s)
