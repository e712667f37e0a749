"""Body lean: the head's place in the driver's frame, measured from where the camera sees the face
and judged against its driving place. Pure.

The face's image place at the driving place (`FacePlace`: the face box's centre and size) is
learned from samples judged on the road, as the neutral pose is: a running mean for its first
`neutral_time_constant_s`, then a first-order filter of that time constant; after its first
`SETTLE_S` of road time a leaning head teaches it nothing. Against it, each face
gives the head's displacement (`roadgaze.cabin.head_place_m`, with the camera mounting and its
distance, the turn of the head about the neck removed). A head moved more than `lean_limit_m`
toward either side or down is leaning out of the driving place: a driver reaching to the
passenger footwell or turning to the rear seat. Such a sample is off road in the zone
`body_lean` (not driving-related), whatever the head faces: a leaning driver is not watching the
road, and a lean that keeps the face pointed ahead must not read as `road` (roadgaze's choice;
the limit's reason: docs/monitor.md, "Body lean").
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.cabin import FacePlace, Vector3, camera_distance_m, face_size_px_per_m, head_place_m
from roadgaze.config import MonitorConfig
from roadgaze.monitor.zones import LEAN
from roadgaze.mounting import CameraMounting
from roadgaze.types import PoseSample

__all__ = ["LEAN_ZONE", "SETTLE_S", "HeadPlace", "face_place", "leaning", "step_place"]

LEAN_ZONE = LEAN
_MAX_STEP_S = 1.0
"""A longer gap between samples teaches the driving place no more than one second would."""
_FIRST_S = 0.1
"""The first face taught counts as this much road time in the running mean."""
SETTLE_S = 1.0
"""For its first second of road time the driving place learns even from a head that reads as
leaning (the first face may have been seen while the driver settled in), as the neutral does."""


@dataclass(frozen=True, slots=True)
class HeadPlace:
    """The learned driving place (the face's image place there) and the head's displacement at
    the last sample (metres, driver's frame; None: no face, or nothing learned yet)."""

    reference: FacePlace | None = None
    learned_s: float = 0.0
    t_s: float | None = None
    """When the reference last learned."""
    lean_m: Vector3 | None = None


def face_place(sample: PoseSample) -> FacePlace | None:
    """Where the sample's face is in the image (None: no face or a box of no size)."""
    features = sample.features if sample.face else None
    if features is None:
        return None
    x0, y0, x1, y1 = features.box_px
    k = face_size_px_per_m(x1 - x0, y1 - y0)
    if not k > 0.0:
        return None
    return FacePlace(0.5 * (x0 + x1), 0.5 * (y0 + y1), k)


def leaning(config: MonitorConfig, lean_m: Vector3 | None) -> bool:
    """The head has moved beyond `lean_limit_m` sideways (either side) or down."""
    limit = config.lean_limit_m
    if lean_m is None:
        return False
    return abs(lean_m[1]) > limit or -lean_m[2] > limit


def step_place(
    config: MonitorConfig,
    mounting: CameraMounting,
    previous: HeadPlace,
    sample: PoseSample,
    turn_deg: tuple[float, float],
    on_road: bool,
) -> HeadPlace:
    """The head's place at `sample` (`turn_deg`: the head's yaw and pitch from the neutral), and
    the driving place after it (learned when `on_road` and not leaning)."""
    seen = face_place(sample)
    if seen is None:
        return HeadPlace(previous.reference, previous.learned_s, previous.t_s, None)
    reference = previous.reference
    lean = None
    if reference is not None:
        distance = camera_distance_m(mounting, config.camera_distance_m)
        lean = head_place_m(mounting, distance, reference, seen, *turn_deg)
    settling = previous.learned_s < SETTLE_S
    if not on_road or (leaning(config, lean) and not settling):
        return HeadPlace(reference, previous.learned_s, previous.t_s, lean)
    if reference is None or previous.t_s is None:
        return HeadPlace(seen, _FIRST_S, sample.t_s, lean)
    step = min(max(sample.t_s - previous.t_s, 0.0), _MAX_STEP_S)
    weight = min(previous.learned_s, config.neutral_time_constant_s)
    gain = step / (weight + step) if weight + step > 0.0 else 1.0
    learned = FacePlace(
        reference.u_px + gain * (seen.u_px - reference.u_px),
        reference.v_px + gain * (seen.v_px - reference.v_px),
        reference.k_px_per_m + gain * (seen.k_px_per_m - reference.k_px_per_m),
    )
    return HeadPlace(learned, previous.learned_s + step, sample.t_s, lean)
