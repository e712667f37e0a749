"""Euro NCAP's gaze locations as points in the driver's frame, and the head's place in it. Pure.

**Locations.** Euro NCAP 2026's driver-monitoring sheet ("DE - DM pred." of its rating
calculator's template) names the places a driver looks at: the driver-side window, the
infotainment system, the passenger footwell, the passenger's face, the passenger-side window,
the glovebox, the rear passenger, the three mirrors and the instrument cluster, and where its
phone-use rows put the phone (mounted on the dashboard outboard or on a dedicated place, at the
driver's outer knee, in the lap, low inboard, held at the wheel's centre). Each `Location`
here is one of them as a point in the driver's frame (x forward, y to the driver's left, z up,
metres from the driver's eyes at their driving place), for a left-hand-drive cabin; a
right-hand-drive cabin mirrors it (y changes sign; the names say "driver side" and "passenger
side", so they stay). The sheet names the locations; the protocol's own test-target positions are
not public, so every point is roadgaze's estimate of a mid-size car (the numbers and their
reasons: docs/monitor.md, "Gaze locations"). Driving-task locations (the mirrors, the cluster)
are kept apart from the others: the sheet scores a glance at them for support, never for a
warning.

From the driver's head at `head_m` (its displacement from the driving place, e.g. a body lean),
a location lies in the direction `direction_deg`: yaw = atan2(y, x), pitch = atan2(z, sqrt(x^2 +
y^2)) of the vector from the head to the point (yaw > 0 to the driver's left, pitch > 0 up).

**The head's place** (`head_place_m`). The camera is aimed at the head at its driving place
(roadgaze.mounting), so there the face sits at the image's principal point; its learned image
place (`FacePlace`: centre u0, v0 and size k0 in pixels per metre of face) is the reference. A
face seen at (u, v) with size k lies, by the pinhole camera, at depth Z = D0 k0 / k from the
camera (D0: the camera's distance from the head at its driving place; the focal length f = D0 k0
cancels), and across the image at a = (u - u0) / k (to the image right), b = -(v - v0) / k (up).
With the camera's direction m, its image right r and up w in the driver's frame (the columns of
the mounting's rotation: an unmirrored camera facing the driver sees the driver's left at its
right), the face's centre is at p_face = (D0 - Z) m + a r + b w. A turned head moves its face
about the neck pivot, `PIVOT_BEHIND_FACE_M` behind it: the head's place is the pivot's,
p = p_face - (R(yaw, pitch) - I) (-PIVOT_BEHIND_FACE_M, 0, 0), which a turn alone leaves at 0.
`face_seen` is the inverse (a head placed and turned -> what the camera sees), for tests and the
renderer.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace

from roadgaze.mounting import Cabin, CameraMounting, rotation

__all__ = [
    "CAMERA_DISTANCES_M",
    "DRIVING_TASK",
    "FACE_HEIGHT_M",
    "FACE_WIDTH_M",
    "LOCATIONS",
    "LOCATION_NAMES",
    "NON_DRIVING",
    "PIVOT_BEHIND_FACE_M",
    "FacePlace",
    "Location",
    "Vector3",
    "camera_distance_m",
    "direction_deg",
    "face_seen",
    "face_size_px_per_m",
    "head_place_m",
    "location",
    "locations_for",
]

Vector3 = tuple[float, float, float]

FACE_WIDTH_M = 0.15
"""The face mesh's width (cheek to cheek), about an adult's bizygomatic breadth (13-15 cm)."""
FACE_HEIGHT_M = 0.19
"""The face mesh's height (chin to upper forehead), about an adult's face height (18-20 cm)."""
PIVOT_BEHIND_FACE_M = 0.105
"""The neck pivot behind the face's centre: the yaw model's pivot, (0.25 + 1.25) half widths of a
14 cm face (docs/pose.md)."""
CAMERA_DISTANCES_M = {
    "front": 0.70,
    "steering_column": 0.69,
    "a_pillar": 0.86,
    "centre_console": 0.83,
}
"""The camera's distance from the head at its driving place, per mounting preset: roadgaze's
cabin estimates behind the presets (roadgaze.mounting): the steering column 0.65 m ahead and 0.23
m below, the A-pillar 0.7 m ahead and 0.5 m to the side, the centre console 0.7 m ahead, 0.37 m
to the side and 0.25 m below; a camera in front 0.7 m ahead."""

DRIVING_TASK, NON_DRIVING = "driving", "non_driving"


@dataclass(frozen=True, slots=True)
class Location:
    """One gaze location of the sheet: a point in the driver's frame (metres, left-hand drive
    unless mirrored), what the sheet calls it, whether a glance at it belongs to the driving
    task, and where the point comes from."""

    name: str
    sheet: str
    """The sheet's own words (column C)."""
    point_m: Vector3
    task: str
    """`DRIVING_TASK` (mirrors, cluster) or `NON_DRIVING`."""
    source: str

    @property
    def driving_task(self) -> bool:
        return self.task == DRIVING_TASK

    def direction_deg(self, head_m: Vector3 = (0.0, 0.0, 0.0)) -> tuple[float, float]:
        """(yaw, pitch) of the point seen from a head displaced by `head_m`."""
        return direction_deg(self.point_m, head_m)


_OWN = "roadgaze's estimate of a mid-size left-hand-drive cabin"
LOCATIONS: tuple[Location, ...] = (
    Location("driver_side_window", "Driver side window", (0.10, 0.55, -0.05), NON_DRIVING, _OWN),
    Location(
        "infotainment", "In-vehicle infotainment system", (0.65, -0.37, -0.25), NON_DRIVING, _OWN
    ),
    Location("passenger_footwell", "Passenger footwell", (0.55, -0.75, -0.85), NON_DRIVING, _OWN),
    Location("passenger_face", "Passenger face", (0.0, -0.75, 0.0), NON_DRIVING, _OWN),
    Location(
        "passenger_side_window", "Passenger side window", (0.10, -1.30, -0.05), NON_DRIVING, _OWN
    ),
    Location("glovebox", "Glovebox", (0.60, -0.75, -0.40), NON_DRIVING, _OWN),
    Location("rear_passenger", "Rear passenger", (-0.80, -0.40, -0.10), NON_DRIVING, _OWN),
    Location("driver_side_mirror", "Driver side mirror", (0.70, 0.60, -0.10), DRIVING_TASK, _OWN),
    Location("rear_view_mirror", "Rear view mirror", (0.60, -0.37, 0.15), DRIVING_TASK, _OWN),
    Location(
        "passenger_side_mirror", "Passenger side mirror", (0.95, -1.30, -0.10), DRIVING_TASK, _OWN
    ),
    Location("instrument_cluster", "Instrument cluster", (0.75, 0.0, -0.20), DRIVING_TASK, _OWN),
    # Where the phone-use rows put the phone (a phone looked at, not held up to the camera).
    Location(
        "phone_dashboard_outboard",
        "Phone mounted on dashboard outboard",
        (0.55, 0.35, -0.35),
        NON_DRIVING,
        _OWN,
    ),
    Location(
        "driver_knee_outboard", "Driver knee outboard", (0.40, 0.25, -0.60), NON_DRIVING, _OWN
    ),
    Location("driver_lap", "Driver lap", (0.35, 0.0, -0.55), NON_DRIVING, _OWN),
    Location("driver_inboard", "Driver inboard", (0.35, -0.25, -0.55), NON_DRIVING, _OWN),
    Location(
        "phone_dedicated_mount",
        "Phone mounted on dedicated position",
        (0.55, -0.35, -0.50),
        NON_DRIVING,
        _OWN,
    ),
    Location(
        "phone_wheel_centre",
        "Phone held centre of steering wheel",
        (0.45, 0.0, -0.28),
        NON_DRIVING,
        _OWN,
    ),
)
"""The sheet's gaze locations in a left-hand-drive cabin (`locations_for` mirrors them): the
looks of the distraction rows, then the phone's places of the phone-use rows."""
LOCATION_NAMES = tuple(loc.name for loc in LOCATIONS)


def locations_for(
    cabin: Cabin, points_m: Mapping[str, Vector3] | None = None
) -> tuple[Location, ...]:
    """The locations in this cabin: right-hand drive mirrors y (the names are by side); a
    location in `points_m` (the cabin's own, not mirrored) lies there instead."""
    if cabin not in ("lhd", "rhd"):
        raise ValueError(f"unknown cabin {cabin!r} (cabins: lhd, rhd)")
    own = points_m or {}
    unknown = sorted(set(own) - set(LOCATION_NAMES))
    if unknown:
        raise ValueError(
            f"unknown gaze locations {unknown} (locations: {', '.join(LOCATION_NAMES)})"
        )
    sign = 1.0 if cabin == "lhd" else -1.0
    return tuple(
        replace(loc, point_m=own[loc.name], source="the cabin's own (configured)")
        if loc.name in own
        else replace(loc, point_m=(loc.point_m[0], sign * loc.point_m[1], loc.point_m[2]))
        for loc in LOCATIONS
    )


def location(
    name: str, cabin: Cabin = "lhd", points_m: Mapping[str, Vector3] | None = None
) -> Location:
    """The location `name` in this cabin; ValueError naming the known ones."""
    for loc in locations_for(cabin, points_m):
        if loc.name == name:
            return loc
    raise ValueError(f"unknown gaze location {name!r} (locations: {', '.join(LOCATION_NAMES)})")


def direction_deg(point_m: Vector3, head_m: Vector3 = (0.0, 0.0, 0.0)) -> tuple[float, float]:
    """(yaw, pitch) in degrees of `point_m` seen from `head_m` (driver's frame)."""
    x, y, z = (p - h for p, h in zip(point_m, head_m, strict=True))
    return math.degrees(math.atan2(y, x)), math.degrees(math.atan2(z, math.hypot(x, y)))


def camera_distance_m(mounting: CameraMounting, configured_m: float | None = None) -> float:
    """The camera's distance from the head: the configured one, else the preset's (0.7 m for a
    custom mounting)."""
    if configured_m is not None:
        return configured_m
    return CAMERA_DISTANCES_M.get(mounting.name, CAMERA_DISTANCES_M["front"])


@dataclass(frozen=True, slots=True)
class FacePlace:
    """Where the face is in the image: its centre (pixels, x right, y down) and its size, pixels
    per metre of face."""

    u_px: float
    v_px: float
    k_px_per_m: float


def face_size_px_per_m(width_px: float, height_px: float) -> float:
    """The face's size in pixels per metre: the larger of its width and height read against the
    face's own (a turn narrows the box, a nod shortens it; each leaves the other)."""
    return max(width_px / FACE_WIDTH_M, height_px / FACE_HEIGHT_M)


def _columns(mounting: CameraMounting) -> tuple[Vector3, Vector3, Vector3]:
    m = rotation(mounting.yaw_deg, mounting.pitch_deg, mounting.roll_deg)
    return (
        (m[0][0], m[1][0], m[2][0]),
        (m[0][1], m[1][1], m[2][1]),
        (m[0][2], m[1][2], m[2][2]),
    )


def _pivot_shift(yaw_deg: float, pitch_deg: float) -> Vector3:
    """How far a turn of the head moves its face's centre: (R - I) (PIVOT_BEHIND_FACE_M, 0, 0)."""
    r = rotation(yaw_deg, pitch_deg)
    d = PIVOT_BEHIND_FACE_M
    return (d * (r[0][0] - 1.0), d * r[1][0], d * r[2][0])


def head_place_m(
    mounting: CameraMounting,
    distance_m: float,
    reference: FacePlace,
    seen: FacePlace,
    yaw_deg: float = 0.0,
    pitch_deg: float = 0.0,
) -> Vector3:
    """The head's displacement from its driving place in the driver's frame (metres), from the
    face `seen` against its `reference` at the driving place, the head turned to `yaw_deg`,
    `pitch_deg` (driver's frame). Raises ValueError for a face of no size."""
    if not (seen.k_px_per_m > 0.0 and reference.k_px_per_m > 0.0 and distance_m > 0.0):
        raise ValueError(f"a face place needs a positive size and distance, found {seen}")
    depth = distance_m * reference.k_px_per_m / seen.k_px_per_m
    across = (seen.u_px - reference.u_px) / seen.k_px_per_m
    up = -(seen.v_px - reference.v_px) / seen.k_px_per_m
    m, r, w = _columns(mounting)
    face = tuple((distance_m - depth) * m[i] + across * r[i] + up * w[i] for i in range(3))
    shift = _pivot_shift(yaw_deg, pitch_deg)
    return face[0] - shift[0], face[1] - shift[1], face[2] - shift[2]


def face_seen(
    mounting: CameraMounting,
    distance_m: float,
    reference: FacePlace,
    head_m: Vector3,
    yaw_deg: float = 0.0,
    pitch_deg: float = 0.0,
) -> FacePlace:
    """Where the camera sees the face of a head displaced by `head_m` and turned to `yaw_deg`,
    `pitch_deg` (the inverse of `head_place_m`)."""
    shift = _pivot_shift(yaw_deg, pitch_deg)
    face = tuple(head_m[i] + shift[i] for i in range(3))
    m, r, w = _columns(mounting)
    depth = distance_m - sum(face[i] * m[i] for i in range(3))
    if depth <= 0.0:
        raise ValueError(f"a head at {head_m} m is at or behind the camera")
    k = reference.k_px_per_m * distance_m / depth
    across = sum(face[i] * r[i] for i in range(3))
    up = sum(face[i] * w[i] for i in range(3))
    return FacePlace(reference.u_px + across * k, reference.v_px - up * k, k)
