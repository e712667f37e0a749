"""Synthetic eyes: timeline fields (old timelines unchanged), the eye truth and its CSV, the
renderer (rest frame unchanged, lids closed, iris moved) and what MediaPipe recovers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from roadgaze.config import Config
from roadgaze.errors import ConfigError
from roadgaze.landmarks import RIGHT_EYE
from roadgaze.landmarks.eye_contrast import polygon_mask
from roadgaze.synth import (
    EYE_TRUTH_HEADER,
    EyeRenderer,
    EyeState,
    FaceRenderer,
    Keyframe,
    parse_timeline,
    read_truth_csv,
    render_clip,
    truth_path_for,
    write_truth_csv,
)
from roadgaze.types import EyeStatus

SIZE = (640, 480)


@pytest.mark.parametrize("spec", ["0:2,40:3.5,0:2,-35:1,0:2", "30/-10:2,0:1"])
def test_old_timelines_are_unchanged(spec: str) -> None:
    timeline = parse_timeline(spec)
    assert not timeline.has_eyes
    truth = timeline.eye_truth(15.0)
    np.testing.assert_array_equal(truth[:, :3], timeline.truth(15.0))
    assert np.all(truth[:, 3:5] == 0.0) and np.all(truth[:, 5] == 1.0)


def test_eye_fields_and_their_transition() -> None:
    timeline = parse_timeline(
        "0:2,0;eyes=closed:1.5,0;eye_yaw=-25;eye_pitch=-30:2,10/5; eyes = 0.4 :1"
    )
    assert timeline.has_eyes
    assert timeline.keyframes == (
        Keyframe(0.0, 0.0, 2.0),
        Keyframe(0.0, 0.0, 1.5, openness=0.0),
        Keyframe(0.0, 0.0, 2.0, -25.0, -30.0, 1.0),
        Keyframe(10.0, 5.0, 1.0, openness=0.4),
    )
    truth = timeline.eye_truth(10.0)
    assert truth.shape == (65, 6)
    # The lids close over 0.1 s from t = 2.0: half way at 2.05, closed from 2.1.
    _, _, openness = timeline.eyes_at([2.0, 2.05, 2.1, 3.4])
    np.testing.assert_allclose(openness, [1.0, 0.5, 0.0, 0.0], atol=1e-9)
    assert truth[40, 3] == -25.0 and truth[40, 4] == -30.0 and truth[40, 5] == 1.0
    slow = parse_timeline("0:1,0;eyes=closed:1", eye_transition_s=0.5)
    assert slow.eyes_at([1.25])[2][0] == pytest.approx(0.5)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("0;eyes=shut:1", "eyes must be open, closed, half"),
        ("0;eyes=1.5:1", "eyes must be"),
        ("0;foo=1:1", "unknown field 'foo=1'"),
        ("0;eyes:1", "unknown field 'eyes'"),
        ("0;eye_yaw=50:1", r"outside \+-35"),
        ("0;eye_pitch=x:1", "eye_pitch 'x' is not a number"),
        ("0;eyes=open;eyes=closed:1", "given twice"),
    ],
)
def test_bad_eye_fields_name_the_item(spec: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        parse_timeline(spec)


def test_six_column_truth_round_trip(tmp_path: Path) -> None:
    truth = parse_timeline("0:0.5,0;eyes=half;eye_yaw=10:0.5").eye_truth(10.0)
    path = tmp_path / "clip.truth.csv"
    write_truth_csv(path, truth)
    assert path.read_text(encoding="utf-8").splitlines()[0] == ",".join(EYE_TRUTH_HEADER)
    np.testing.assert_allclose(read_truth_csv(path), truth, atol=1e-4)


@pytest.fixture(scope="module")
def renderer() -> EyeRenderer:
    from roadgaze.synth import load_photo

    return EyeRenderer(load_photo(), SIZE)


def test_eyes_at_rest_render_the_plain_frame(renderer: EyeRenderer) -> None:
    plain = FaceRenderer.render(renderer, 10.0, 0.0)
    assert np.array_equal(renderer.render_eyes(10.0, 0.0, EyeState()), plain)


def test_closing_the_lids_changes_the_eyes_and_nothing_else(renderer: EyeRenderer) -> None:
    open_eyes = renderer.render_eyes(0.0, 0.0, EyeState()).astype(float)
    closed = renderer.render_eyes(0.0, 0.0, EyeState.both(openness=0.0)).astype(float)
    changed = np.abs(closed - open_eyes).max(axis=2) > 0
    near_eyes = np.zeros(changed.shape, bool)
    for indices in (RIGHT_EYE.contour, (263, 362, 386, 374)):
        points = renderer.mesh.points_px[list(indices), :2]
        width = float(np.ptp(points[:, 0]))
        x0, y0 = points.min(axis=0) - 0.5 * width
        x1, y1 = points.max(axis=0) + 0.5 * width
        near_eyes[round(y0) : round(y1), round(x0) : round(x1)] = True
    assert changed.any() and not (changed & ~near_eyes).any()
    polygon = renderer.mesh.points_px[list(RIGHT_EYE.contour), :2]
    opening = polygon_mask(polygon, changed.shape)
    assert np.mean(np.abs(closed - open_eyes)[opening]) > 20.0


def test_the_iris_moves_with_the_eye(renderer: EyeRenderer) -> None:
    rest, _ = renderer.iris_placement(RIGHT_EYE, 0.0, 0.0, EyeState())
    left, _ = renderer.iris_placement(RIGHT_EYE, 0.0, 0.0, EyeState.both(25.0))
    down, _ = renderer.iris_placement(RIGHT_EYE, 0.0, 0.0, EyeState.both(0.0, -20.0))
    width = float(np.linalg.norm(np.subtract(*renderer.mesh.points_px[[33, 133], :2])))
    k = renderer.k
    # Turned 25 deg toward the person's left (the image right), down 20 deg (image down).
    assert left[0] - rest[0] == pytest.approx(k * width * np.sin(np.radians(25)), rel=0.05)
    assert down[1] - rest[1] == pytest.approx(k * width * np.sin(np.radians(20)), rel=0.05)


def test_a_clip_with_eye_fields_writes_the_eye_truth(tmp_path: Path) -> None:
    out = tmp_path / "eyes.mkv"
    truth = render_clip("0:0.4,0;eyes=closed:0.4", out, fps=10.0, size=(160, 160))
    assert truth.shape == (8, 6)
    np.testing.assert_allclose(read_truth_csv(truth_path_for(out)), truth, atol=1e-4)
    with pytest.raises(ConfigError, match="EyeRenderer"):
        render_clip("0;eyes=closed:0.4", tmp_path / "x.mkv", renderer=_plain_renderer())


def _plain_renderer() -> FaceRenderer:
    from roadgaze.synth import load_photo

    return FaceRenderer(load_photo(), (160, 160))


@pytest.mark.slow
def test_mediapipe_reads_closed_lids_and_turned_eyes(renderer: EyeRenderer) -> None:
    from roadgaze.landmarks import MediaPipeLandmarker, driver_eyes
    from roadgaze.monitor import classify_eyes

    config = Config()
    with MediaPipeLandmarker.from_config(config) as landmarker:

        def eyes_of(state: EyeState) -> tuple[float, float, EyeStatus]:
            face = landmarker.detect(renderer.render_eyes(0.0, 0.0, state)).driver
            eyes = driver_eyes(face, 0.0)
            assert eyes is not None and eyes.yaw_deg is not None and eyes.openness is not None
            return eyes.yaw_deg, eyes.openness, classify_eyes(config.monitor, eyes, 0.0)[0]

        rest_yaw, rest_openness, rest_status = eyes_of(EyeState())
        _, closed_openness, closed_status = eyes_of(EyeState.both(openness=0.0))
        left_yaw, _, _ = eyes_of(EyeState.both(30.0))
        right_yaw, _, _ = eyes_of(EyeState.both(-30.0))
    assert rest_status is EyeStatus.OPEN and rest_openness > 0.28
    assert closed_status is EyeStatus.CLOSED and closed_openness < 0.08
    assert 18.0 < left_yaw - rest_yaw < 42.0 and -42.0 < right_yaw - rest_yaw < -18.0
