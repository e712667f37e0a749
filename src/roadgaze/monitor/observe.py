"""One sample's facts, measured once before the behaviours run: the `Context`. Pure.

In order: the sample's angles into the driver's frame (`camera_mounting`), whether the vehicle
moves fast enough for a configured protocol, the eyes (roadgaze.monitor.eyes), where the driver
looks (roadgaze.monitor.look), the distraction trigger at this speed, the timers
(roadgaze.monitor.episode); and the neutral pose learned from the sample (used from the next).
"""

from __future__ import annotations

from roadgaze.config import MonitorConfig
from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import step_episode
from roadgaze.monitor.eye_rules import HIDDEN
from roadgaze.monitor.eyes import measure_eyes
from roadgaze.monitor.failures import frame_issue
from roadgaze.monitor.look import classify, finite, to_driver_frame
from roadgaze.monitor.neutral import NeutralPose, learn_neutral
from roadgaze.monitor.protocols import configured, distraction_trigger, moving_at
from roadgaze.monitor.state import MonitorState
from roadgaze.monitor.zones import ROAD, ZoneMap
from roadgaze.mounting import CameraMounting
from roadgaze.types import PoseSample

__all__ = ["observe"]


def observe(
    config: MonitorConfig,
    zones: ZoneMap,
    mounting: CameraMounting,
    state: MonitorState,
    sample: PoseSample,
    speed_kmh: float | None,
) -> tuple[Context, NeutralPose]:
    """The context of `sample` (in the camera's frame) after `state`, and the neutral pose after
    it."""
    t_s = sample.t_s
    sample = to_driver_frame(mounting, sample)
    moving = moving_at(config, speed_kmh)
    head_yaw = finite(sample.yaw_deg, sample.yaw_raw_deg) if sample.face else None
    head_pitch = finite(sample.pitch_deg, sample.pitch_raw_deg)
    eyes = measure_eyes(
        config,
        state.eyes,
        sample,
        moving,
        state.on_road,
        head_yaw,
        state.neutral.pitch_deg if head_pitch is None else head_pitch,
        (state.neutral.yaw_deg, state.neutral.pitch_deg),
    )
    look = classify(config, zones, state.look, state.neutral, sample, eyes.verdict, mounting)
    issue = frame_issue(config, sample.frame_check)
    # ADDW's allowance applies when the service knows conditions are non-nominal: eyes hidden,
    # or a poor frame.
    non_nominal = eyes.verdict.reason.startswith(HIDDEN) or bool(issue)
    episode = step_episode(
        config,
        state.episode,
        t_s,
        look.gaze,
        zones.is_driving_related(look.zone),
        sample.face,
        image_works=not issue,
        moving=moving,
    )
    context = Context(
        config=config,
        zones=zones,
        protocols=configured(config.protocol),
        sample=sample,
        speed_kmh=speed_kmh,
        moving=moving,
        look=look,
        eyes=eyes,
        episode=episode,
        episode_ended=state.episode.off_road and not episode.off_road,
        frame_issue=issue,
        trigger=distraction_trigger(config, speed_kmh, non_nominal) if moving else None,
        active=state.active,
        neutral_pitch_deg=state.neutral.pitch_deg,
    )
    neutral = learn_neutral(
        config,
        state.neutral,
        state.t_s,
        look.yaw_deg,
        look.pitch_deg,
        t_s,
        sample.yaw_rate_dps,
        judged_on_road=look.zone == ROAD,
    )
    return context, neutral
