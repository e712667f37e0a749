"""A phone held up in the outer hand: on the outer side of the face, mirrored in a right-hand-
drive cabin, the eyes left free, the fingers up across a dark phone."""

from __future__ import annotations

import numpy as np
import pytest

from roadgaze.landmarks.eye_contrast import polygon_mask
from roadgaze.landmarks.eye_landmarks import EYES
from roadgaze.synth import FaceRenderer
from roadgaze.synth.lean import FACE_CENTRE_HEIGHT
from roadgaze.synth.phone_hand import PHONE_BGR, PLACES, phone_hand_layer, placed


@pytest.fixture(scope="module")
def renderer() -> FaceRenderer:
    from roadgaze.synth import load_photo

    return FaceRenderer(load_photo(), (320, 320))


def test_the_fingers_point_up_from_the_wrist_and_the_thumb_toward_the_face() -> None:
    eyes = np.array([160.0, 120.0])
    points = placed(PLACES["wheel"], eyes, 100.0, 1.0)
    assert points.shape == (21, 2)
    assert points[0, 1] > points[9, 1] > points[12, 1]  # wrist, middle finger's base, its tip
    assert points[0, 0] > eyes[0] and points[4, 0] < points[20, 0]  # the thumb on the inner side
    mirrored = placed(PLACES["wheel"], eyes, 100.0, -1.0)
    assert mirrored[:, 0] == pytest.approx(2 * eyes[0] - points[:, 0])
    assert mirrored[:, 1] == pytest.approx(points[:, 1])


@pytest.mark.parametrize("place", sorted(PLACES))
def test_the_hand_is_on_the_outer_side_and_leaves_the_eyes_free(
    renderer: FaceRenderer, place: str
) -> None:
    zoom, (width, height) = 0.7, renderer.size
    lens = np.array([0.5 * width, FACE_CENTRE_HEIGHT * height])  # the zoom's fixed point
    points = lens + zoom * (renderer.mesh.points_px[:, :2] - lens)
    centre = points[[33, 263], 0].mean()
    columns = np.arange(width)
    sides = {}
    for cabin in ("lhd", "rhd"):
        layer = phone_hand_layer(renderer, place, cabin, zoom=zoom)
        shown = layer.alpha > 0.5
        sides[cabin] = columns[shown.any(axis=0)].mean()
        for eye in EYES:
            inside = polygon_mask(points[list(eye.contour)], (height, width))
            assert layer.alpha[inside].max() < 0.1  # at most the blurred edge of the phone
        dark = np.all(np.abs(layer.colour - np.asarray(PHONE_BGR)) < 12.0, axis=2) & shown
        skin = (layer.colour[..., 2] > layer.colour[..., 1] + 5) & shown
        assert dark.sum() > 1500 and skin.sum() > 2000  # a phone and a hand, each of some size
    assert sides["lhd"] > centre > sides["rhd"]
