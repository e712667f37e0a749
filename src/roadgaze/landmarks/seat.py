"""Where the driver sits in the image, the first pick among several faces, and when two faces
cannot be told apart. Pure (the standard library's `math` only).

**The seat side.** The camera is aimed at the driver's head from its mounting
(`roadgaze.mounting`): in the driver's frame (origin at the driver's head, x forward, y to
the driver's left, z up) its axes are the columns of M = R(yaw, pitch, roll) = Rz(yaw) .
Ry(-pitch) . Rx(roll), x_cam pointing from the head to the camera, the camera at d x_cam. It
looks along -x_cam, so (z_cam up) its image's x grows along f x up = -x_cam x z_cam = y_cam.
The front passenger's head sits beside the driver's at P = (0, -w, 0) in a left-hand-drive car
(w > 0: on the driver's right) or (0, +w, 0) in a right-hand-drive car. The driver's head lies
on the optical axis (image x 0); the passenger's image x is (P - d x_cam) . y_cam / depth =
P . y_cam / depth (x_cam is orthogonal to y_cam), with depth > 0 for a passenger in view. So its
sign is that of -w M22 (LHD), where

    M22 = y_cam . (0, 1, 0) = cos yaw cos roll - sin yaw sin pitch sin roll

whatever d and w: for every camera ahead of the occupants and not rolled far (M22 > 0: every
preset, front, steering column, A-pillar, centre console, M22 = cos yaw), the passenger appears
on the image's left of the driver in a left-hand-drive car and on its right in a right-hand-drive
car: the driver is the face furthest to the image's right (LHD) or left (RHD). A camera beside
the heads or rolled on its side (|M22| below `SEAT_SIDE_MIN`) sees them one above or behind the
other: the side is unknown. M22 < 0 (a camera upside down) swaps the sides. The image must be as
the camera sees it (not mirrored, as everywhere in roadgaze).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

Box = tuple[float, float, float, float]

DRIVER_SWITCH_AREA_RATIO = 1.25
"""Under the "largest" rule a stream moves to another face only when that face's box is this much
larger than the current driver's (faces of similar size would otherwise swap from frame to
frame), and a face within this ratio of the driver's size makes the pick ambiguous."""
SEAT_SIDE_MIN = math.cos(math.radians(75.0))
"""|M22| below this (e.g. a level camera more than 75 deg off the driver's forward direction, or
one rolled by more than 75 deg): the seat side cannot be told."""
PLAUSIBLE_AREA_RATIO = 0.5
"""A face whose box area is at least this share of another's could be the driver in its place
(linear size 0.71). A front passenger seen by a camera 0.65 m in front of the driver is about
1.0 m from it (area share about 0.42), rear passengers further still: they fall below."""
SEAT_MARGIN_WIDTHS = 0.5
"""Two faces whose box centres lie less than this many face widths apart along the image's x
sit in the same place as far as the seat can tell (one behind the other, or leaning over)."""

REASON_SIDE_UNKNOWN = "the driver's seat side is unknown for this camera mounting"
REASON_SAME_PLACE = "another face of similar size sits at the driver's place in the image"
REASON_NEARER_SEAT = "another face of similar size sits nearer the driver's seat than the driver"
REASON_SIMILAR_SIZE = "another face of similar size: the largest rule cannot tell them apart"


class Boxed(Protocol):
    """A face with its bounding box: `FaceFeatures`, or a face found but not yet measured."""

    @property
    def box_px(self) -> Box: ...


def area(box: Box) -> float:
    return max(0.0, box[2] - box[0]) * max(0.0, box[3] - box[1])


def centre_x(box: Box) -> float:
    return 0.5 * (box[0] + box[2])


def driver_image_side(
    cabin: str,
    camera_yaw_deg: float = 0.0,
    camera_pitch_deg: float = 0.0,
    camera_roll_deg: float = 0.0,
) -> int:
    """+1: the driver sits on the image's right of a passenger beside them; -1: on its left; 0:
    unknown (a camera beside the heads, or on its side). `cabin` is "lhd" or "rhd"; the angles
    are the camera mounting's (`roadgaze.mounting.CameraMounting`, degrees). See the module
    doc; raises ValueError for another cabin."""
    if cabin not in ("lhd", "rhd"):
        raise ValueError(f"unknown cabin {cabin!r}; choose lhd or rhd")
    yaw, pitch, roll = (
        math.radians(a) for a in (camera_yaw_deg, camera_pitch_deg, camera_roll_deg)
    )
    along = math.cos(yaw) * math.cos(roll) - math.sin(yaw) * math.sin(pitch) * math.sin(roll)
    if abs(along) < SEAT_SIDE_MIN:
        return 0
    passenger_right = 1 if cabin == "lhd" else -1  # the passenger on the driver's right (LHD)
    return passenger_right if along > 0 else -passenger_right


def seat_pick(faces: Sequence[Boxed], side: int) -> int | None:
    """The face in the driver's seat: among the faces of plausible size (`PLAUSIBLE_AREA_RATIO`
    of the largest), the one furthest toward `side` (+1 image right, -1 left). Ties (the
    runner-up within `SEAT_MARGIN_WIDTHS`) and an unknown side (0) take the larger face, the one
    nearer the camera. None without a face."""
    if not faces:
        return None
    areas = [area(face.box_px) for face in faces]
    largest = max(areas)
    plausible = [i for i, value in enumerate(areas) if value >= PLAUSIBLE_AREA_RATIO * largest]
    if side == 0 or len(plausible) == 1:
        return max(plausible, key=lambda i: areas[i])
    ranked = sorted(plausible, key=lambda i: side * centre_x(faces[i].box_px), reverse=True)
    best, runner_up = ranked[0], ranked[1]
    if _apart_px(faces[best].box_px, faces[runner_up].box_px, side) < _margin_px(
        faces[best].box_px, faces[runner_up].box_px
    ):
        return best if areas[best] >= areas[runner_up] else runner_up
    return best


def _margin_px(a: Box, b: Box) -> float:
    return SEAT_MARGIN_WIDTHS * max(a[2] - a[0], b[2] - b[0])


def _apart_px(driver: Box, other: Box, side: int) -> float:
    """How far `driver` lies toward the driver's side of `other`, pixels (< 0: the other way)."""
    return side * (centre_x(driver) - centre_x(other))


def ambiguity(faces: Sequence[Boxed], driver_index: int | None, rule: str, side: int) -> str:
    """Why the driver `faces[driver_index]` cannot be told from another face in view, '' when it
    can (or there is no driver, or no other face).

    A rival is a face of at least `PLAUSIBLE_AREA_RATIO` of the driver's area (as near the
    camera, roughly). Under "largest" a rival within `DRIVER_SWITCH_AREA_RATIO` of the driver's
    size is ambiguous; under a side (`seat` with `side`, "left", "right") a rival not clearly on
    the passenger's side: at the same place (within `SEAT_MARGIN_WIDTHS`), nearer the driver's
    seat, or any rival when the side is unknown (0).
    """
    if driver_index is None or len(faces) < 2:
        return ""
    driver = faces[driver_index].box_px
    driver_area = area(driver)
    for index, face in enumerate(faces):
        other = face.box_px
        if index == driver_index or area(other) < PLAUSIBLE_AREA_RATIO * driver_area:
            continue
        if rule == "largest":
            if area(other) * DRIVER_SWITCH_AREA_RATIO > driver_area:
                return REASON_SIMILAR_SIZE
            continue
        if side == 0:
            return REASON_SIDE_UNKNOWN
        apart = _apart_px(driver, other, side)
        if apart <= -_margin_px(driver, other):
            return REASON_NEARER_SEAT
        if apart < _margin_px(driver, other):
            return REASON_SAME_PLACE
    return ""
