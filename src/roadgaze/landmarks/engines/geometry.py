"""The facial transformation matrix from 468 landmarks, as MediaPipe's geometry pipeline makes it.

MediaPipe fits its canonical face (the bundle's `geometry_pipeline_metadata_landmarks.binarypb`:
468 vertices in centimetres and the weights of the landmarks the fit uses) to the landmarks seen
through a virtual perspective camera (vertical field of view 63 deg, near plane 1, origin at the
image's top-left; `face_geometry_from_landmarks_graph.cc`, `geometry_pipeline.cc`):

1. screen -> near plane: x, y scaled to the near plane's width and height (y flipped), z by the
   width; the mean z is the depth offset;
2. a first weighted Procrustes fit (rotation, uniform scale, translation) of the canonical face
   to these points (z negated: right- to left-handed) gives a scale s1;
3. z moved to `(z - offset + near) / s1`, x and y unprojected (times z / near), handedness
   changed, and a second fit gives s2;
4. the same with the total scale s1 * s2 gives the metric landmarks, and a last fit the matrix
   (canonical face -> camera space).

The Procrustes solution is the weighted orthogonal one (SVD of the weighted cross-covariance,
reflection removed, least-squares scale; `procrustes_solver.cc`). Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.errors import ModelError

VERTICAL_FOV_DEG = 63.0
NEAR_PLANE = 1.0
MESH_LANDMARKS = 468
VERTEX_FLOATS = 5
"""Mesh3d VERTEX_PT: x, y, z, u, v per vertex."""


def _varint(data: bytes, pos: int) -> tuple[int, int]:
    value = shift = 0
    while True:
        if pos >= len(data):
            raise ValueError("truncated varint")
        byte = data[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return value, pos
        shift += 7


def _fields(data: bytes) -> list[tuple[int, int, bytes | int]]:
    """(field number, wire type, value) of a protobuf message (varint, 32-bit, length-delimited)."""
    found: list[tuple[int, int, bytes | int]] = []
    pos = 0
    while pos < len(data):
        key, pos = _varint(data, pos)
        number, wire = key >> 3, key & 7
        if wire == 0:
            value, pos = _varint(data, pos)
            found.append((number, wire, value))
        elif wire == 5:
            found.append((number, wire, data[pos : pos + 4]))
            pos += 4
        elif wire == 1:
            found.append((number, wire, data[pos : pos + 8]))
            pos += 8
        elif wire == 2:
            length, pos = _varint(data, pos)
            if pos + length > len(data):
                raise ValueError("truncated field")
            found.append((number, wire, data[pos : pos + length]))
            pos += length
        else:
            raise ValueError(f"unsupported wire type {wire}")
    return found


@dataclass(frozen=True, slots=True)
class CanonicalFace:
    """The canonical face (3, 468) in centimetres and the Procrustes weight of each landmark."""

    points: npt.NDArray[np.float64]
    weights: npt.NDArray[np.float64]

    @property
    def basis(self) -> npt.NDArray[np.intp]:
        """The landmarks with a weight (33 in the bundle): the fit reads only these."""
        return np.flatnonzero(self.weights > 0)

    @classmethod
    def from_metadata(cls, data: bytes) -> CanonicalFace:
        """Parsed from `GeometryPipelineMetadata` bytes; ModelError when they are not one."""
        try:
            vertices: list[float] = []
            weights = np.zeros(MESH_LANDMARKS, np.float64)
            for number, wire, value in _fields(data):
                if number == 1 and wire == 2 and isinstance(value, bytes):  # canonical_mesh
                    for field, kind, item in _fields(value):
                        if field == 3 and kind == 2 and isinstance(item, bytes):  # packed floats
                            vertices.extend(np.frombuffer(item, "<f4").tolist())
                        elif field == 3 and kind == 5 and isinstance(item, bytes):
                            vertices.append(float(np.frombuffer(item, "<f4")[0]))
                elif number == 2 and wire == 2 and isinstance(value, bytes):  # landmark basis
                    entry = {f: v for f, _, v in _fields(value)}
                    index, weight = entry.get(1, 0), entry.get(2, b"\0\0\0\0")
                    if isinstance(index, int) and isinstance(weight, bytes):
                        weights[index] = float(np.frombuffer(weight, "<f4")[0])
        except (ValueError, IndexError) as exc:
            raise ModelError(f"unreadable face geometry metadata: {exc}") from None
        if len(vertices) != MESH_LANDMARKS * VERTEX_FLOATS or weights.sum() <= 0:
            raise ModelError(
                f"face geometry metadata has {len(vertices) // VERTEX_FLOATS} vertices and "
                f"weight {weights.sum():.3g}; expected {MESH_LANDMARKS} vertices and weights"
            )
        mesh = np.asarray(vertices, np.float64).reshape(MESH_LANDMARKS, VERTEX_FLOATS)
        return cls(np.ascontiguousarray(mesh[:, :3].T), weights)


def _procrustes(
    source: npt.NDArray[np.float64],
    target: npt.NDArray[np.float64],
    weights: npt.NDArray[np.float64],
) -> npt.NDArray[np.float64]:
    """The 4x4 similarity (scale * rotation, translation) taking `source` (3, N) closest to
    `target` in the weighted least-squares sense (`FloatPrecisionProcrustesSolver`)."""
    sqrt_w = np.sqrt(weights)
    ws, wt = source * sqrt_w, target * sqrt_w
    total = float(weights.sum())
    center = (ws * sqrt_w).sum(axis=1) / total
    centered = ws - center[:, None] * sqrt_w
    u, _, vt = np.linalg.svd(wt @ centered.T)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        u[:, 2] *= -1
    rotation = u @ vt
    scale = float(((rotation @ centered) * wt).sum() / (centered * ws).sum())
    rotation_scale = scale * rotation
    translation = ((wt - rotation_scale @ ws) * sqrt_w).sum(axis=1) / total
    matrix = np.eye(4)
    matrix[:3, :3] = rotation_scale
    matrix[:3, 3] = translation
    return matrix


def transformation_matrix(
    landmarks: npt.NDArray[np.floating], size: tuple[int, int], face: CanonicalFace
) -> npt.NDArray[np.float64] | None:
    """MediaPipe's 4x4 facial transformation matrix of one face from its normalised landmarks
    (the first 468 are used) in an image of `size` (width, height) pixels; None where MediaPipe
    gives none (landmarks collapsed to a point)."""
    mesh = np.asarray(landmarks[:MESH_LANDMARKS], np.float64)
    spread = np.hypot(mesh[:, 0] - mesh[:, 0].mean(), mesh[:, 1] - mesh[:, 1].mean()).max()
    if spread <= 1e-3:
        return None
    height_near = 2.0 * NEAR_PLANE * math.tan(0.5 * math.radians(VERTICAL_FOV_DEG))
    width_near = size[0] * height_near / size[1]
    depth_offset = float(mesh[:, 2].mean()) * width_near
    # Only the weighted landmarks enter the fits (the others have weight 0); the depth offset
    # is the mean over all of them.
    basis = face.basis
    source, weights = face.points[:, basis], face.weights[basis]
    screen = mesh[basis].T.copy()
    screen[1] = 1.0 - screen[1]
    screen *= np.array([[width_near], [height_near], [width_near]])
    screen[0] -= 0.5 * width_near
    screen[1] -= 0.5 * height_near

    def scale_of(points: npt.NDArray[np.float64]) -> float:
        return float(np.linalg.norm(_procrustes(source, points, weights)[:3, 0]))

    def to_metric(scale: float) -> npt.NDArray[np.float64]:
        points = screen.copy()
        points[2] = (points[2] - depth_offset + NEAR_PLANE) / scale
        points[:2] *= points[2] / NEAR_PLANE
        points[2] *= -1.0
        return points

    flipped = screen.copy()
    flipped[2] *= -1.0
    first = scale_of(flipped)
    second = scale_of(to_metric(first))
    return _procrustes(source, to_metric(first * second), weights)
