"""The rendered head's own axes, in face-proportional units, for things worn on or near the face.

The photo's head is not square to the camera (the astronaut looks 15 deg down, rolled 3 deg), so
a cap's brim or a lens is placed along the head's axes, not the image's: `right` runs from the
person's right eye's outer corner to the left one's, `up` from the chin to the top of the
forehead (made square to `right`), `forward` out of the face toward the camera. One unit is the
face width W (the face oval, `PhotoMesh.face_width_px`: about 14 cm on an adult). A point given
as (across, up, forward) in W from an anchor landmark is turned with the head exactly as the
mesh is (`FaceRenderer.turned_points`), so everything worn follows the turned face.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roadgaze.landmarks.features import (
    LEFT_EYE_OUTER,
    MIDLINE_BOTTOM,
    MIDLINE_TOP,
    RIGHT_EYE_OUTER,
)
from roadgaze.synth.renderer import FaceRenderer, turn_points
from roadgaze.types import FloatArray


def _unit(vector: FloatArray) -> FloatArray:
    return np.asarray(vector / max(float(np.linalg.norm(vector)), 1e-9), dtype=np.float64)


@dataclass(frozen=True, slots=True)
class HeadFrame:
    """The head's axes in the unturned mesh (texture pixels; z grows away from the camera)."""

    right: FloatArray
    """Toward the person's left (the image right of an unmirrored camera)."""
    up: FloatArray
    forward: FloatArray
    """Out of the face, toward the camera (about -z)."""
    width_px: float
    """W: the face width in pixels."""

    @classmethod
    def of(cls, renderer: FaceRenderer) -> HeadFrame:
        points = renderer.mesh.points_px
        right = _unit(points[LEFT_EYE_OUTER] - points[RIGHT_EYE_OUTER])
        rising = points[MIDLINE_TOP] - points[MIDLINE_BOTTOM]
        up = _unit(rising - float(rising @ right) * right)
        forward = _unit(np.cross(right, up))
        return cls(right, up, forward, renderer.mesh.face_width_px)

    def at(self, anchor: FloatArray, offsets_w: FloatArray) -> FloatArray:
        """(N, 3) points `offsets_w` (N, 3: across, up, forward, in face widths) from `anchor`."""
        offsets = np.asarray(offsets_w, dtype=np.float64).reshape(-1, 3) * self.width_px
        axes = np.vstack([self.right, self.up, self.forward])
        return np.asarray(anchor + offsets @ axes, dtype=np.float64)

    @property
    def facing_pitch_deg(self) -> float:
        """How far the photo's face looks down from the camera (degrees, > 0 = down): the nod up
        that turns it to face the lens (the astronaut's: 11.5, where MediaPipe's matrix pitch
        reads 0)."""
        return math.degrees(math.asin(max(-1.0, min(1.0, float(self.forward[1])))))

    def down_2d(self) -> FloatArray:
        """The head's down direction in the unturned image (unit, 2-D)."""
        return _unit(-self.up[:2])


def turn(
    renderer: FaceRenderer, points: FloatArray, yaw_deg: float, pitch_deg: float
) -> FloatArray:
    """(N, 3) points fixed to the head, turned as the renderer turns the mesh."""
    return turn_points(points, renderer.mesh.pivot_px, yaw_deg, pitch_deg)
