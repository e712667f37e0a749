"""A phone held up in front of a camera that faces the driver: roadgaze's own geometric rule
beside the classifier (pure: numpy only).

The classifier (`roadgaze.phone.model`) learnt phone use from a camera on the passenger side; it
does not carry over to a camera in front of the driver (docs/phone.md, "Held up in front"). There
a phone held up at the wheel or in view of the windscreen is a hand raised beside or below the
face, its fingers up, the face seen from the front. `held_up(vector)` says so from the frame's
classifier vector (`roadgaze.phone.features.FEATURES`), for one hand slot at a time:

- the face is found and seen from the front: MediaPipe's yaw within `FRONT_YAW_DEG` (the rule is
  about a camera ahead of the driver; from the side the classifier judges alone);
- the hand points up: the wrist -> middle-finger base line within about 37 degrees of straight up
  (`UP_DIRECTION`), its fingers not closed in a fist (`OPEN_REACH`, the middle finger's tip at
  least that many hand sizes from the wrist);
- it is beside or below the face, not on it: its centre `BELOW_FACE_W` face widths below the
  face's centre and `ASIDE_FACE_W` across (a hand at the hair or the eyes is above that, a cup at
  the mouth on the face's middle).

The limits are roadgaze's choice, not a published rule; it cannot see the phone itself, so any
hand held up that way for the warning's time counts, and it was checked not to fire on the
State Farm drivers' other activities (docs/phone.md). Nothing in it is fitted to a driver.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from roadgaze.phone.features import FEATURES

FRONT_YAW_DEG = 30.0
UP_DIRECTION = -0.8
"""The largest (image y down) y of the unit wrist -> middle-finger base direction."""
OPEN_REACH = 1.2
BELOW_FACE_W = (0.3, 3.0)
ASIDE_FACE_W = (0.6, 3.0)
SLOTS = ("left", "right")


def _at(vector: npt.NDArray[np.floating], name: str) -> float:
    return float(vector[FEATURES.index(name)])


def held_up_slots(vector: npt.NDArray[np.floating]) -> tuple[str, ...]:
    """The hand slots (`left`, `right`: the driver's own) whose hand is held up in front."""
    if _at(vector, "face") < 0.5 or abs(_at(vector, "head_yaw_deg")) > FRONT_YAW_DEG:
        return ()
    found = []
    for slot in SLOTS:
        if _at(vector, f"{slot}_present") < 0.5 or _at(vector, f"{slot}_face_known") < 0.5:
            continue
        below, aside = _at(vector, f"{slot}_face_dy"), abs(_at(vector, f"{slot}_face_dx"))
        if (
            _at(vector, f"{slot}_direction_y") <= UP_DIRECTION
            and _at(vector, f"{slot}_middle_reach") >= OPEN_REACH
            and BELOW_FACE_W[0] <= below <= BELOW_FACE_W[1]
            and ASIDE_FACE_W[0] <= aside <= ASIDE_FACE_W[1]
        ):
            found.append(slot)
    return tuple(found)


def held_up(vector: npt.NDArray[np.floating]) -> bool:
    """A hand is held up in front (see the module docstring)."""
    return bool(held_up_slots(vector))


def held_up_rows(x: npt.NDArray[np.floating]) -> npt.NDArray[np.bool_]:
    """`held_up` of each row of a feature matrix (a row with NaN: False)."""
    return np.array([not np.isnan(row).any() and held_up(row) for row in x], dtype=bool)
