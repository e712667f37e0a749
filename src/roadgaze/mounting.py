"""Camera mounting: head pose and gaze from the camera's frame into the driver's frame and back.

Pure (the standard library's `math` only). Angles in degrees; yaw > 0 = towards the driver's own
left, pitch > 0 = up, roll > 0 = the right ear down (ISO 8855: x forward, y left, z up).

**The two frames.** The *driver's frame* has x along the driver's forward direction (straight
down the road), y to the driver's left, z up. The *camera's frame* is the one the pose stage
measures in: its x points from the driver's head to the camera, so a head facing the camera reads
yaw 0 and pitch 0. The camera is taken as aimed at the driver's head, as a driver-monitoring
camera is; its `CameraMounting` is where it sits, seen from the driver's head: the yaw and pitch
of the line from the head to the camera in the driver's frame, and the camera's roll about that
line.

**Rotations.** One orientation per (yaw, pitch, roll), in the order yaw, then pitch, then roll
(intrinsic z-y'-x''):

    R(yaw, pitch, roll) = Rz(yaw) . Ry(-pitch) . Rx(roll)

with Rz, Ry, Rx the right-handed rotations about z, y, x (Ry takes -pitch because a positive
pitch lifts x towards z, a negative rotation about y). Its first column is the direction the
orientation faces, d(yaw, pitch) = (cos pitch cos yaw, cos pitch sin yaw, sin pitch). Back from
a rotation matrix M: yaw = atan2(M21, M11), pitch = asin(M31), roll = atan2(M32, M33)
(1-based indices; at pitch +-90 the yaw is undefined and reads as atan2 gives it).

With M = R(mounting) the camera's orientation in the driver's frame, a head of orientation H_cam
in the camera's frame has the orientation H_drv = M . H_cam in the driver's frame, and a gaze
direction g_cam becomes g_drv = M . g_cam; back: H_cam = M^T . H_drv (M is orthonormal). The
angles compose as rotations, not as sums: they add only when the camera turns about the same
axis as the head (a yaw-only mounting with a yaw-only head: yaw_drv = yaw_cam + yaw_mount). With
a camera below the line of sight (pitch_mount < 0) a head turned sideways reads a pitch that is
neither its own nor the mounting's: sin pitch_drv = sin p_m cos p cos y + cos p_m sin p
(y, p: the camera-frame yaw and pitch, p_m the mounting's pitch).

**Cabins.** Presets are given for a left-hand-drive cabin (the driver on the left); a right-hand
-drive cabin mirrors them in the car's vertical mid plane: yaw and roll change sign, pitch stays.

The mounting ignores the camera's offset from the head's line of sight in the image (the camera
is aimed at the head) and the parallax of a head that moves in the cabin: both are a few degrees
for a driver-monitoring camera, well inside the learned neutral's range (docs/monitor.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    from roadgaze.config.protocol import ProtocolSettings

__all__ = [
    "CABINS",
    "FRONT",
    "MOUNTING_PRESETS",
    "Cabin",
    "CameraMounting",
    "Matrix3",
    "angles_of",
    "gaze_to_camera",
    "gaze_to_driver",
    "head_to_camera",
    "head_to_driver",
    "mounting_for",
    "rotation",
]

Cabin = Literal["lhd", "rhd"]
CABINS: tuple[Cabin, ...] = ("lhd", "rhd")
Matrix3 = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]


@dataclass(frozen=True, slots=True)
class CameraMounting:
    """Where the camera sits, seen from the driver's head, in the driver's frame (degrees).

    `yaw_deg`: the line from the head to the camera, > 0 = to the driver's left; `pitch_deg`:
    > 0 = above the driver's eyes; `roll_deg`: the camera's roll about that line, right-handed
    about the direction from the head to the camera (> 0: the side of the image on the driver's
    left goes up)."""

    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    name: str = "custom"

    def __post_init__(self) -> None:
        for label, value, limit in (
            ("yaw_deg", self.yaw_deg, 180.0),
            ("pitch_deg", self.pitch_deg, 89.0),
            ("roll_deg", self.roll_deg, 180.0),
        ):
            if not math.isfinite(value) or abs(value) > limit:
                raise ValueError(f"camera {label} must be finite within +-{limit:g}, found {value}")

    @classmethod
    def from_config(cls, config: ProtocolSettings) -> CameraMounting:
        """The mounting `[monitor]` configures: the preset in its cabin, with any explicit
        angles (`camera_mounting`, `cabin`, `camera_yaw_deg`, ...)."""
        return mounting_for(
            config.camera_mounting,
            config.cabin,
            config.camera_yaw_deg,
            config.camera_pitch_deg,
            config.camera_roll_deg,
        )

    @property
    def is_identity(self) -> bool:
        """The camera sits straight ahead, level: both frames are one."""
        return self.yaw_deg == 0.0 and self.pitch_deg == 0.0 and self.roll_deg == 0.0

    def mirrored(self) -> CameraMounting:
        """The same mounting in the mirrored cabin (left- <-> right-hand drive)."""
        return CameraMounting(-self.yaw_deg, self.pitch_deg, -self.roll_deg, self.name)


FRONT = CameraMounting(0.0, 0.0, 0.0, "front")
MOUNTING_PRESETS: dict[str, CameraMounting] = {
    "front": FRONT,
    "steering_column": CameraMounting(0.0, -20.0, 0.0, "steering_column"),
    "a_pillar": CameraMounting(35.0, 5.0, 0.0, "a_pillar"),
    "centre_console": CameraMounting(-28.0, -18.0, 0.0, "centre_console"),
}
"""Left-hand-drive presets (`mounting_for` mirrors them for right-hand drive). roadgaze's
estimates of typical cabin geometry, from the camera's position relative to the driver's eyes
(docs/monitor.md, "Camera mounting"): `steering_column` about 0.65 m ahead and 0.23 m below
(atan(0.23/0.65) = 19.5 deg); `a_pillar` the driver-side pillar about 0.5 m to the left, 0.7 m
ahead, slightly above (atan(0.5/0.7) = 35.5 deg); `centre_console` on top of the centre stack,
about 0.37 m to the right, 0.7 m ahead and 0.25 m below (-27.9, -17.6 deg)."""


def mounting_for(
    preset: str,
    cabin: Cabin = "lhd",
    yaw_deg: float | None = None,
    pitch_deg: float | None = None,
    roll_deg: float | None = None,
) -> CameraMounting:
    """The preset's mounting in this cabin, with any of the angles given explicitly instead.

    Explicit angles are the cabin's own (not mirrored). Raises ValueError for an unknown preset
    or cabin, or an angle out of range."""
    if preset not in MOUNTING_PRESETS:
        raise ValueError(
            f"unknown camera mounting {preset!r} (presets: {', '.join(MOUNTING_PRESETS)})"
        )
    if cabin not in CABINS:
        raise ValueError(f"unknown cabin {cabin!r} (cabins: {', '.join(CABINS)})")
    base = MOUNTING_PRESETS[preset]
    base = base.mirrored() if cabin == "rhd" else base
    return CameraMounting(
        base.yaw_deg if yaw_deg is None else yaw_deg,
        base.pitch_deg if pitch_deg is None else pitch_deg,
        base.roll_deg if roll_deg is None else roll_deg,
        base.name if yaw_deg is None and pitch_deg is None and roll_deg is None else "custom",
    )


def rotation(yaw_deg: float, pitch_deg: float, roll_deg: float = 0.0) -> Matrix3:
    """R = Rz(yaw) . Ry(-pitch) . Rx(roll), the orientation of these angles (module doc)."""
    y, p, r = math.radians(yaw_deg), math.radians(pitch_deg), math.radians(roll_deg)
    cy, sy, cp, sp, cr, sr = (
        math.cos(y),
        math.sin(y),
        math.cos(p),
        math.sin(p),
        math.cos(r),
        math.sin(r),
    )
    return (
        (cy * cp, -sy * cr - cy * sp * sr, sy * sr - cy * sp * cr),
        (sy * cp, cy * cr - sy * sp * sr, -cy * sr - sy * sp * cr),
        (sp, cp * sr, cp * cr),
    )


def angles_of(matrix: Matrix3) -> tuple[float, float, float]:
    """(yaw, pitch, roll) in degrees of a rotation matrix, the inverse of `rotation`."""
    yaw = math.degrees(math.atan2(matrix[1][0], matrix[0][0]))
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, matrix[2][0]))))
    roll = math.degrees(math.atan2(matrix[2][1], matrix[2][2]))
    return yaw, pitch, roll


def _product(a: Matrix3, b: Matrix3, transpose_a: bool = False) -> Matrix3:
    def at(i: int, k: int) -> float:
        return a[k][i] if transpose_a else a[i][k]

    rows = tuple(
        tuple(sum(at(i, k) * b[k][j] for k in range(3)) for j in range(3)) for i in range(3)
    )
    return rows  # type: ignore[return-value]


def _mounting_matrix(mounting: CameraMounting) -> Matrix3:
    return rotation(mounting.yaw_deg, mounting.pitch_deg, mounting.roll_deg)


def head_to_driver(
    mounting: CameraMounting, yaw_deg: float, pitch_deg: float, roll_deg: float = 0.0
) -> tuple[float, float, float]:
    """A head pose measured in the camera's frame, in the driver's frame: H_drv = M . H_cam."""
    if mounting.is_identity:
        return yaw_deg, pitch_deg, roll_deg
    return angles_of(_product(_mounting_matrix(mounting), rotation(yaw_deg, pitch_deg, roll_deg)))


def head_to_camera(
    mounting: CameraMounting, yaw_deg: float, pitch_deg: float, roll_deg: float = 0.0
) -> tuple[float, float, float]:
    """A head pose in the driver's frame, as the camera measures it: H_cam = M^T . H_drv."""
    if mounting.is_identity:
        return yaw_deg, pitch_deg, roll_deg
    return angles_of(
        _product(_mounting_matrix(mounting), rotation(yaw_deg, pitch_deg, roll_deg), True)
    )


def _direction(yaw_deg: float, pitch_deg: float) -> tuple[float, float, float]:
    y, p = math.radians(yaw_deg), math.radians(pitch_deg)
    return math.cos(p) * math.cos(y), math.cos(p) * math.sin(y), math.sin(p)


def _angles_of_direction(x: float, y: float, z: float) -> tuple[float, float]:
    return math.degrees(math.atan2(y, x)), math.degrees(math.asin(max(-1.0, min(1.0, z))))


def gaze_to_driver(
    mounting: CameraMounting, yaw_deg: float, pitch_deg: float
) -> tuple[float, float]:
    """A gaze (or head-facing) direction in the camera's frame, in the driver's: g = M . g_cam."""
    if mounting.is_identity:
        return yaw_deg, pitch_deg
    m, d = _mounting_matrix(mounting), _direction(yaw_deg, pitch_deg)
    x, y, z = (sum(m[i][k] * d[k] for k in range(3)) for i in range(3))
    return _angles_of_direction(x, y, z)


def gaze_to_camera(
    mounting: CameraMounting, yaw_deg: float, pitch_deg: float
) -> tuple[float, float]:
    """A direction in the driver's frame, as the camera sees it: g_cam = M^T . g."""
    if mounting.is_identity:
        return yaw_deg, pitch_deg
    m, d = _mounting_matrix(mounting), _direction(yaw_deg, pitch_deg)
    x, y, z = (sum(m[k][i] * d[k] for k in range(3)) for i in range(3))
    return _angles_of_direction(x, y, z)
