"""The LiteRT engine against MediaPipe's FaceLandmarker, the contract between the two engines.

IMAGE mode and streams with several faces run the same detector input, so the two engines agree
to numerical noise (measured: 0.009 px, 0.006 deg). A one-face stream tracks the face from the
previous frame's landmarks and smooths them (MediaPipe's one-euro filter, beta 80): there a
difference of 0.01 px in one frame's landmarks moves the next frame's crop, and the engines drift
apart by what MediaPipe itself drifts when invisible noise is added to its input (on the demo
drive, MediaPipe against MediaPipe with 1 % of the pixels' lowest bit flipped: landmarks p99
0.32 px, yaw p99 0.40 deg, matrix pitch p99 0.21 deg; LiteRT against MediaPipe: 0.35 px,
0.43 deg, 0.41 deg). The bounds below are those figures with margin; the equal faces, equal
eye openness and equal alerts hold exactly.
"""

from __future__ import annotations

import math
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from repo_paths import POINTING04, VIDEOS
from roadgaze.config import Config, LandmarksConfig, load_config
from roadgaze.errors import ModelError
from roadgaze.landmarks import Landmarker, MediaPipeLandmarker
from roadgaze.landmarks.engines import graph
from roadgaze.landmarks.engines.geometry import (
    CanonicalFace,
    _procrustes,
    _scale_of,
    transformation_matrix,
)
from roadgaze.landmarks.features import angles_from_matrix_deg
from roadgaze.landmarks.model_store import resolve_model
from roadgaze.types import Detection

litert = pytest.importorskip("ai_edge_litert.interpreter", reason="ai-edge-litert not installed")

STILLS = (
    "Person01/person01146+0+0.jpg",
    "Person02/person02118-30-30.jpg",
    "Person03/person03122-30+30.jpg",
    "Person04/person04142+0-60.jpg",
    "Person05/person05160+15+15.jpg",
    "Person06/person06150+0+60.jpg",
)


@pytest.fixture(scope="module")
def model_path() -> Path:
    return resolve_model(load_config(environ={}).model)


@pytest.fixture(scope="module")
def canonical_face(model_path: Path) -> CanonicalFace:
    with zipfile.ZipFile(model_path) as bundle:
        return CanonicalFace.from_metadata(
            bundle.read("geometry_pipeline_metadata_landmarks.binarypb")
        )


def gif_frames(name: str, limit: int) -> list[np.ndarray[Any, Any]]:
    capture = cv2.VideoCapture(str(VIDEOS / name))
    frames = []
    while len(frames) < limit:
        ok, frame = capture.read()
        if not ok:
            break
        frames.append(frame)
    capture.release()
    return frames


def both_engines(
    model_path: Path, config: LandmarksConfig, video: bool
) -> Iterator[tuple[Landmarker, Landmarker]]:
    with (
        Landmarker(config, model_path, video=video, engine="litert") as fast,
        MediaPipeLandmarker(config, model_path, video=video) as reference,
    ):
        assert fast.engine == "litert" and reference.engine == "mediapipe"
        yield fast, reference


def compare(fast: Detection, reference: Detection) -> tuple[float, float, float]:
    """Max landmark distance (px), |yaw| and |pitch| difference of MediaPipe's matrix (deg)."""
    assert len(fast.faces) == len(reference.faces)
    assert fast.driver_index == reference.driver_index
    worst = (0.0, 0.0, 0.0)
    for a, b in zip(fast.faces, reference.faces, strict=True):
        assert a.mediapipe_yaw_deg is not None and b.mediapipe_yaw_deg is not None
        assert a.mediapipe_pitch_deg is not None and b.mediapipe_pitch_deg is not None
        distance = float(np.abs(a.landmarks_px[:, :2] - b.landmarks_px[:, :2]).max())
        yaw = abs(a.mediapipe_yaw_deg - b.mediapipe_yaw_deg)
        pitch = abs(a.mediapipe_pitch_deg - b.mediapipe_pitch_deg)
        worst = (max(worst[0], distance), max(worst[1], yaw), max(worst[2], pitch))
        assert a.blendshapes is not None and b.blendshapes is not None
        assert max(abs(a.blendshapes[k] - b.blendshapes[k]) for k in b.blendshapes) < 0.01
    return worst


@pytest.mark.skipif(not POINTING04.is_dir(), reason=f"no data at {POINTING04}")
def test_stills_equal_mediapipe(model_path: Path) -> None:
    """IMAGE mode on Pointing'04 dev stills: the same faces, landmarks, matrix and blendshapes."""
    for fast, reference in both_engines(model_path, LandmarksConfig(), video=False):
        for name in STILLS:
            image = cv2.imread(str(POINTING04 / "images" / name))
            worst = compare(fast.detect(image), reference.detect(image))
            assert worst[0] < 0.05 and worst[1] < 0.02 and worst[2] < 0.02, (name, worst)


@pytest.mark.skipif(not VIDEOS.is_dir(), reason=f"no data at {VIDEOS}")
def test_two_face_stream_equals_mediapipe(model_path: Path) -> None:
    """A stream with two faces (the detector runs on every frame): equal, the same driver."""
    frames = gif_frames("head-pose-face-detection-female-and-male.gif", 12)
    for fast, reference in both_engines(model_path, LandmarksConfig(), video=True):
        for index, frame in enumerate(frames):
            t_s = index / 15.0
            worst = compare(fast.detect(frame, t_s), reference.detect(frame, t_s))
            assert worst[0] < 0.05 and worst[1] < 0.02 and worst[2] < 0.02, (index, worst)


def tracked_stream_differences(
    model_path: Path, frames: list[np.ndarray[Any, Any]]
) -> dict[str, np.ndarray[Any, Any]]:
    found: dict[str, list[float]] = {"px": [], "yaw": [], "pitch": [], "openness": []}
    for fast, reference in both_engines(model_path, LandmarksConfig(), video=True):
        for index, frame in enumerate(frames):
            a, b = fast.detect(frame, index / 15.0), reference.detect(frame, index / 15.0)
            assert len(a.faces) == len(b.faces) == 1
            face_a, face_b = a.faces[0], b.faces[0]
            found["px"] += list(np.abs(face_a.landmarks_px - face_b.landmarks_px)[:, :2].max(1))
            assert face_a.mediapipe_yaw_deg is not None and face_b.mediapipe_yaw_deg is not None
            assert face_a.mediapipe_pitch_deg is not None and face_b.mediapipe_pitch_deg is not None
            found["yaw"].append(abs(face_a.mediapipe_yaw_deg - face_b.mediapipe_yaw_deg))
            found["pitch"].append(abs(face_a.mediapipe_pitch_deg - face_b.mediapipe_pitch_deg))
    return {key: np.asarray(values) for key, values in found.items()}


@pytest.mark.skipif(not VIDEOS.is_dir(), reason=f"no data at {VIDEOS}")
def test_tracked_stream_within_mediapipes_own_noise(model_path: Path) -> None:
    """One face, tracked and smoothed: landmarks within 1 px at p99, angles within the drift
    MediaPipe shows against itself (see the module docstring)."""
    differences = tracked_stream_differences(
        model_path, gif_frames("head-pose-face-detection-female.gif", 23)
    )
    assert np.percentile(differences["px"], 99) < 1.0
    assert np.median(differences["px"]) < 0.05
    assert np.median(differences["yaw"]) < 0.05 and differences["yaw"].max() < 1.0
    assert np.median(differences["pitch"]) < 0.05 and differences["pitch"].max() < 1.0


def test_rendered_drive_gives_the_same_records(synthetic_clip: Any) -> None:
    """The whole loop on a rendered drive: the same faces, yaw and pitch within the bounds above,
    eye openness within 0.01, the same alerts at the same times."""
    from test_pipeline_synthetic import run_pipeline

    path, _ = synthetic_clip("0:1.5,0/-35:4,0:1.5")  # a lap look (-35 yaw is a mirror glance)
    records = {}
    for engine in ("litert", "mediapipe"):
        base = Config()
        landmarks = base.landmarks.model_copy(update={"engine": engine})
        records[engine] = run_pipeline(path, base.model_copy(update={"landmarks": landmarks}))
    fast, reference = records["litert"].records, records["mediapipe"].records
    assert [r.sample.face for r in fast] == [r.sample.face for r in reference]
    for name in ("yaw_raw_deg", "pitch_raw_deg"):
        a = np.array([getattr(r.sample, name) or math.nan for r in fast])
        b = np.array([getattr(r.sample, name) or math.nan for r in reference])
        assert np.nanpercentile(np.abs(a - b), 50) < 0.05 and np.nanmax(np.abs(a - b)) < 1.0
    for a_record, b_record in zip(fast, reference, strict=True):
        a_eyes, b_eyes = a_record.sample.eyes, b_record.sample.eyes
        if a_eyes is not None and b_eyes is not None and b_eyes.openness is not None:
            assert a_eyes.openness is not None and abs(a_eyes.openness - b_eyes.openness) < 0.01

    def alerts(items: list[Any]) -> list[tuple[float, str]]:
        return [(r.sample.t_s, str(alert.kind)) for r in items for alert in r.alerts]

    assert alerts(fast) == alerts(reference) and alerts(reference)


# ---------------------------------------------------------------- the graph's rules, no models


def test_anchors_and_rects() -> None:
    anchors = graph.ssd_anchors()
    assert anchors.shape == (896, 2)
    assert np.allclose(anchors[0], [0.5 / 16, 0.5 / 16]) and np.allclose(anchors[-1], [7.5 / 8] * 2)
    assert graph.normalize_radians(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    points = np.zeros((478, 3))
    points[:, :2] = [0.4, 0.5]
    points[33, :2], points[263, :2] = [0.3, 0.5], [0.6, 0.5]  # eyes level, 0.3 wide
    rect = graph.landmarks_rect(points, (640, 480))
    # A 0.3 x 0 box in a 640x480 image: its long side is 192 px, squared and scaled by 1.5.
    assert rect.width == pytest.approx(1.5 * 192 / 640) and rect.height == pytest.approx(0.6)
    assert rect.rotation == 0.0 and rect.x_center == pytest.approx(0.45)
    tracked = [graph.Rect(0.5, 0.5, 0.2, 0.2)]
    moved = graph.Rect(0.52, 0.5, 0.2, 0.2)
    assert graph.associate(tracked, [moved], 0.5) == [moved]
    far = graph.Rect(0.1, 0.1, 0.1, 0.1)
    assert graph.associate(tracked, [far], 0.5) == [tracked[0], far]


def test_one_euro_filter_holds_a_still_face_and_follows_a_jump() -> None:
    smoother = graph.OneEuroSmoother()
    face = np.random.default_rng(0).uniform(100, 200, (478, 3)).astype(np.float32)
    for step in range(5):
        assert np.array_equal(smoother.apply(step * 66_000, face), face)
    moved = face + np.float32(20.0)
    out = smoother.apply(5 * 66_000, moved)
    assert np.all(out > face) and np.all(out <= moved + 1e-3)
    smoother.reset()
    assert np.array_equal(smoother.apply(10 * 66_000, moved), moved)


@pytest.mark.parametrize(("yaw_deg", "pitch_deg"), [(0.0, 0.0), (25.0, -10.0), (-40.0, 15.0)])
def test_matrix_recovers_the_pose_of_a_projected_canonical_face(
    canonical_face: CanonicalFace, yaw_deg: float, pitch_deg: float
) -> None:
    """The canonical face turned by a known yaw and pitch, placed 60 cm in front of the
    pipeline's camera and projected: the matrix gives the pose back (the depth is a weak
    perspective, so within a degree)."""
    yaw, pitch = math.radians(yaw_deg), -math.radians(pitch_deg)  # pitch > 0: the nose up
    turn = np.array(
        [[math.cos(yaw), 0, math.sin(yaw)], [0, 1, 0], [-math.sin(yaw), 0, math.cos(yaw)]]
    )
    tilt = np.array(
        [[1, 0, 0], [0, math.cos(pitch), -math.sin(pitch)], [0, math.sin(pitch), math.cos(pitch)]]
    )
    points = turn @ tilt @ canonical_face.points + np.array([[0.0], [0.0], [-60.0]])
    size = (640, 480)
    height_near = 2 * math.tan(math.radians(31.5))
    width_near = height_near * size[0] / size[1]
    screen = np.empty((468, 3))
    screen[:, 0] = (points[0] / -points[2]) / width_near + 0.5
    screen[:, 1] = 0.5 - (points[1] / -points[2]) / height_near
    screen[:, 2] = -(points[2] - points[2].mean()) / 60.0 / width_near
    matrix = transformation_matrix(screen, size, canonical_face)
    assert matrix is not None
    found_yaw, found_pitch = angles_from_matrix_deg(matrix)
    assert found_yaw == pytest.approx(yaw_deg, abs=1.0)
    assert found_pitch == pytest.approx(pitch_deg, abs=1.0)


@pytest.mark.parametrize("mirrored", [False, True])
def test_procrustes_recovers_a_similarity_and_its_scale_alone_agrees(
    canonical_face: CanonicalFace, mirrored: bool
) -> None:
    """The weighted basis turned, scaled by 1.7 and moved: the fit gives the similarity back.
    The scale-only fit (singular values and the sign of det(cross)) gives the full fit's scale
    (u, vt and MediaPipe's reflection rule), also for a mirrored face, whose best orthogonal
    map is a reflection the fit must refuse."""
    fit = canonical_face.fit
    rotation, _ = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))
    rotation *= np.sign(np.linalg.det(rotation))
    offset = np.array([[2.0], [-3.0], [-60.0]])
    target = 1.7 * rotation @ canonical_face.points[:, fit.basis] + offset
    if mirrored:
        target[0] *= -1.0
    matrix = _procrustes(fit, target)
    scale = float(np.linalg.norm(matrix[:3, 0]))
    assert _scale_of(fit, target) == pytest.approx(scale, rel=1e-12)
    assert np.linalg.det(matrix[:3, :3]) > 0
    if not mirrored:
        np.testing.assert_allclose(matrix[:3, :3], 1.7 * rotation, atol=1e-9)
        np.testing.assert_allclose(matrix[:3, 3], offset[:, 0], atol=1e-9)
        np.testing.assert_allclose(matrix[3], [0, 0, 0, 1])


# ---------------------------------------------------------------- bad input


def test_bad_bundles_fall_back_or_fail_in_one_line(
    tmp_path: Path, model_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    corrupt = tmp_path / "corrupt.task"
    corrupt.write_bytes(b"not a zip" * 100)
    with pytest.raises(ModelError) as raised:
        Landmarker(LandmarksConfig(), corrupt, engine="litert")
    assert "\n" not in str(raised.value)
    assert "LiteRT engine cannot start" in caplog.text  # tried, warned, then MediaPipe failed too
    foreign = tmp_path / "foreign.task"
    with zipfile.ZipFile(foreign, "w") as bundle:
        bundle.writestr("face_detector.tflite", b"\0" * 64)
    with pytest.raises(ModelError):
        Landmarker(LandmarksConfig(), foreign, engine="litert")


def test_missing_litert_runs_mediapipe_with_a_warning(
    model_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "ai_edge_litert.interpreter", None)
    with Landmarker(LandmarksConfig(), model_path, engine="litert") as detector:
        assert detector.engine == "mediapipe"
    assert "pip install 'ai-edge-litert==2.3.0'" in caplog.text


def test_a_delegate_that_does_not_load_runs_mediapipe_with_a_warning(
    model_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    config = LandmarksConfig(delegate="/nonexistent/libnpu_delegate.so")
    with Landmarker(config, model_path, engine="litert") as detector:
        assert detector.engine == "mediapipe"
    assert "libnpu_delegate.so" in caplog.text and "running MediaPipe instead" in caplog.text


def test_faces_completed_when_measured_equal_a_whole_run(model_path: Path) -> None:
    """The loop measures a LiteRT face (matrix, blendshapes) after tracking it, on its own
    thread: the same numbers as the runner's whole `run` on the same frames."""
    from roadgaze.landmarks.engines.litert import Bundle, LiteRtFaceLandmarker

    config = LandmarksConfig(multi_face_check_s=0.0, max_faces=1)
    frames = gif_frames("head-pose-face-detection-male.gif", 12)
    runner = LiteRtFaceLandmarker(Bundle.read(model_path), config, 1, video=True)
    with Landmarker(config, model_path, video=True, engine="litert") as landmarker:
        for index, frame in enumerate(frames):
            t_s = index / 15.0
            prepared = landmarker.prepare(frame)
            inference = landmarker.infer(prepared, t_s)
            assert all(face.pending is not None for face in inference.faces)
            measured = landmarker.measure(inference).faces
            whole = runner.run(prepared.rgb, max(round(t_s * 1000.0), index))
            assert len(measured) == len(whole) == 1
            _, matrix, blendshapes = whole[0]
            assert measured[0].blendshapes == blendshapes
            assert matrix is not None
            yaw_deg, pitch_deg = angles_from_matrix_deg(matrix)
            assert measured[0].mediapipe_yaw_deg == yaw_deg
            assert measured[0].mediapipe_pitch_deg == pitch_deg


# ---------------------------------------------------------------- a rejected face looked at again


def test_the_mirror_order_pairs_each_landmark_with_its_mirror_image(
    canonical_face: CanonicalFace,
) -> None:
    order = graph.mirror_order(canonical_face.points)
    assert order.shape == (478,) and np.array_equal(order[order], np.arange(478))
    pairs = {33: 263, 133: 362, 61: 291, 234: 454, 468: 473, 469: 476, 471: 474, 472: 477}
    assert all(order[a] == b and order[b] == a for a, b in pairs.items())
    assert all(order[i] == i for i in (1, 4, 10, 152))  # on the mid-line
    lopsided = canonical_face.points.copy()
    lopsided[0, 33] += 0.5
    with pytest.raises(ValueError, match="not mirror-symmetric"):
        graph.mirror_order(lopsided)
    raw = np.random.default_rng(0).uniform(0, 256, (1, 1434)).astype(np.float32)
    once = graph.unmirror_landmarks(raw, 256, order)
    assert (
        once[33, 0] == pytest.approx(256 - raw[0, 263 * 3]) and once[33, 2] == raw[0, 263 * 3 + 2]
    )
    twice = graph.unmirror_landmarks(once, 256, order)
    np.testing.assert_allclose(twice, raw.reshape(-1, 3), atol=1e-4)


class _OneSidedModel:
    """A fake landmark model that sees a face only in a crop brighter on its right half (the
    test's image is brighter on its left: only the mirrored crop), with every landmark at x 64,
    y 128, z 0 in the crop but the right eye's outer corner (33) at x 40."""

    def __init__(self) -> None:
        self.crops: list[np.ndarray[Any, Any]] = []

    def run(self, values: np.ndarray[Any, Any], scale: float = 1.0) -> list[np.ndarray[Any, Any]]:
        self.crops.append(np.array(values))
        raw = np.tile(np.float32([64.0, 128.0, 0.0]), (478, 1))
        raw[33, 0] = 40.0
        right_brighter = values[:, 128:].mean() > values[:, :128].mean()
        return [raw.reshape(1, -1), np.float32([[10.0 if right_brighter else -10.0]])]


class _OneFace:
    """A fake detector: one face in the middle of the image."""

    def detect(self, rgb: np.ndarray[Any, Any]) -> list[graph.FaceDetection]:
        keypoints = np.array(
            [[0.4, 0.45], [0.6, 0.45], [0.5, 0.55], [0.5, 0.65], [0.3, 0.5], [0.7, 0.5]]
        )
        return [graph.FaceDetection((0.3, 0.3, 0.7, 0.7), keypoints, 0.9)]


def test_a_rejected_face_is_looked_at_again_recut_and_mirrored(model_path: Path) -> None:
    from roadgaze.landmarks.engines.litert import Bundle, LiteRtFaceLandmarker, Models

    model = _OneSidedModel()
    models = Models(_OneFace(), model, model)  # type: ignore[arg-type]
    runner = LiteRtFaceLandmarker(Bundle.read(model_path), LandmarksConfig(), 1, False, models)
    rgb = np.zeros((480, 640, 3), np.uint8)
    rgb[:, :320] = 200  # brighter on the left: the face is seen only mirrored
    assert runner.track(rgb, None) == [] and len(model.crops) == 1  # MediaPipe's rule
    model.crops.clear()
    (points,) = runner.track(rgb, None, retry_rejected=True)
    assert len(model.crops) == 3  # the detector's region, re-cut, mirrored: found
    np.testing.assert_array_equal(model.crops[2], model.crops[0][:, ::-1])
    model.crops.clear()
    rgb[:] = 100  # even: no look finds the face, the fourth is re-cut from the mirrored one
    assert runner.track(rgb, None, retry_rejected=True) == [] and len(model.crops) == 4
    # Put back from the mirrored crop: x 64 -> 192 of 256, the corner 33 is 263's (x 64 -> 192),
    # and 263 is 33's (x 40 -> 216): the eye corners on their own sides again.
    order = graph.mirror_order(Bundle.read(model_path).face.points)
    assert order[33] == 263
    xs = (points[:, 0] - 0.5) * 640 / (1.5 * 0.4 * 640) * 256 + 128  # back to crop pixels
    assert xs[33] == pytest.approx(192.0, abs=0.01) and xs[263] == pytest.approx(216.0, abs=0.01)
    assert np.median(xs) == pytest.approx(192.0, abs=0.01)
