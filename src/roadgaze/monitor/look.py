"""Where the driver looks at one sample: the zone from the head pose or the eyes, and the head
pose mapped from the camera's frame into the driver's. Pure; part of
`roadgaze.monitor.inattention.step`."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from roadgaze.config import MonitorConfig
from roadgaze.monitor.eye_rules import eye_zone_map
from roadgaze.monitor.state import MonitorState
from roadgaze.monitor.zones import AWAY, ROAD, ZoneMap
from roadgaze.pose.mounting import CameraMounting, gaze_to_driver
from roadgaze.types import EyesVerdict, Gaze, PoseSample

__all__ = ["Look", "classify", "finite", "to_driver_frame"]


def to_driver_frame(mounting: CameraMounting, sample: PoseSample) -> PoseSample:
    """The sample with its yaw and pitch (smoothed and raw) in the driver's frame
    (roadgaze.pose.mounting); unchanged for a camera in front. A sample without a pitch is
    mapped at level pitch and keeps no pitch."""
    if mounting.is_identity or not sample.face:
        return sample

    def mapped(yaw: float | None, pitch: float | None) -> tuple[float | None, float | None]:
        if yaw is None or not math.isfinite(yaw):
            return yaw, pitch
        level = pitch is None or not math.isfinite(pitch)
        new_yaw, new_pitch = gaze_to_driver(mounting, yaw, 0.0 if level else pitch)  # type: ignore[arg-type]
        return new_yaw, None if pitch is None else (pitch if level else new_pitch)

    yaw, pitch = mapped(sample.yaw_deg, sample.pitch_deg)
    yaw_raw, pitch_raw = mapped(sample.yaw_raw_deg, sample.pitch_raw_deg)
    return replace(
        sample, yaw_deg=yaw, pitch_deg=pitch, yaw_raw_deg=yaw_raw, pitch_raw_deg=pitch_raw
    )


def finite(smoothed: float | None, raw: float | None) -> float | None:
    value = smoothed if smoothed is not None else raw
    if value is None or not math.isfinite(value):
        return None
    return value


@dataclass(frozen=True, slots=True)
class Look:
    """Where the driver looks at one sample, as `_classify` judged it."""

    gaze: Gaze
    zone: str | None
    face_zone: str
    yaw_deg: float | None
    pitch_deg: float | None
    lost_since_s: float | None
    turned_away: bool
    by_eyes: bool = False

    @property
    def why(self) -> str:
        """Why the driver counts as off road, for the alert's `reason`."""
        if self.turned_away:
            return f"face out of view, last seen in {self.zone}"
        if self.gaze is Gaze.UNKNOWN:
            return "face out of view"
        return f"{'eyes' if self.by_eyes else 'head'} in {self.zone}"


def _eyes_moved(eyes: EyesVerdict, head_yaw_deg: float, head_pitch_deg: float) -> bool:
    """The eyes give the gaze and have moved beyond the deadband (gaze != head pose)."""
    return (
        eyes.gaze_source == "eyes"
        and eyes.gaze_yaw_deg is not None
        and eyes.gaze_pitch_deg is not None
        and (eyes.gaze_yaw_deg != head_yaw_deg or eyes.gaze_pitch_deg != head_pitch_deg)
    )


def classify(
    config: MonitorConfig,
    zones: ZoneMap,
    state: MonitorState,
    sample: PoseSample,
    t_s: float,
    eyes: EyesVerdict,
) -> Look:
    yaw = finite(sample.yaw_deg, sample.yaw_raw_deg) if sample.face else None
    pitch = finite(sample.pitch_deg, sample.pitch_raw_deg) if sample.face else None
    if sample.face:
        if yaw is None:  # a face whose yaw the model cannot explain: keep the last decision
            zone = state.face_zone
        else:
            pitch_offset = 0.0 if pitch is None else pitch - state.neutral_pitch_deg
            zone = zones.classify(yaw - state.neutral_yaw_deg, pitch_offset, state.face_zone)
            if _eyes_moved(eyes, yaw, state.neutral_pitch_deg if pitch is None else pitch):
                # An eye glance: judged on the gaze, on a narrower road. The eyes may take the
                # gaze off a road the head is on, never back onto it: a head judged off road
                # stays off road (fail-safe; MediaPipe's eye direction is least reliable with
                # the head turned, where it can read the eyes turned back by 15-20 deg).
                gaze_zones = eye_zone_map(zones, config.eyes_road_margin_deg)
                gaze_zone = gaze_zones.classify(
                    (eyes.gaze_yaw_deg or 0.0) - state.neutral_yaw_deg,
                    (eyes.gaze_pitch_deg or 0.0) - state.neutral_pitch_deg,
                    state.face_zone,
                )
                # Nor into a driving-related zone from one that is not (a look out of the side
                # window read as a mirror glance: the rendered A-pillar drive read the eyes
                # turned back 10 deg at a 60 deg head turn, test_mounting_end_to_end).
                excused_head = zone == ROAD or zones.is_driving_related(zone)
                if (gaze_zone != ROAD or zone == ROAD) and (
                    excused_head or not zones.is_driving_related(gaze_zone)
                ):
                    gaze = Gaze.ON_ROAD if gaze_zone == ROAD else Gaze.OFF_ROAD
                    return Look(gaze, gaze_zone, gaze_zone, yaw, pitch, None, False, by_eyes=True)
        gaze = Gaze.ON_ROAD if zone == ROAD else Gaze.OFF_ROAD
        return Look(gaze, zone, zone, yaw, pitch, None, False)
    if state.face_lost_since_s is not None:
        lost_since, turned = state.face_lost_since_s, state.face_lost_turned_away
    else:
        lost_since = t_s
        if config.turn_away_deg is None or state.last_face_yaw_deg is None:
            turned = not state.on_road
        else:
            turned = abs(state.last_face_yaw_deg - state.neutral_yaw_deg) > config.turn_away_deg
    if not turned:
        return Look(Gaze.UNKNOWN, None, state.face_zone, None, None, lost_since, False)
    zone = state.face_zone
    if zone == ROAD or zones.is_driving_related(zone):  # out of view: no longer a mirror glance
        zone = AWAY
    return Look(Gaze.OFF_ROAD, zone, zone, None, None, lost_since, True)
