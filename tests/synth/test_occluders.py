"""A hand on top of the wheel, placed by where the camera sits: a camera on the steering column
loses most of the face, one in front the lower face, one on the A-pillar nothing."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from roadgaze.landmarks.eye_contrast import polygon_mask
from roadgaze.landmarks.eye_landmarks import EYES
from roadgaze.synth import FaceRenderer
from roadgaze.synth.facial_hair import LIPS
from roadgaze.synth.occluders import hand_at_12


@pytest.fixture(scope="module")
def renderer() -> FaceRenderer:
    from roadgaze.synth import load_photo

    return FaceRenderer(load_photo(), (320, 320))


def covered(renderer: FaceRenderer, mounting: str, indices: Any, cabin: str = "lhd") -> float:
    """The share of the region's pixels the hand changed (by more than 10 grey levels)."""
    frame = renderer.render(0.0, 0.0)
    hand = hand_at_12(frame, renderer, mounting, cabin)
    inside = polygon_mask(renderer.mesh.points_px[list(indices), :2], frame.shape[:2])
    change = np.abs(hand.astype(np.float64) - frame.astype(np.float64)).mean(axis=2)
    return float((change > 10.0)[inside].mean())


@pytest.mark.parametrize(
    ("mounting", "eyes", "mouth"),
    [
        ("steering_column", (0.9, 1.0), (0.9, 1.0)),
        ("front", (0.0, 0.0), (0.3, 1.0)),
        ("centre_console", (0.0, 0.0), (0.0, 0.6)),
        ("a_pillar", (0.0, 0.0), (0.0, 0.0)),
    ],
)
def test_how_much_the_hand_hides_depends_on_the_camera(
    renderer: FaceRenderer,
    mounting: str,
    eyes: tuple[float, float],
    mouth: tuple[float, float],
) -> None:
    assert eyes[0] <= covered(renderer, mounting, EYES[0].contour) <= eyes[1]
    assert mouth[0] <= covered(renderer, mounting, LIPS) <= mouth[1]


def test_the_hand_is_skin_and_mirrors_in_a_right_hand_drive_cabin(renderer: FaceRenderer) -> None:
    frame = renderer.render(0.0, 0.0)
    left = hand_at_12(frame, renderer, "centre_console", "lhd").astype(np.float64)
    right = hand_at_12(frame, renderer, "centre_console", "rhd").astype(np.float64)
    changed_left = np.abs(left - frame).mean(axis=2) > 10.0
    changed_right = np.abs(right - frame).mean(axis=2) > 10.0
    columns = np.arange(frame.shape[1])
    centre = renderer.mesh.points_px[[33, 263], 0].mean()
    assert (
        columns[changed_left.any(axis=0)].mean()
        > centre
        > columns[changed_right.any(axis=0)].mean()
    )
    fist = hand_at_12(frame, renderer, "steering_column")[
        round(renderer.mesh.points_px[1, 1]), round(renderer.mesh.points_px[1, 0])
    ]
    assert fist[2] > fist[1] > fist[0]  # skin: more red than green than blue
    assert np.array_equal(hand_at_12(frame, renderer, "a_pillar"), frame)
