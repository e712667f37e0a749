"""The eye settings: `[eyes]` (measurement) and the monitor's eye thresholds (in `[monitor]`).

Kept apart from `roadgaze.config.settings`, which builds `[monitor]` on them; defaults and their
sources are in docs/eyes.md and docs/monitor.md.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from roadgaze.config.section import Section


class EyesConfig(Section):
    """Eye measurement: which eyes are trusted and where their direction comes from.

    Defaults and their sources: docs/eyes.md.
    """

    method: Literal["blendshapes", "iris"] = "blendshapes"
    """Eye-in-head direction from MediaPipe's eyeLook* blendshapes, or from the iris landmarks
    with an eyeball-centre model (a diagnostic: worse on real faces)."""
    max_head_yaw_deg: float = Field(default=45.0, gt=0, le=90)
    """Beyond this head yaw the eyes give no direction: MediaPipe's eye direction degrades with
    the head turned (docs/eyes.md)."""
    closure_max_head_yaw_deg: float = Field(default=80.0, gt=0, le=90)
    """Up to this head yaw the nearer eye's openness is still judged."""
    far_eye_max_yaw_deg: float = Field(default=35.0, ge=0, le=90)
    """Beyond this head yaw only the nearer eye is used."""
    far_eye_min_width_ratio: float = Field(default=0.6, ge=0, le=1)
    """An eye narrower than this fraction of the other in the image is not used."""
    min_eye_width_px: float = Field(default=8.0, ge=0)
    min_quality: float = Field(default=0.3, ge=0, le=1)
    """Faces of lower landmark quality (small, cut by the image edge) give no eyes."""
    min_contrast: float = Field(default=0.15, ge=0)
    """Eyes whose opening shows less contrast than this (relative to the skin below) while the
    lids look open are taken as hidden (sunglasses); 0 turns the image check off."""
    occluded_min_openness: float = Field(default=0.18, ge=0)
    """The lids look open (so low contrast means a lens, not a closed lid) above this openness."""
    min_lid_share: float = Field(default=0.3, ge=0, le=1)
    """Eyes whose surroundings show less than this share of their edge energy running along the
    eye (the lids, the crease, the brow), in both eyes (both measured), are taken as hidden:
    strands across them (a hair fringe). Seen eyes read 0.42 or more in at least one eye on
    every real face measured, a rendered fringe 0.16 or less (docs/eyes.md); 0: off."""
    min_sharpness: float = Field(default=0.65, ge=0)
    """Eyes whose surroundings show weaker edges than this (relative to the skin below) in every
    measured eye are blurred: lids that read closed there are not judged (unavailable, never
    closed); 0 turns the check off."""


class EyeMonitorSettings(Section):
    """The monitor's eye thresholds: closure, PERCLOS, blinks, gaze (fields of `[monitor]`)."""

    eyes_close_below: float = Field(default=0.14, gt=0)
    """Openness (lid gap / eye width) below which the eyes count as closed when the blink score
    agrees (`eyes_blink_min`)."""
    eyes_hard_close_below: float = Field(default=0.10, gt=0)
    """Openness below which the eyes count as closed whatever the blink score."""
    eyes_open_above: float = Field(default=0.18, gt=0)
    """Closed eyes count as open again only above this openness (hysteresis)."""
    eyes_blink_min: float = Field(default=0.4, ge=0, le=1)
    """The eyeBlink score that must agree between `eyes_hard_close_below` and `eyes_close_below`."""
    look_down_head_deg: float = Field(default=4.0, gt=0)
    """Narrowed lids with the head this far below its road pitch (MediaPipe matrix pitch) read
    as looking down, not as closed."""
    closure_needs_centred_iris: bool = True
    """Lids that read closed while the eyes read turned sideways beyond the driver's yaw
    threshold, from both their resting direction and the eye's centre, are narrowed for a glance
    (open, "looking aside"), not shut: a shut lid's iris reads near one of the two (docs/eyes.md,
    "Looking down vs closing the eyes"). Applies once the eyes are calibrated, never inside a
    closure that began centred."""
    gaze_deadband_deg: float = Field(default=10.0, ge=0)
    """Eye-in-head deviations from the driver's resting eye direction below this count as none."""
    eyes_road_margin_deg: float = Field(default=5.0, ge=0)
    """With the eyes measured, the road zone is narrower by this in yaw (both sides) and at its
    lower edge, so an eyes-only glance beyond 20 deg sideways or 15 deg down leaves it (with the
    default road and deadband), although MediaPipe reads a glance through tinted lenses or under
    heavy lashes about a fifth short (docs/eyes.md)."""
    eye_neutral_limit_deg: float = Field(default=15.0, ge=0)
    """The learned resting eye yaw is used within +-this (Pointing'04: per-subject resting yaw
    -8..+17 deg, docs/eyes.md)."""
    eye_neutral_pitch_limit_deg: float = Field(default=30.0, ge=0)
    """The learned resting eye pitch is used within +-this (real faces read -26..+15 deg looking
    ahead, docs/eyes.md)."""
    eye_calibration_s: float = Field(default=3.0, gt=0)
    """Open-eyed, on-road, steady-head time the driver's resting eye direction and its noise are
    learned from before the eyes may move the gaze (until then the gaze is the head pose)."""
    eye_noise_sigmas: float = Field(default=3.0, gt=0)
    """The eyes move the gaze only beyond this many of the driver's measured standard deviations
    of each axis (and never within `gaze_deadband_deg`)."""
    eye_full_shift_factor: float = Field(default=2.0, ge=1)
    """An eye movement beyond this many of its thresholds moves the gaze by all of it; between one
    and this many, by a ramp from 0 (firm shrinkage; infinite: the soft threshold, where every
    glance is shortened by the threshold). roadgaze's choice: twice the 10 deg deadband is 5.7
    standard deviations of the noisiest real clip's eye pitch, 3.5 deg (docs/eyes.md)."""
    microsleep_s: float = Field(default=1.0, gt=0)
    sleep_s: float = Field(default=3.0, gt=0)
    unresponsive_closed_s: float = Field(default=6.0, gt=0)
    unresponsive_away_s: float = Field(default=6.0, gt=0)
    unresponsive_after_warning_s: float = Field(default=3.0, gt=0)
    closure_gap_s: float = Field(default=0.3, ge=0)
    """Eyes unavailable this long inside a closure do not end it."""
    perclos_window_s: float = Field(default=60.0, gt=0)
    perclos_min_judged_s: float = Field(default=30.0, ge=0)
    """PERCLOS is reported (and may raise `drowsy`) once this much of its window was judged."""
    perclos_drowsy: float = Field(default=0.15, gt=0, le=1)
    perclos_rearm: float = Field(default=0.10, ge=0, le=1)
    long_blink_s: float = Field(default=0.5, gt=0)
    long_blinks_drowsy: int = Field(default=3, ge=1)
    degraded_after_s: float = Field(default=10.0, gt=0)
    """Eyes unavailable this long while moving: monitoring is degraded (head pose only)."""
