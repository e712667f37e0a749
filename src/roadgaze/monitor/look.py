"""Where the driver looks at one sample: the zone from the head pose or the eyes (with hysteresis,
and through face losses), and the head pose mapped from the camera's frame into the driver's.
Pure; measured once per sample before the behaviours run (`roadgaze.monitor.context`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from roadgaze.config import MonitorConfig
from roadgaze.monitor.eye_rules import eye_zone_map
from roadgaze.monitor.lean import LEAN_ZONE, HeadPlace, leaning, step_place
from roadgaze.monitor.neutral import NeutralPose
from roadgaze.monitor.zones import AWAY, ROAD, ZoneMap
from roadgaze.mounting import CameraMounting, gaze_to_driver
from roadgaze.types import EyesVerdict, Gaze, PoseSample

__all__ = ["Look", "classify", "finite", "to_driver_frame"]


def to_driver_frame(mounting: CameraMounting, sample: PoseSample) -> PoseSample:
    """The sample with its yaw and pitch (smoothed and raw) in the driver's frame
    (roadgaze.mounting); unchanged for a camera in front. A sample without a pitch is
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
    """Where the driver looks at one sample, as `classify` judged it; the next sample's zone is
    judged from it (hysteresis, face losses)."""

    gaze: Gaze = Gaze.ON_ROAD
    zone: str | None = ROAD
    """This sample's zone; None when the gaze is unknown."""
    face_zone: str = ROAD
    """The zone of the last sample with a usable yaw: the hysteresis state, kept through face
    losses."""
    yaw_deg: float | None = None
    pitch_deg: float | None = None
    lost_since_s: float | None = None
    """When the face was lost (None: it is seen)."""
    turned_away: bool = False
    """The face was lost while the head was turned away: off road, not unknown."""
    by_eyes: bool = False
    """The zone was judged on the eyes' gaze, not the head pose."""
    last_face_yaw_deg: float | None = None
    """The yaw of the last sample with a usable yaw."""
    place: HeadPlace = field(default_factory=HeadPlace)
    """The head's place (body lean) and its learned driving place (roadgaze.monitor.lean)."""
    past_road_edge: bool = False
    """On the road by hysteresis only: the head is past the road's entry bound (its rectangle:
    `road_half_width_deg - hysteresis_deg` of yaw, `road_pitch_deg`), not yet past its exit
    bound. Forward and lane support count it as not watching the road (`support_road_edge`)."""

    @property
    def on_road(self) -> bool:
        """The hysteresis state: the last judged zone is the road."""
        return self.face_zone == ROAD

    @property
    def why(self) -> str:
        """Why the driver counts as off road, for the alert's `reason`."""
        if self.turned_away:
            return f"face out of view, last seen in {self.zone}"
        if self.zone == LEAN_ZONE:
            return "head leaning out of the driving place"
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
    previous: Look,
    neutral: NeutralPose,
    sample: PoseSample,
    eyes: EyesVerdict,
    mounting: CameraMounting | None = None,
) -> Look:
    """Where the driver looks at `sample` (in the driver's frame), after `previous`; a head
    leaning out of the driving place is off road (`roadgaze.monitor.lean`)."""
    gaze, zone, face_zone, yaw, pitch, lost_since, turned, by_eyes = _judge(
        config, zones, previous, neutral, sample, eyes
    )
    last_yaw = yaw if yaw is not None else previous.last_face_yaw_deg
    turn = (
        0.0 if yaw is None else yaw - neutral.yaw_deg,
        0.0 if pitch is None else pitch - neutral.pitch_deg,
    )
    mounting = CameraMounting.from_config(config) if mounting is None else mounting
    place = step_place(config, mounting, previous.place, sample, turn, zone == ROAD)
    if leaning(config, place.lean_m) and (zone == ROAD or zones.is_driving_related(zone)):
        gaze, zone, face_zone, by_eyes = Gaze.OFF_ROAD, LEAN_ZONE, LEAN_ZONE, False
    past_edge = zone == ROAD and yaw is not None and not zones.road.contains(*turn)
    return Look(
        gaze, zone, face_zone, yaw, pitch, lost_since, turned, by_eyes, last_yaw, place, past_edge
    )


def _judge(
    config: MonitorConfig,
    zones: ZoneMap,
    previous: Look,
    neutral: NeutralPose,
    sample: PoseSample,
    eyes: EyesVerdict,
) -> tuple[Gaze, str | None, str, float | None, float | None, float | None, bool, bool]:
    """Gaze, zone, face zone, yaw, pitch, face lost since, turned away, judged by the eyes."""
    t_s = sample.t_s
    yaw = finite(sample.yaw_deg, sample.yaw_raw_deg) if sample.face else None
    pitch = finite(sample.pitch_deg, sample.pitch_raw_deg) if sample.face else None
    if sample.face:
        if yaw is None:  # a face whose yaw the model cannot explain: keep the last decision
            zone = previous.face_zone
        else:
            pitch_offset = 0.0 if pitch is None else pitch - neutral.pitch_deg
            zone = zones.classify(yaw - neutral.yaw_deg, pitch_offset, previous.face_zone)
            if _eyes_moved(eyes, yaw, neutral.pitch_deg if pitch is None else pitch):
                # An eye glance: judged on the gaze, on a narrower road. The eyes may take the
                # gaze off a road the head is on, never back onto it: a head judged off road
                # stays off road (fail-safe; MediaPipe's eye direction is least reliable with
                # the head turned, where it can read the eyes turned back by 15-20 deg).
                gaze_zones = eye_zone_map(zones, config.eyes_road_margin_deg)
                gaze_zone = gaze_zones.classify(
                    (eyes.gaze_yaw_deg or 0.0) - neutral.yaw_deg,
                    (eyes.gaze_pitch_deg or 0.0) - neutral.pitch_deg,
                    previous.face_zone,
                )
                # Nor into a driving-related zone from one that is not (a look out of the side
                # window read as a mirror glance: the rendered A-pillar drive read the eyes
                # turned back 10 deg at a 60 deg head turn, test_mounting_end_to_end).
                excused_head = zone == ROAD or zones.is_driving_related(zone)
                if (gaze_zone != ROAD or zone == ROAD) and (
                    excused_head or not zones.is_driving_related(gaze_zone)
                ):
                    gaze = Gaze.ON_ROAD if gaze_zone == ROAD else Gaze.OFF_ROAD
                    return gaze, gaze_zone, gaze_zone, yaw, pitch, None, False, True
        gaze = Gaze.ON_ROAD if zone == ROAD else Gaze.OFF_ROAD
        return gaze, zone, zone, yaw, pitch, None, False, False
    if previous.lost_since_s is not None:
        lost_since, turned = previous.lost_since_s, previous.turned_away
    else:
        lost_since = t_s
        if config.turn_away_deg is None or previous.last_face_yaw_deg is None:
            turned = not previous.on_road
        else:
            turned = abs(previous.last_face_yaw_deg - neutral.yaw_deg) > config.turn_away_deg
    if not turned:
        return Gaze.UNKNOWN, None, previous.face_zone, None, None, lost_since, False, False
    zone = previous.face_zone
    if zone == ROAD or zones.is_driving_related(zone):  # out of view: no longer a mirror glance
        zone = AWAY
    return Gaze.OFF_ROAD, zone, zone, None, None, lost_since, True, False
