"""Synthetic ground-truth clips: one real photo's face mesh turned to known yaws and re-rendered.

Yaw > 0 turns the head to the person's own left (the nose moves to the image right), pitch > 0
looks up, both relative to the photo's own head pose; the head nods first and then turns, so the
pitch is the elevation of the face's direction (the convention of Pointing'04 and of MediaPipe's
matrix angles).

Rendering: MediaPipe's 478-point face mesh of the photo is lifted to 3D with its own depth
(landmark z, in pixels), rotated about a neck pivot behind the face and projected orthographically.
The pivot sits on the face's vertical mid line at chin height, `(alpha + beta) * r` behind the nose
tip, r being half the face width and alpha = 0.25, beta = 1.25 the paper's constants: the pivot of
the ellipsoidal face model the yaw estimator assumes (for a 14 cm wide face, 10.5 cm behind the
nose tip, close to the atlanto-axial joint). Each of the mesh's 852 triangles that faces the camera
after the turn is mapped by its own affine transform back into the photo; the triangles are
rasterised far to near (painter's order) into a triangle-index buffer, and one `cv2.remap` samples
the photo through the per-pixel affine maps. The rest of the photo stays as background, with the
original face area in-painted so the landmarker never sees two faces.
"""

from __future__ import annotations

import importlib.resources
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.config import Config
from roadgaze.errors import ConfigError, SourceError
from roadgaze.landmarks.features import FACE_OVAL, NOSE_TIP
from roadgaze.synth.mouth import inside_triangles, jaw_of, paint_inside
from roadgaze.types import FloatArray

ImageBGR = npt.NDArray[np.uint8]

DEFAULT_SIZE = (320, 320)
PIVOT_DEPTH_HALF_WIDTHS = 1.5
"""Neck pivot behind the nose tip in half face widths: the paper's alpha + beta = 0.25 + 1.25."""
FACE_WIDTH_FRACTION = 0.32
"""Face width in the output frame as a fraction of the frame's smaller side."""
TESSELLATION_TRIANGLES = 852
CHIN = 152
TEETH_BGR = (200, 215, 225)
"""The teeth's colour where the photo shows none (a closed mouth)."""


def default_photo_path() -> Path:
    """scikit-image's public-domain `astronaut` portrait (NASA photo of Eileen Collins)."""
    return Path(str(importlib.resources.files("skimage.data").joinpath("astronaut.png")))


def load_photo(photo: Path | None = None) -> ImageBGR:
    """Read a photo as BGR uint8; None gives the astronaut. Raises SourceError when unreadable."""
    import cv2

    path = default_photo_path() if photo is None else Path(photo)
    if not path.is_file():
        raise SourceError(f"photo {path} not found; pass an existing image file with --photo")
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise SourceError(f"cannot decode photo {path}; pass a PNG or JPEG image")
    return np.ascontiguousarray(image, dtype=np.uint8)


def _boundary_loops(triangles: npt.NDArray[np.int32]) -> list[list[int]]:
    """The closed loops of edges used by exactly one triangle (the mesh's border and holes)."""
    uses: dict[tuple[int, int], int] = {}
    for a, b, c in triangles.tolist():
        for edge in ((a, b), (b, c), (c, a)):
            key = (min(edge), max(edge))
            uses[key] = uses.get(key, 0) + 1
    neighbours: dict[int, list[int]] = {}
    for (a, b), count in uses.items():
        if count == 1:
            neighbours.setdefault(a, []).append(b)
            neighbours.setdefault(b, []).append(a)
    loops: list[list[int]] = []
    seen: set[int] = set()
    for start in neighbours:
        if start in seen:
            continue
        loop, previous, current = [start], -1, start
        seen.add(start)
        for _ in range(len(neighbours)):
            following = next(n for n in neighbours[current] if n != previous)
            if following == start:
                break
            loop.append(following)
            seen.add(following)
            previous, current = current, following
        loops.append(loop)
    return loops


def _strip(loop: list[int]) -> list[tuple[int, int, int]]:
    """Triangulate a convex-ish loop as a zig-zag strip between its two ends."""
    triangles = []
    left, right = 0, len(loop) - 1
    while right - left >= 2:
        triangles.append((loop[left], loop[left + 1], loop[right]))
        left += 1
        if right - left >= 2:
            triangles.append((loop[left], loop[right - 1], loop[right]))
            right -= 1
    return triangles


def mesh_triangles() -> npt.NDArray[np.int32]:
    """(898, 3) vertex indices: MediaPipe's 852 tessellation triangles and 46 that close its holes.

    The tessellation (its edges come in triangle triples) leaves the eye openings and the mouth
    open; those three loops are closed with strips so the eyes and lips are re-rendered too. The
    winding is not consistent for the added triangles (`FaceRenderer` fixes it from the photo).
    """
    from mediapipe.tasks.python.vision import FaceLandmarksConnections

    edges = FaceLandmarksConnections.FACE_LANDMARKS_TESSELATION
    triangles = np.asarray(
        [(edges[i].start, edges[i + 1].start, edges[i + 2].start) for i in range(0, len(edges), 3)],
        dtype=np.int32,
    )
    loops = sorted(_boundary_loops(triangles), key=len)[:-1]  # the longest is the face's border
    holes = [triangle for loop in loops for triangle in _strip(loop)]
    return np.concatenate([triangles, np.asarray(holes, dtype=np.int32).reshape(-1, 3)])


def photo_landmarks_px(photo_bgr: ImageBGR, config: Config | None = None) -> FloatArray:
    """The driver face's (478, 3) landmarks in the photo, in pixels, from the landmark stage.

    Raises SourceError when the photo shows no face, ModelError when the model is unavailable.
    """
    from roadgaze.landmarks.landmarker import Landmarker

    config = config if config is not None else Config()
    with Landmarker.from_config(config, video=False) as landmarker:
        face = landmarker.detect(photo_bgr).driver
    if face is None:
        raise SourceError("no face found in the photo; pass a photo with one clear frontal face")
    return np.asarray(face.landmarks_px, dtype=np.float64)


@dataclass(frozen=True, slots=True)
class PhotoMesh:
    """The photo's face mesh, in output-frame pixels, and the neck pivot used to turn it."""

    points_px: FloatArray
    """(478, 3): x, y in output pixels, z depth in the same scale (larger is farther away)."""
    pivot_px: FloatArray
    """(3,) the neck pivot: face mid line, chin height, 1.5 half widths behind the nose tip."""
    face_width_px: float


class FaceRenderer:
    """Renders one photo's face turned to any yaw/pitch, at a fixed output size.

    Build once per photo and size (this runs MediaPipe once and in-paints the background), then
    call `render(yaw_deg, pitch_deg)` per frame. `size` is (width, height) in pixels;
    `landmarks_px` skips the landmarker (the photo's (478, 3) mesh), `config` chooses its model.
    `render(..., mouth_open=f)` opens the jaw (`roadgaze.synth.mouth`); `show_mouth_inside`
    False leaves the opened mouth as the texture has it (a face mask over it).
    """

    def __init__(
        self,
        photo_bgr: ImageBGR,
        size: tuple[int, int] = DEFAULT_SIZE,
        landmarks_px: FloatArray | None = None,
        config: Config | None = None,
    ) -> None:
        import cv2

        width, height = size
        if width < 64 or height < 64:
            raise ConfigError(f"frame size must be at least 64x64 px, found {width}x{height}")
        self.size = (int(width), int(height))
        photo_points = (
            photo_landmarks_px(photo_bgr, config) if landmarks_px is None else landmarks_px
        )
        oval = photo_points[list(FACE_OVAL)]
        photo_face_width = float(np.ptp(oval[:, 0]))
        scale = FACE_WIDTH_FRACTION * min(width, height) / photo_face_width
        centre_x = 0.5 * (oval[:, 0].min() + oval[:, 0].max())
        centre_y = 0.5 * (oval[:, 1].min() + oval[:, 1].max())
        to_frame = np.array(
            [
                [scale, 0.0, width / 2 - scale * centre_x],
                [0.0, scale, 0.45 * height - scale * centre_y],
            ]
        )
        self.texture = cv2.warpAffine(
            photo_bgr,
            to_frame,
            self.size,
            flags=cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REFLECT101,
        )
        points = np.column_stack(
            [photo_points[:, :2] @ to_frame[:, :2].T + to_frame[:, 2], photo_points[:, 2] * scale]
        )
        face_width_px = photo_face_width * scale
        half_width = face_width_px / 2
        pivot = np.array(
            [
                0.5 * (points[list(FACE_OVAL), 0].min() + points[list(FACE_OVAL), 0].max()),
                points[CHIN, 1],
                points[NOSE_TIP, 2] + PIVOT_DEPTH_HALF_WIDTHS * half_width,
            ]
        )
        self.mesh = PhotoMesh(points, pivot, face_width_px)
        self.jaw = jaw_of(points, face_width_px)
        self.triangles = mesh_triangles()
        self._front_sign = self._majority_sign(points)
        self.mouth_inside = inside_triangles(self.triangles)
        # The hole fillers have no set winding: take it from the photo, and for a mouth closed
        # too tightly to tell (a sliver under 0.5 px^2) from the jaw opened half way.
        areas = self._signed_areas(points)
        opened = self._signed_areas(self.jaw.open(points, 0.5))
        slivers = np.intersect1d(self.mouth_inside, np.flatnonzero(np.abs(areas) < 0.5))
        areas[slivers] = opened[slivers]
        backwards = areas * self._front_sign < 0
        backwards[:TESSELLATION_TRIANGLES] = False
        self.triangles[backwards] = self.triangles[backwards][:, ::-1]
        self.show_mouth_inside = True
        self.teeth_bgr = self._teeth_colour(cv2)
        self.background = self._inpaint_face(cv2)
        ys, xs = np.mgrid[0:height, 0:width]
        self._pixel_x = xs.astype(np.float64)
        self._pixel_y = ys.astype(np.float64)

    def _signed_areas(self, points: FloatArray) -> FloatArray:
        a, b, c = (points[self.triangles[:, i], :2] for i in range(3))
        ab, ac = b - a, c - a
        return np.asarray(0.5 * (ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0]), dtype=np.float64)

    def _majority_sign(self, points: FloatArray) -> float:
        return 1.0 if np.sum(self._signed_areas(points) > 0) >= len(self.triangles) / 2 else -1.0

    def _teeth_colour(self, cv2: Any) -> FloatArray:
        """The brightest quarter of the photo's open mouth (its teeth), or `TEETH_BGR`."""
        mask = np.zeros(self.texture.shape[:2], dtype=np.uint8)
        corners = np.round(self.mesh.points_px[self.triangles[self.mouth_inside], :2])
        for triangle in corners.astype(np.int32):
            cv2.fillConvexPoly(mask, triangle, 255)
        pixels = self.texture[mask > 0].astype(np.float64)
        if len(pixels) < 8:
            return np.asarray(TEETH_BGR, dtype=np.float64)
        luma = pixels.mean(axis=1)
        return np.asarray(pixels[luma >= np.percentile(luma, 75)].mean(axis=0), dtype=np.float64)

    def _inpaint_face(self, cv2: Any) -> ImageBGR:
        """The texture with the face area (dilated by 6 % of the face width) filled smoothly."""
        mask = np.zeros(self.texture.shape[:2], dtype=np.uint8)
        hull = cv2.convexHull(np.round(self.mesh.points_px[:, :2]).astype(np.int32))
        cv2.fillConvexPoly(mask, hull, 255)
        grow = max(3, round(0.06 * self.mesh.face_width_px))
        mask = cv2.dilate(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * grow + 1,) * 2))
        known = (mask == 0).astype(np.float32)
        filled = push_pull_fill(self.texture.astype(np.float32), known)
        background: ImageBGR = np.clip(filled + 0.5, 0, 255).astype(np.uint8)
        return background

    def turned_points(
        self, yaw_deg: float, pitch_deg: float = 0.0, mouth_open: float = 0.0
    ) -> FloatArray:
        """The mesh (its jaw opened by `mouth_open`, `roadgaze.synth.mouth`) nodded by pitch
        (about the head's lateral axis), then turned by yaw (about the vertical axis), both about
        the neck pivot: pitch is the elevation of the face's forward direction, as in
        Pointing'04's tilt and MediaPipe's matrix angles."""
        points = self.jaw.open(self.mesh.points_px, mouth_open)
        return turn_points(points, self.mesh.pivot_px, yaw_deg, pitch_deg)

    def render(self, yaw_deg: float, pitch_deg: float = 0.0, mouth_open: float = 0.0) -> ImageBGR:
        """One BGR frame of the face turned to `yaw_deg`, `pitch_deg` over the background, the
        jaw opened by `mouth_open` (a fraction of a wide yawn, `roadgaze.synth.mouth`)."""
        import cv2

        turned = self.turned_points(yaw_deg, pitch_deg, mouth_open)
        areas = self._signed_areas(turned) * self._front_sign
        visible = np.flatnonzero(areas > 0.05)  # back faces and edge-on slivers culled
        depth = turned[self.triangles[visible]][:, :, 2].mean(axis=1)
        order = visible[np.argsort(-depth, kind="stable")]  # far to near
        width, height = self.size
        index = np.full((height, width), -1, dtype=np.int32)
        corners = np.round(turned[self.triangles, :2] * 16).astype(np.int32)
        for triangle in order:
            cv2.fillConvexPoly(
                index, corners[triangle], int(triangle), lineType=cv2.LINE_8, shift=4
            )
        covered = index >= 0
        ids = index[covered]
        # Per triangle, the affine map from turned (destination) to photo (source) pixels.
        destination = np.concatenate(
            [turned[self.triangles, :2], np.ones((len(self.triangles), 3, 1))], axis=2
        )
        source = self.mesh.points_px[self.triangles, :2]
        maps = np.zeros((len(self.triangles), 3, 2))
        solvable = np.abs(np.linalg.det(destination)) > 1e-9
        maps[solvable] = np.linalg.solve(destination[solvable], source[solvable])
        xs, ys = self._pixel_x[covered], self._pixel_y[covered]
        map_x = np.full((height, width), -1.0, dtype=np.float32)
        map_y = np.full((height, width), -1.0, dtype=np.float32)
        chosen = maps[ids]
        map_x[covered] = chosen[:, 0, 0] * xs + chosen[:, 1, 0] * ys + chosen[:, 2, 0]
        map_y[covered] = chosen[:, 0, 1] * xs + chosen[:, 1, 1] * ys + chosen[:, 2, 1]
        face = cv2.remap(
            self.texture, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
        )
        frame = self.background.copy()
        frame[covered] = face[covered]
        if mouth_open > 0.0 and self.show_mouth_inside:
            inside = np.isin(index, self.mouth_inside)
            paint_inside(frame, inside, turned, self.teeth_bgr, self.mesh.face_width_px)
        return frame


def turn_points(
    points_px: FloatArray, pivot_px: FloatArray, yaw_deg: float, pitch_deg: float = 0.0
) -> FloatArray:
    """(N, 3) points turned as the renderer turns the mesh, about `pivot_px`: nodded by pitch,
    then turned by yaw (pitch is the elevation of the face's forward direction)."""
    yaw, pitch = math.radians(yaw_deg), math.radians(pitch_deg)
    # Image axes: x right, y down, z away from the camera. Positive yaw moves the nose (z < 0
    # relative to the pivot) to +x; positive pitch moves it up (-y).
    rotate_yaw = np.array(
        [
            [math.cos(yaw), 0.0, -math.sin(yaw)],
            [0.0, 1.0, 0.0],
            [math.sin(yaw), 0.0, math.cos(yaw)],
        ]
    )
    rotate_pitch = np.array(
        [
            [1.0, 0.0, 0.0],
            [0.0, math.cos(pitch), math.sin(pitch)],
            [0.0, -math.sin(pitch), math.cos(pitch)],
        ]
    )
    relative = np.asarray(points_px, dtype=np.float64) - pivot_px
    return np.asarray(relative @ (rotate_yaw @ rotate_pitch).T + pivot_px)


def push_pull_fill(
    image: npt.NDArray[np.float32], known: npt.NDArray[np.float32], depth: int = 0
) -> npt.NDArray[np.float32]:
    """Fill pixels where `known` is 0 from a coarser level of a pyramid (push-pull in-painting).

    Gives a smooth blend of the surrounding colours (hair, skin, background) without the streaks of
    `cv2.inpaint`, so the hole left by the original face reads as no face at all.
    """
    import cv2

    height, width = known.shape
    if known.min() > 0:
        return image
    if min(height, width) <= 4 or depth > 12:
        weight = max(float(known.sum()), 1e-6)
        mean = (image * known[..., None]).sum(axis=(0, 1)) / weight
        return np.where(known[..., None] > 0, image, mean).astype(np.float32)
    small_sum = cv2.pyrDown(image * known[..., None])
    small_weight = cv2.pyrDown(known)
    has = small_weight > 1e-3
    small = np.where(has[..., None], small_sum / np.maximum(small_weight, 1e-3)[..., None], 0)
    coarse = push_pull_fill(small.astype(np.float32), has.astype(np.float32), depth + 1)
    up = cv2.pyrUp(coarse, dstsize=(width, height))
    blended = known[..., None] * image + (1.0 - known[..., None]) * up
    return blended.astype(np.float32)
