"""Synthetic ground-truth clips: one real photo's face mesh turned to known yaws and re-rendered.

A timeline such as `0:2,40:3.5,0:2,-35:1,0:2` lists keyframes `YAW[/PITCH]:SECONDS`: in each
segment the head turns to YAW (and PITCH, default 0) degrees during the first `transition_s`
seconds with a cosine ease, then holds it for the rest of the segment; the first segment starts
already at its pose. Yaw > 0 turns the head to the person's own left (the nose moves to the image
right), pitch > 0 looks up, both relative to the photo's own head pose.

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

import csv
import importlib.resources
import logging
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.config import Config
from roadgaze.errors import ConfigError, RoadgazeError, SourceError
from roadgaze.landmarks import FACE_OVAL

log = logging.getLogger(__name__)

FloatArray = npt.NDArray[np.float64]
ImageBGR = npt.NDArray[np.uint8]

MAX_ABS_YAW_DEG = 80.0
MAX_ABS_PITCH_DEG = 40.0
MAX_CLIP_S = 3600.0
DEFAULT_TRANSITION_S = 0.5
DEFAULT_FPS = 15.0
DEFAULT_SIZE = (320, 320)
PIVOT_DEPTH_HALF_WIDTHS = 1.5
"""Neck pivot behind the nose tip in half face widths: the paper's alpha + beta = 0.25 + 1.25."""
FACE_WIDTH_FRACTION = 0.32
"""Face width in the output frame as a fraction of the frame's smaller side."""
TESSELLATION_TRIANGLES = 852
NOSE_TIP = 1
CHIN = 152
TRUTH_HEADER = ("t_s", "yaw_deg", "pitch_deg")
FOURCC_BY_SUFFIX = {".mp4": "mp4v", ".avi": "MJPG", ".mkv": "FFV1"}


@dataclass(frozen=True, slots=True)
class Keyframe:
    """Turn to `yaw_deg`/`pitch_deg` at the start of a segment of `duration_s` and hold it."""

    yaw_deg: float
    pitch_deg: float
    duration_s: float


@dataclass(frozen=True, slots=True)
class Timeline:
    """Keyframes with cosine-eased transitions of `transition_s` between them."""

    keyframes: tuple[Keyframe, ...]
    transition_s: float = DEFAULT_TRANSITION_S

    @property
    def duration_s(self) -> float:
        return sum(k.duration_s for k in self.keyframes)

    def pose_at(self, t_s: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Yaw and pitch in degrees at times `t_s` (seconds; clamped to the timeline)."""
        t = np.asarray(t_s, dtype=np.float64)
        yaw = np.full(t.shape, self.keyframes[0].yaw_deg)
        pitch = np.full(t.shape, self.keyframes[0].pitch_deg)
        start_s = 0.0
        previous = self.keyframes[0]
        for keyframe in self.keyframes:
            ramp_s = min(self.transition_s, keyframe.duration_s / 2.0)
            if ramp_s > 0.0:
                progress = np.clip((t - start_s) / ramp_s, 0.0, 1.0)
            else:
                progress = np.ones_like(t)
            ease = 0.5 - 0.5 * np.cos(np.pi * progress)
            in_segment = t >= start_s
            yaw = np.where(
                in_segment, previous.yaw_deg + (keyframe.yaw_deg - previous.yaw_deg) * ease, yaw
            )
            pitch = np.where(
                in_segment,
                previous.pitch_deg + (keyframe.pitch_deg - previous.pitch_deg) * ease,
                pitch,
            )
            start_s += keyframe.duration_s
            previous = keyframe
        return yaw, pitch

    def truth(self, fps: float) -> FloatArray:
        """(N, 3) rows `t_s, yaw_deg, pitch_deg` at `i / fps`; N = round(duration * fps)."""
        n_frames = max(1, round(self.duration_s * fps))
        t = np.arange(n_frames, dtype=np.float64) / fps
        yaw, pitch = self.pose_at(t)
        return np.column_stack([t, yaw, pitch])


def _number(text: str, what: str, item: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ConfigError(
            f"timeline keyframe '{item}': {what} '{text}' is not a number "
            "(expected YAW[/PITCH]:SECONDS, e.g. 40:3.5 or 30/-10:2)"
        ) from None
    if not math.isfinite(value):
        raise ConfigError(f"timeline keyframe '{item}': {what} must be finite, found '{text}'")
    return value


def parse_timeline(spec: str, transition_s: float = DEFAULT_TRANSITION_S) -> Timeline:
    """Parse `YAW[/PITCH]:SECONDS,...` (degrees, seconds); raises ConfigError naming the bad item.

    Yaw must lie within +-80 deg, pitch within +-40 deg, each duration must be positive and the
    whole timeline at most an hour.
    """
    if not math.isfinite(transition_s) or transition_s < 0:
        raise ConfigError(f"transition must be a finite number >= 0 s, found {transition_s}")
    items = [item.strip() for item in spec.split(",")]
    if not spec.strip() or any(not item for item in items):
        raise ConfigError(
            f"timeline '{spec}' has an empty keyframe; expected comma-separated YAW[/PITCH]:SECONDS"
            " items, e.g. '0:2,40:3.5,0:2'"
        )
    keyframes = []
    for item in items:
        pose, sep, seconds = item.partition(":")
        if not sep or ":" in seconds:
            raise ConfigError(
                f"timeline keyframe '{item}' must be YAW[/PITCH]:SECONDS (one colon), e.g. 40:3.5"
            )
        yaw_text, slash, pitch_text = pose.partition("/")
        yaw_deg = _number(yaw_text, "yaw", item)
        pitch_deg = _number(pitch_text, "pitch", item) if slash else 0.0
        duration_s = _number(seconds, "duration", item)
        if abs(yaw_deg) > MAX_ABS_YAW_DEG:
            raise ConfigError(
                f"timeline keyframe '{item}': yaw {yaw_deg:g} deg is outside "
                f"+-{MAX_ABS_YAW_DEG:g} deg (a face mesh seen from the side cannot be rendered)"
            )
        if abs(pitch_deg) > MAX_ABS_PITCH_DEG:
            raise ConfigError(
                f"timeline keyframe '{item}': pitch {pitch_deg:g} deg is outside "
                f"+-{MAX_ABS_PITCH_DEG:g} deg"
            )
        if duration_s <= 0:
            raise ConfigError(
                f"timeline keyframe '{item}': duration must be > 0 s, found {duration_s:g}"
            )
        keyframes.append(Keyframe(yaw_deg, pitch_deg, duration_s))
    timeline = Timeline(tuple(keyframes), transition_s)
    if timeline.duration_s > MAX_CLIP_S:
        raise ConfigError(
            f"timeline lasts {timeline.duration_s:g} s; at most {MAX_CLIP_S:g} s is allowed"
        )
    return timeline


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
    from roadgaze.landmarks import MediaPipeLandmarker

    config = config if config is not None else Config()
    with MediaPipeLandmarker.from_config(config, video=False) as landmarker:
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
        self.triangles = mesh_triangles()
        self._front_sign = self._majority_sign(points)
        backwards = self._signed_areas(points) * self._front_sign < 0
        backwards[:TESSELLATION_TRIANGLES] = False  # only the hole fillers have no set winding
        self.triangles[backwards] = self.triangles[backwards][:, ::-1]
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

    def _inpaint_face(self, cv2: Any) -> ImageBGR:
        """The texture with the face area (dilated by 6 % of the face width) filled smoothly."""
        mask = np.zeros(self.texture.shape[:2], dtype=np.uint8)
        hull = cv2.convexHull(np.round(self.mesh.points_px[:, :2]).astype(np.int32))
        cv2.fillConvexPoly(mask, hull, 255)
        grow = max(3, round(0.06 * self.mesh.face_width_px))
        mask = cv2.dilate(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * grow + 1,) * 2))
        known = (mask == 0).astype(np.float32)
        filled = _push_pull_fill(self.texture.astype(np.float32), known)
        background: ImageBGR = np.clip(filled + 0.5, 0, 255).astype(np.uint8)
        return background

    def turned_points(self, yaw_deg: float, pitch_deg: float = 0.0) -> FloatArray:
        """The mesh turned by yaw (about the vertical axis) then pitch, about the neck pivot."""
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
        relative = self.mesh.points_px - self.mesh.pivot_px
        return np.asarray(relative @ (rotate_pitch @ rotate_yaw).T + self.mesh.pivot_px)

    def render(self, yaw_deg: float, pitch_deg: float = 0.0) -> ImageBGR:
        """One BGR frame of the face turned to `yaw_deg`, `pitch_deg` over the background."""
        import cv2

        turned = self.turned_points(yaw_deg, pitch_deg)
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
        return frame


def _push_pull_fill(
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
    coarse = _push_pull_fill(small.astype(np.float32), has.astype(np.float32), depth + 1)
    up = cv2.pyrUp(coarse, dstsize=(width, height))
    blended = known[..., None] * image + (1.0 - known[..., None]) * up
    return blended.astype(np.float32)


def truth_path_for(video_path: Path) -> Path:
    """`clip.mp4` -> `clip.truth.csv`, beside the video."""
    return video_path.with_name(video_path.stem + ".truth.csv")


def write_truth_csv(path: Path, truth: FloatArray) -> None:
    """Write rows `t_s,yaw_deg,pitch_deg` with a header."""
    with Path(path).open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(TRUTH_HEADER)
        for t_s, yaw_deg, pitch_deg in truth:
            writer.writerow((f"{t_s:.4f}", f"{yaw_deg:.4f}", f"{pitch_deg:.4f}"))


def read_truth_csv(path: Path) -> FloatArray:
    """Read a truth CSV written by `write_truth_csv` as an (N, 3) array; raises SourceError."""
    try:
        with Path(path).open(newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
    except OSError as exc:
        raise SourceError(f"cannot read truth file {path}: {exc}") from None
    if not rows or tuple(rows[0]) != TRUTH_HEADER:
        raise SourceError(f"truth file {path} must start with the header {','.join(TRUTH_HEADER)}")
    try:
        return np.array([[float(v) for v in row] for row in rows[1:]], dtype=np.float64).reshape(
            -1, 3
        )
    except ValueError as exc:
        raise SourceError(f"truth file {path} has a bad row: {exc}") from None


def render_frames(
    timeline: Timeline, renderer: FaceRenderer, fps: float = DEFAULT_FPS
) -> Iterator[tuple[FloatArray, ImageBGR]]:
    """Yield (truth row `t_s, yaw_deg, pitch_deg`, BGR frame) for every frame of the timeline."""
    for row in timeline.truth(fps):
        yield row, renderer.render(float(row[1]), float(row[2]))


def render_clip(
    timeline: Timeline | str,
    out_path: Path | str,
    photo: Path | None = None,
    fps: float = DEFAULT_FPS,
    size: tuple[int, int] = DEFAULT_SIZE,
    renderer: FaceRenderer | None = None,
    config: Config | None = None,
) -> FloatArray:
    """Render the timeline to a video and its `<stem>.truth.csv`; return the (N, 3) truth.

    The container follows the suffix: .mp4 (mp4v), .avi (MJPG) or .mkv (FFV1, lossless). Pass a
    `renderer` to reuse one already built for the same photo and size. Raises ConfigError for a bad
    timeline, size, fps or suffix and SourceError for an unreadable photo or one without a face.
    """
    import cv2

    if isinstance(timeline, str):
        timeline = parse_timeline(timeline)
    if not math.isfinite(fps) or not 1.0 <= fps <= 240.0:
        raise ConfigError(f"fps must be within 1..240, found {fps}")
    out = Path(out_path)
    fourcc = FOURCC_BY_SUFFIX.get(out.suffix.lower())
    if fourcc is None:
        raise ConfigError(
            f"cannot write '{out.suffix}' video {out}; use one of {', '.join(FOURCC_BY_SUFFIX)}"
        )
    if renderer is None:
        renderer = FaceRenderer(load_photo(photo), size, config=config)
    elif renderer.size != tuple(size):
        size = renderer.size
    out.parent.mkdir(parents=True, exist_ok=True)
    writer = cv2.VideoWriter(str(out), cv2.VideoWriter.fourcc(*fourcc), fps, renderer.size)
    if not writer.isOpened():
        raise RoadgazeError(f"cannot open {out} for writing a {fourcc} video; check the folder")
    rows = []
    try:
        for row, frame in render_frames(timeline, renderer, fps):
            writer.write(frame)
            rows.append(row)
    finally:
        writer.release()
    truth = np.asarray(rows, dtype=np.float64).reshape(-1, 3)
    write_truth_csv(truth_path_for(out), truth)
    return truth


YAW_RANGES_DEG: tuple[tuple[float, float], ...] = (
    (0.0, 15.0),
    (15.0, 30.0),
    (30.0, 45.0),
    (45.0, 60.0),
)
"""The |true yaw| ranges the measurement reports on; each includes its low end, the last both."""


@dataclass(frozen=True, slots=True)
class RangeError:
    """Errors (estimate minus truth, degrees) of the frames whose |true yaw| lies in a range."""

    low_deg: float
    high_deg: float
    frames: int
    estimated: int
    """Frames with a face and a finite estimate; the errors are over these."""
    mae_deg: float
    bias_deg: float
    """Mean signed error of the frames with positive truth minus that of negative truth, halved:
    the part of the error that grows with |yaw| (an offset common to both signs cancels)."""
    offset_deg: float
    """Mean signed error over the range: the part common to both signs."""
    max_error_deg: float


@dataclass(frozen=True, slots=True)
class YawRecovery:
    """Yaw estimated on a rendered sweep against its truth."""

    truth_deg: FloatArray
    estimate_deg: FloatArray
    """NaN where no face was found or the yaw model could not explain the geometry."""
    ranges: tuple[RangeError, ...]
    overall: RangeError
    mesh_estimate_deg: FloatArray
    """The same yaw model on the turned mesh's own landmarks (a perfect landmarker): separates
    the face model's and the mesh's share of the error from the landmarker's."""
    mesh_ranges: tuple[RangeError, ...]
    mesh_overall: RangeError
    model: str
    size: tuple[int, int]
    video: bool


def range_error(
    truth_deg: FloatArray, estimate_deg: FloatArray, low_deg: float, high_deg: float, last: bool
) -> RangeError:
    """Errors of the frames with low <= |truth| < high (<= high when `last`)."""
    magnitude = np.abs(truth_deg)
    inside = (magnitude >= low_deg) & ((magnitude <= high_deg) if last else (magnitude < high_deg))
    valid = inside & np.isfinite(estimate_deg)
    error = estimate_deg[valid] - truth_deg[valid]
    sign = np.sign(truth_deg[valid])
    nan = float("nan")

    def mean(values: FloatArray) -> float:
        return float(values.mean()) if values.size else nan

    positive, negative = mean(error[sign > 0]), mean(error[sign < 0])
    return RangeError(
        low_deg=low_deg,
        high_deg=high_deg,
        frames=int(inside.sum()),
        estimated=int(valid.sum()),
        mae_deg=mean(np.abs(error)),
        bias_deg=0.5 * (positive - negative),
        offset_deg=mean(error),
        max_error_deg=float(np.abs(error).max()) if error.size else nan,
    )


def measure_yaw_recovery(
    config: Config | None = None,
    photo: Path | None = None,
    size: tuple[int, int] = DEFAULT_SIZE,
    step_deg: float = 1.0,
    max_yaw_deg: float = 60.0,
    video: bool = True,
    renderer: FaceRenderer | None = None,
) -> YawRecovery:
    """Render a yaw sweep -max..max in `step_deg` steps and estimate each frame's yaw.

    The estimate is the landmark stage (MediaPipe, the configured landmark choice) followed by the
    configured yaw model (Center-CE by default), exactly as `Pipeline.raw_yaw_deg` computes it.
    `video`: run the landmarker in VIDEO mode over the sweep as a 15 fps clip (as the service
    does); False: each still in IMAGE mode.
    """
    from roadgaze.landmarks import MediaPipeLandmarker, features_from_landmarks
    from roadgaze.model_store import resolve_model
    from roadgaze.pipeline import Pipeline

    config = config if config is not None else Config()
    renderer = (
        renderer if renderer is not None else FaceRenderer(load_photo(photo), size, config=config)
    )
    count = round(2 * max_yaw_deg / step_deg) + 1
    truth = np.linspace(-max_yaw_deg, max_yaw_deg, count)
    estimate = np.full(count, np.nan)
    mesh_estimate = np.full(count, np.nan)
    model_path = resolve_model(config.model)
    with MediaPipeLandmarker(config.landmarks, model_path, video=video) as detector:
        pipeline = Pipeline.from_config(config, detector)
        for index, yaw_deg in enumerate(truth):
            image = renderer.render(float(yaw_deg))
            detection = detector.detect(image, index / DEFAULT_FPS if video else None)
            value = pipeline.raw_yaw_deg(detection.driver)
            if value is not None:
                estimate[index] = value
            exact = features_from_landmarks(renderer.turned_points(float(yaw_deg)), renderer.size)
            value = pipeline.raw_yaw_deg(exact)
            if value is not None:
                mesh_estimate[index] = value
    last = len(YAW_RANGES_DEG) - 1

    def by_range(values: FloatArray) -> tuple[RangeError, ...]:
        return tuple(
            range_error(truth, values, low, high, i == last)
            for i, (low, high) in enumerate(YAW_RANGES_DEG)
            if low < max_yaw_deg
        )

    return YawRecovery(
        truth_deg=truth,
        estimate_deg=estimate,
        ranges=by_range(estimate),
        overall=range_error(truth, estimate, 0.0, max_yaw_deg, True),
        mesh_estimate_deg=mesh_estimate,
        mesh_ranges=by_range(mesh_estimate),
        mesh_overall=range_error(truth, mesh_estimate, 0.0, max_yaw_deg, True),
        model=config.geometry.model,
        size=renderer.size,
        video=video,
    )


def format_measurement(result: YawRecovery) -> str:
    """Per range: frames, detections, MAE, bias, offset and max error, then the same model's MAE
    and bias on the turned mesh's own landmarks."""
    mode = "VIDEO mode sweep" if result.video else "IMAGE mode stills"
    lines = [
        f"yaw recovery on synthetic frames ({result.size[0]}x{result.size[1]}, {mode}, "
        f"model {result.model}); errors are estimate - truth in degrees",
        f"{'|yaw| range':>12} {'frames':>6} {'found':>6} {'MAE':>6} {'bias':>6} {'offset':>7} "
        f"{'max':>6} | {'mesh MAE':>8} {'mesh bias':>9}",
    ]
    rows = zip(
        (*result.ranges, result.overall), (*result.mesh_ranges, result.mesh_overall), strict=True
    )
    for item, mesh in rows:
        label = f"{item.low_deg:g}-{item.high_deg:g}"
        lines.append(
            f"{label:>12} {item.frames:>6} {item.estimated:>6} {item.mae_deg:>6.2f} "
            f"{item.bias_deg:>+6.2f} {item.offset_deg:>+7.2f} {item.max_error_deg:>6.2f} | "
            f"{mesh.mae_deg:>8.2f} {mesh.bias_deg:>+9.2f}"
        )
    lines.append(
        "bias: half the difference of the mean errors at positive and negative yaw (< 0: the "
        "magnitude is underestimated); offset: mean error common to both signs; mesh: the same "
        "model on the rendered mesh's exact landmarks (no landmarker error)."
    )
    return "\n".join(lines)


def write_measurement_csv(path: Path, result: YawRecovery) -> None:
    """Rows `truth_yaw_deg,estimate_yaw_deg,error_deg,mesh_estimate_yaw_deg` (empty: none)."""
    with Path(path).open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(("truth_yaw_deg", "estimate_yaw_deg", "error_deg", "mesh_estimate_yaw_deg"))
        rows = zip(result.truth_deg, result.estimate_deg, result.mesh_estimate_deg, strict=True)
        for truth, estimate, mesh in rows:
            found = math.isfinite(estimate)
            writer.writerow(
                (
                    f"{truth:.3f}",
                    f"{estimate:.3f}" if found else "",
                    f"{estimate - truth:.3f}" if found else "",
                    f"{mesh:.3f}" if math.isfinite(mesh) else "",
                )
            )
