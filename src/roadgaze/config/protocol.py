"""The monitor's protocol, camera mounting, distraction areas and failure settings (in `[monitor]`).

Kept apart from `roadgaze.config.settings`, which builds `[monitor]` on them. Each protocol rule's
source is in its table (`roadgaze.monitor.protocols`) and in docs/monitor.md.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from roadgaze.config.section import Section

AREA1_ZONE_NAMES = ("far_left", "far_right", "roof")
"""The zones of ADDW's distraction area 1 (roadgaze.monitor.zones): reserved names."""
ROOF_PITCH_MAX_DEG = 30.0
"""The highest `roof_pitch_deg`. The regulation places area 1 at the vehicle's roof, not at an
angle; roadgaze's angle is the head's pitch relative to the neutral, which reads about half of a
look up: a look 60 deg up at Pointing'04's markers reads +30.0 on average (docs/pose.md). A roof
set higher would lie beyond that look, and a look at the roof would never reach area 1."""
ProtocolName = Literal["addw", "euroncap", "both"]
MountingName = Literal["front", "steering_column", "a_pillar", "centre_console"]


class ProtocolSettings(Section):
    """Which protocol's rules warn, their timings, the camera mounting and the failure checks."""

    protocol: ProtocolName = "both"
    """`addw` (EU 2023/2590), `euroncap` (Euro NCAP driver state monitoring) or `both` (the
    earlier warning of the two)."""
    addw_min_speed_kmh: float = Field(default=20.0, ge=0)
    """ADDW warns only above this speed."""
    addw_band_kmh: float = Field(default=50.0, gt=0)
    """ADDW's speed bands meet here: the lower band up to it, the higher one above."""
    addw_distraction_low_s: float = Field(default=6.0, gt=0)
    """ADDW: warn by this much distraction between `addw_min_speed_kmh` and `addw_band_kmh`."""
    addw_distraction_high_s: float = Field(default=3.5, gt=0)
    """ADDW: warn within this much distraction above `addw_band_kmh` (and at unknown speed)."""
    addw_non_nominal_s: float = Field(default=1.5, ge=0)
    """ADDW: added to its trigger times while the service knows conditions are non-nominal
    (eyes hidden, e.g. by sunglasses; a dark frame)."""
    critical_after_warning_s: float = Field(default=3.0, ge=0)
    """A distraction warning escalates to critical this long after it (and not before
    `critical_distraction_s`)."""
    clear_on_road_s: float = Field(default=0.0, ge=0)
    """Distraction alerts clear once the gaze has stayed on the road this long (0: the first
    on-road sample)."""

    camera_mounting: MountingName = "front"
    """Where the camera sits (roadgaze.mounting): head pose and gaze are mapped into the
    driver's frame before zones, the neutral and alerts."""
    cabin: Literal["lhd", "rhd"] = "lhd"
    """Left- or right-hand drive: mirrors the mounting preset and the default zones."""
    camera_yaw_deg: float | None = Field(default=None, ge=-180, le=180)
    """Explicit camera yaw (driver's frame, > 0 = to the driver's left) instead of the preset's."""
    camera_pitch_deg: float | None = Field(default=None, ge=-89, le=89)
    camera_roll_deg: float | None = Field(default=None, ge=-180, le=180)
    camera_distance_m: float | None = Field(default=None, gt=0, le=3)
    """The camera's distance from the driver's head at its driving place (metres), for the
    head's place (body lean, roadgaze.cabin); None: the preset's estimate."""

    distraction_yaw_deg: float = Field(default=55.0, gt=0, le=55)
    """ADDW area 1: beyond +-this yaw from the driver's forward direction is always distraction
    (at most 55: the regulation's planes)."""
    roof_pitch_deg: float = Field(default=20.0, gt=0, le=ROOF_PITCH_MAX_DEG)
    """ADDW area 1, the roof: above this pitch (relative to the neutral) is always distraction
    (at most ROOF_PITCH_MAX_DEG: higher, no look at a roof would reach it)."""

    # --- phone use (docs/phone.md, docs/monitor.md "Protocols") ---
    phone_use_s: float = Field(default=3.0, gt=0)
    """A phone judged in hand this long while moving: `phone_use`."""
    phone_gap_s: float = Field(default=0.7, gt=0)
    """A judgement "no phone" (or none) shorter than this does not end a phone-in-hand run;
    this long, it ends it and clears `phone_use`."""

    frame_failure_s: float = Field(default=2.0, gt=0)
    """Blocked, black or saturated frames this long while moving: `temporary_failure`."""
    frozen_failure_s: float = Field(default=10.0, gt=0)
    """Identical frames this long while moving: `temporary_failure` (frozen camera)."""
    no_face_failure_s: float = Field(default=10.0, gt=0)
    """No face (none judgeable) this long while moving: `temporary_failure`."""
    permanent_failure_s: float = Field(default=30.0, gt=0)
    """A camera lost (reconnecting) or never opened this long: `permanent_failure`."""
    frame_dark_mean: float = Field(default=12.0, ge=0, le=255)
    """A frame darker than this mean grey level is black."""
    frame_min_std: float = Field(default=4.0, ge=0)
    """A frame with less grey-level spread than this is blocked (covered lens, flat image)."""
    frame_saturated_fraction: float = Field(default=0.6, gt=0, le=1)
    """A frame with more than this fraction of pixels at 250 or more is saturated (blinded)."""
    frozen_max_diff: float = Field(default=0.5, ge=0)
    """A frame none of whose grey samples differs from the previous frame's by more than this
    is a repeat (frozen)."""

    @model_validator(mode="after")
    def _bands_agree(self) -> ProtocolSettings:
        if self.addw_band_kmh <= self.addw_min_speed_kmh:
            raise ValueError(
                f"addw_band_kmh ({self.addw_band_kmh:g}) must be above addw_min_speed_kmh "
                f"({self.addw_min_speed_kmh:g})"
            )
        if self.addw_distraction_high_s > self.addw_distraction_low_s:
            raise ValueError(
                f"addw_distraction_high_s ({self.addw_distraction_high_s:g}) must not exceed "
                f"addw_distraction_low_s ({self.addw_distraction_low_s:g}): faster warns sooner"
            )
        return self
