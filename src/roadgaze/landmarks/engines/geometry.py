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
from dataclasses import dataclass, field

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
class _FitSource:
    """The canonical face's side of the weighted Procrustes fits, computed once per bundle.

    Only the weighted landmarks (33 of 468 in the bundle) enter a fit, and per frame only the
    target changes. What remains per frame is a few numpy calls on (3, 33) arrays; at that size
    a call's fixed cost (microseconds) is what a fit costs, not its arithmetic, so the fits
    make as few calls as they can.
    """

    basis: npt.NDArray[np.intp]
    """The weighted landmarks."""
    sqrt_weights: npt.NDArray[np.float64]
    center: npt.NDArray[np.float64]
    """The weighted mean of the source points (3,)."""
    centered_t: npt.NDArray[np.float64]
    """sqrt(weight) * (source - center), transposed (N, 3): the cross-covariance's right side."""
    norm: float
    """sum(weight * (source - center) . source): the least-squares scale's denominator."""
    mean_weights: npt.NDArray[np.float64]
    """weight / sum(weight): `target @ mean_weights` is the target's weighted mean."""

    @classmethod
    def of(cls, points: npt.NDArray[np.float64], weights: npt.NDArray[np.float64]) -> _FitSource:
        basis = np.flatnonzero(weights > 0)
        source, used = points[:, basis], weights[basis]
        sqrt_weights = np.sqrt(used)
        weighted = source * sqrt_weights
        total = float(used.sum())
        center = (weighted * sqrt_weights).sum(axis=1) / total
        centered = weighted - center[:, None] * sqrt_weights
        return cls(
            basis,
            sqrt_weights,
            center,
            np.ascontiguousarray(centered.T),
            float((centered * weighted).sum()),
            used / total,
        )


@dataclass(frozen=True, slots=True)
class CanonicalFace:
    """The canonical face (3, 468) in centimetres and the Procrustes weight of each landmark."""

    points: npt.NDArray[np.float64]
    weights: npt.NDArray[np.float64]
    fit: _FitSource = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "fit", _FitSource.of(self.points, self.weights))

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


def _det3(matrix: npt.NDArray[np.float64]) -> float:
    """The determinant of a 3x3 matrix in Python floats (a tenth of np.linalg.det's 7 us; the
    fits only read its sign)."""
    (a, b, c), (d, e, f), (g, h, i) = matrix.tolist()
    return float(a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g))


def _cross(fit: _FitSource, target: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The weighted cross-covariance (3x3) of `target` (3, N over `fit.basis`) and the
    canonical face."""
    cross: npt.NDArray[np.float64] = (target * fit.sqrt_weights).dot(fit.centered_t)
    return cross


def _scale(fit: _FitSource, singular: list[float], reflection: bool) -> float:
    """The least-squares scale of a fit whose cross-covariance has these singular values.

    The solver's scale is sum((rotation @ centered) * weighted_target) / `fit.norm`, the trace
    of rotation.T @ cross; with cross = u s vt and rotation = u vt (the last axis of u negated
    against a reflection), that trace is s1 + s2 + s3 (s1 + s2 - s3).
    """
    s1, s2, s3 = singular
    return (s1 + s2 - s3 if reflection else s1 + s2 + s3) / fit.norm


def _scale_of(fit: _FitSource, target: npt.NDArray[np.float64]) -> float:
    """The scale of the weighted orthogonal Procrustes fit of the canonical face to `target`
    (3, N over `fit.basis`), from the singular values alone (half the SVD's cost): det(cross)
    has the sign of det(u) det(vt), singular values being >= 0 (where it is 0, so is s3)."""
    cross = _cross(fit, target)
    singular = np.linalg.svd(cross, compute_uv=False).tolist()
    return _scale(fit, singular, _det3(cross) < 0)


def _procrustes(fit: _FitSource, target: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The 4x4 similarity (scale * rotation, translation) taking the canonical face closest to
    `target` (3, N over `fit.basis`) in the weighted least-squares sense
    (`FloatPrecisionProcrustesSolver`: SVD of the cross-covariance, reflection removed,
    least-squares scale); the translation maps the source's weighted mean onto the target's."""
    u, singular, vt = np.linalg.svd(_cross(fit, target))
    reflection = _det3(u) * _det3(vt) < 0
    if reflection:
        u[:, 2] *= -1
    rotation_scale = _scale(fit, singular.tolist(), reflection) * u.dot(vt)
    matrix = np.empty((4, 4))
    matrix[:3, :3] = rotation_scale
    matrix[:3, 3] = target.dot(fit.mean_weights) - rotation_scale.dot(fit.center)
    matrix[3] = (0.0, 0.0, 0.0, 1.0)
    return matrix


def transformation_matrix(
    landmarks: npt.NDArray[np.floating], size: tuple[int, int], face: CanonicalFace
) -> npt.NDArray[np.float64] | None:
    """MediaPipe's 4x4 facial transformation matrix of one face from its normalised landmarks
    (the first 468 are used) in an image of `size` (width, height) pixels; None where MediaPipe
    gives none (landmarks collapsed to a point)."""
    mesh = np.asarray(landmarks[:MESH_LANDMARKS], np.float64)
    x, y, z = mesh.T
    # Sums over 1-D columns (numpy reduces (N, 3) along axis 0 several times slower); squared
    # distances (np.hypot takes 30 ns a point).
    dx, dy = x - x.sum() / len(mesh), y - y.sum() / len(mesh)
    dx *= dx
    dy *= dy
    dx += dy
    if math.sqrt(dx.max()) <= 1e-3:
        return None
    height_near = 2.0 * NEAR_PLANE * math.tan(0.5 * math.radians(VERTICAL_FOV_DEG))
    width_near = size[0] * height_near / size[1]
    depth_offset = float(z.sum()) / len(mesh) * width_near
    # Only the weighted landmarks enter the fits (the others have weight 0); the depth offset
    # is the mean over all of them.
    fit = face.fit
    screen = mesh.take(fit.basis, axis=0).T
    np.subtract(1.0, screen[1], out=screen[1])
    screen *= ((width_near,), (height_near,), (width_near,))
    screen -= ((0.5 * width_near,), (0.5 * height_near,), (0.0,))
    depth_base = screen[2] - depth_offset + NEAR_PLANE

    def to_metric(scale: float) -> npt.NDArray[np.float64]:
        depth = depth_base / scale
        points = np.empty_like(screen)
        np.multiply(screen[:2], depth / NEAR_PLANE, out=points[:2])
        np.negative(depth, out=points[2])
        return points

    first = _scale_of(fit, screen * ((1.0,), (1.0,), (-1.0,)))
    second = _scale_of(fit, to_metric(first))
    return _procrustes(fit, to_metric(first * second))
