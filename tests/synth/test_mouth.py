"""A mouth that opens: the jaw turns the lower face only, by the gap asked (read back by
MediaPipe's lips and its jawOpen blendshape), the inside of the mouth shows, speech is 3-5 Hz."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from roadgaze.synth import FaceRenderer
from roadgaze.synth.mouth import (
    FULL_GAP_W,
    SPEECH_HZ,
    SPEECH_OPENING,
    UPPER_INNER,
    speech_track,
)


@pytest.fixture(scope="module")
def renderer() -> FaceRenderer:
    from roadgaze.synth import load_photo

    return FaceRenderer(load_photo(), (320, 320))


def test_the_jaw_moves_the_lower_face_only_by_the_gap_asked(renderer: FaceRenderer) -> None:
    rest = renderer.mesh.points_px
    width = renderer.mesh.face_width_px
    for fraction in (0.1, 0.3, 1.0):
        opened = renderer.jaw.open(rest, fraction)
        moved = np.linalg.norm(opened - rest, axis=1)
        gap = opened[14, 1] - rest[14, 1]
        assert gap == pytest.approx(fraction * FULL_GAP_W * width, rel=1e-6)
        assert moved[list(UPPER_INNER[1:-1])].max() == 0.0  # the upper lip stays
        assert moved[[33, 263, 1, 10]].max() == 0.0  # eyes, nose tip, forehead stay
        assert opened[152, 1] - rest[152, 1] > 0.6 * gap  # the chin drops
        assert opened[152, 2] > rest[152, 2]  # and moves back, as a jaw turning about its hinge
    assert renderer.jaw.open(rest, 0.0) is rest


def test_an_open_mouth_shows_its_inside_only_between_the_lips(renderer: FaceRenderer) -> None:
    closed = renderer.render(0.0, 0.0).astype(np.float64)
    assert np.array_equal(renderer.render(0.0, 0.0, 0.0), renderer.render(0.0, 0.0))
    opened = renderer.render(0.0, 0.0, 0.5).astype(np.float64)
    turned = renderer.turned_points(0.0, 0.0, 0.5)
    x, y = (round(v) for v in 0.5 * (turned[13, :2] + turned[14, :2]))
    middle = opened[y, x - 3 : x + 4]
    assert middle.mean() < 90.0  # the dark inside between the lips
    eyes = slice(round(turned[159, 1]) - 8, round(turned[145, 1]) + 8)
    assert np.abs(opened[eyes] - closed[eyes]).max() == 0.0  # nothing above the mouth moves
    renderer.show_mouth_inside = False
    try:
        hidden = renderer.render(0.0, 0.0, 0.5).astype(np.float64)
    finally:
        renderer.show_mouth_inside = True
    assert hidden[y, x - 3 : x + 4].mean() > middle.mean() + 30.0  # the texture, stretched


def test_speech_is_syllables_at_3_to_5_hz_of_irregular_size() -> None:
    t_s = np.arange(0.0, 30.0, 1 / 60)
    opening = speech_track(t_s, seed=4)
    assert np.array_equal(opening, speech_track(t_s, seed=4))
    assert not np.array_equal(opening, speech_track(t_s, seed=5))
    assert opening.min() >= 0.0 and opening.max() <= SPEECH_OPENING[1]
    closed = opening < 1e-3
    starts = np.flatnonzero(closed[:-1] & ~closed[1:])  # each syllable opens from closed
    rate_hz = len(starts) / 30.0
    assert 0.6 * SPEECH_HZ[0] < rate_hz < SPEECH_HZ[1]  # pauses between phrases lower the mean
    peaks = [opening[a:b].max() for a, b in itertools.pairwise(starts)]
    assert np.std(peaks) > 0.04  # irregular size
    assert closed.mean() > 0.1  # pauses


@pytest.mark.slow
def test_mediapipe_reads_the_opening_asked(renderer: FaceRenderer) -> None:
    """The inner lips' gap MediaPipe finds grows by the asked gap (within 25 % of a full
    opening's, 0.1 W), and jawOpen rises with it."""
    from roadgaze.config import Config
    from roadgaze.landmarks import MediaPipeLandmarker

    width = renderer.mesh.face_width_px
    gaps, jaw_open = [], []
    with MediaPipeLandmarker.from_config(Config(), video=False) as landmarker:
        for fraction in (0.0, 0.15, 0.3, 0.6):
            face = landmarker.detect(renderer.render(0.0, 0.0, fraction)).driver
            assert face is not None and face.blendshapes is not None
            points = np.asarray(face.landmarks_px)
            gaps.append((points[14, 1] - points[13, 1]) / width)
            jaw_open.append(face.blendshapes["jawOpen"])
    for fraction, gap in zip((0.15, 0.3, 0.6), gaps[1:], strict=True):
        assert gap - gaps[0] == pytest.approx(fraction * FULL_GAP_W, abs=0.25 * 0.4 * FULL_GAP_W)
    assert jaw_open == sorted(jaw_open) and jaw_open[-1] - jaw_open[0] > 0.2
