"""The scenarios of Euro NCAP's gaze locations (`roadgaze.cabin`): owl, lizard and body-lean
looks at each non-driving location the sheet tests, long (one 4 s look) and short (glances that
add up to VATS), at 70 km/h.

Where the driver looks is the location's direction from the head (`Location.direction_deg`), in
the driver's frame. An **owl** look turns the head to it (within what the renderer turns a face
to). A **lizard** look moves the eyes (up to `EYE_REACH_DEG` each way, what the rendered eyes
reach) and turns the head only by what the eyes cannot reach; the head stays within the road's
entry limit. A **body lean** moves the head (`Segment.lean_m`) and turns it to the location as
seen from there, through a lens `LEAN_ZOOM` as wide (so the leaning face stays in the picture).
The looks, lean distances and eye reach are roadgaze's choice (the protocol's own test targets
are not public); every expected window comes from the rule tables (`roadgaze.conformance.expect`).
"""

from __future__ import annotations

from roadgaze.cabin import Vector3, location
from roadgaze.config import MonitorConfig
from roadgaze.conformance import expect
from roadgaze.conformance.matrix import (
    FAST_KMH,
    LOOK_S,
    PITCH_LIMITS_DEG,
    SHOULDER_YAW_DEG,
    VATS_GLANCE_S,
    VATS_ROAD_S,
    ahead,
    back,
)
from roadgaze.conformance.model import Scenario, Segment
from roadgaze.monitor.protocols import euroncap

__all__ = [
    "EYE_REACH_DEG",
    "LEANS_M",
    "LEAN_ZOOM",
    "PHONE_LOOKS",
    "location_scenarios",
    "look_at",
    "look_name",
    "phone_look_scenarios",
]

EYE_REACH_DEG = 35.0
"""How far a lizard look moves the eyes in the head, each way (the renderer's eyes reach 35)."""
LEAN_ZOOM = 0.7
"""A lean's picture: the lens 1/0.7 as wide as the other scenarios' (about 50 deg across)."""
LEANS_M: dict[str, Vector3] = {
    "passenger_footwell": (0.10, -0.20, -0.15),
    "rear_passenger": (-0.10, -0.20, 0.0),
    "road": (0.0, -0.22, -0.10),
}
"""The head's displacement for each body lean (driver's frame: forward, left, up; metres; left-
hand drive, mirrored for right-hand drive): toward the passenger footwell, turned to the rear
seat, and a lean that keeps the face to the road."""


def _clamp(value: float, low: float, high: float) -> float:
    return max(low, min(high, value))


def look_at(
    config: MonitorConfig,
    name: str,
    movement: str,
    duration_s: float,
    label: str = "look",
) -> Segment:
    """A look at location `name` by `movement` (`owl`, `lizard`, `lean`) for `duration_s`."""
    cabin = config.cabin
    lean: Vector3 = (0.0, 0.0, 0.0)
    if movement == "lean":
        lean = LEANS_M[name]
        lean = (lean[0], lean[1] if cabin == "lhd" else -lean[1], lean[2])
        if name == "road":
            return Segment(duration_s, label=label, lean_m=lean)
    points = {own.name: own.point_m for own in config.locations}
    yaw, pitch = location(name, cabin, points).direction_deg(lean)
    if movement == "lizard":
        eye_yaw = _clamp(yaw, -EYE_REACH_DEG, EYE_REACH_DEG)
        eye_pitch = _clamp(pitch, -EYE_REACH_DEG, EYE_REACH_DEG)
        return Segment(
            duration_s, yaw - eye_yaw, pitch - eye_pitch, eye_yaw, eye_pitch, label=label
        )
    head_yaw = _clamp(yaw, -SHOULDER_YAW_DEG, SHOULDER_YAW_DEG)
    head_pitch = _clamp(pitch, *PITCH_LIMITS_DEG)
    return Segment(duration_s, head_yaw, head_pitch, label=label, lean_m=lean)


def look_name(movement: str, name: str) -> str:
    """The scenario of a 4 s look by `movement` at location `name` (`owl_driver_lap_70`)."""
    return f"{movement}_{name}_70"


def _long(
    config: MonitorConfig, name: str, movement: str, mounting: str = "front", what: str = ""
) -> Scenario:
    scenario = look_name(movement, name)
    what = what or f"4 s {movement} look at the {name.replace('_', ' ')} at 70 km/h"
    if movement == "lean":
        what = f"4 s body lean toward the {name.replace('_', ' ')} at 70 km/h"
    if mounting != "front":
        scenario = f"preset_{mounting}_{scenario}"
        what = f"{what}, camera on the {mounting.replace('_', ' ')}"
    requirement = expect.distraction(config, FAST_KMH, f"{scenario}.warns", what)
    segments = (ahead(), look_at(config, name, movement, LOOK_S), back())
    zoom = LEAN_ZOOM if movement == "lean" else 1.0
    return Scenario(
        scenario, what, segments, FAST_KMH, (requirement,), mounting=mounting, zoom=zoom
    )


def _short(
    config: MonitorConfig, scenario: str, movement: str, targets: tuple[str, ...]
) -> Scenario:
    """Glances of `VATS_GLANCE_S` (each below the long-distraction trigger) at `targets` in turn,
    `VATS_ROAD_S` on the road between, until their time reaches the VATS threshold."""
    threshold_s = euroncap.VATS.value(config) or 0.0
    count = int(threshold_s // VATS_GLANCE_S) + 1
    glances: list[Segment] = []
    for index in range(count):
        target = targets[index % len(targets)]
        label = "look" if index == 0 else f"glance{index}"
        glances.append(look_at(config, target, movement, VATS_GLANCE_S, label))
        glances.append(Segment(VATS_ROAD_S))
    places = " and ".join(t.replace("_", " ") for t in targets)
    what = f"{count} {movement} glances of {VATS_GLANCE_S:g} s at the {places} at 70 km/h"
    warns = expect.vats(
        config, f"{scenario}.warns", what, (ahead(), *glances, back()), (count - 1) * VATS_ROAD_S
    )
    short = expect.no_distraction(
        config,
        FAST_KMH,
        f"{scenario}.no_long",
        "each glance below the trigger: no long distraction",
    )
    return Scenario(scenario, what, (ahead(), *glances, back()), FAST_KMH, (warns, short))


MULTI_TARGET = ("infotainment", "passenger_footwell", "glovebox")
"""The multi-target lizard pattern: eyes-only glances at several locations in turn."""


PHONE_LOOKS: dict[int, tuple[str, str]] = {
    51: ("owl", "phone_dashboard_outboard"),
    52: ("owl", "driver_knee_outboard"),
    53: ("owl", "driver_lap"),
    54: ("owl", "driver_inboard"),
    55: ("owl", "phone_dedicated_mount"),
    56: ("lizard", "driver_knee_outboard"),
    57: ("lizard", "driver_lap"),
    58: ("lizard", "driver_inboard"),
    59: ("lizard", "phone_dedicated_mount"),
    60: ("lizard", "phone_wheel_centre"),
    61: ("lizard", "phone_dashboard_outboard"),
}
"""The phone-use rows measured by a look at the phone, by sheet row: (movement, location); basic
phone use by the head (owl) and by the eyes (lizard), and advanced phone use at the dashboard
mount."""


def phone_look_scenarios(config: MonitorConfig) -> list[Scenario]:
    """A 4 s look at the phone at each of `PHONE_LOOKS` at 70 km/h: the eyes leave the road for
    the phone, so the long-distraction rule warns (the phone itself is not drawn: lying in the
    lap or mounted low, it is outside a driver camera's picture, and no rule needs to see it)."""
    scenarios = []
    for movement, name in PHONE_LOOKS.values():
        sheet = location(name).sheet
        what = f"4 s {movement} look at a phone ({sheet.lower()}) at 70 km/h"
        scenarios.append(_long(config, name, movement, what=what))
    return scenarios


def location_scenarios(config: MonitorConfig) -> list[Scenario]:
    """The sheet's owl, lizard and body-lean rows this module measures, in sheet order."""
    return [
        _long(config, "passenger_footwell", "owl"),
        _long(config, "passenger_face", "owl"),
        _long(config, "infotainment", "lizard"),
        _long(config, "glovebox", "lizard"),
        _long(config, "passenger_footwell", "lean"),
        _long(config, "rear_passenger", "lean"),
        _long(config, "road", "lean"),
        _long(config, "road", "lean", "steering_column"),
        _short(config, "vats_owl_passenger_footwell_70", "owl", ("passenger_footwell",)),
        _short(config, "vats_lizard_infotainment_70", "lizard", ("infotainment",)),
        _short(config, "vats_lizard_passenger_footwell_70", "lizard", ("passenger_footwell",)),
        _short(config, "vats_lizard_multi_target_70", "lizard", MULTI_TARGET),
    ]
