"""Body lean: the head's place judged against its learned driving place (roadgaze.monitor.lean)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fakes import open_eyes
from roadgaze.cabin import FACE_WIDTH_M, FacePlace, face_seen
from roadgaze.config import MonitorConfig
from roadgaze.monitor import AlertKind, Monitor
from roadgaze.monitor.lean import SETTLE_S, HeadPlace, face_place, leaning, step_place
from roadgaze.mounting import FRONT, mounting_for
from roadgaze.types import FaceFeatures, PoseSample

FPS = 30.0
REFERENCE = FacePlace(320.0, 240.0, 1000.0)


def box_of(place: FacePlace) -> tuple[float, float, float, float]:
    """A face box of `place` (square in metres of width: its width reads the size)."""
    half = 0.5 * FACE_WIDTH_M * place.k_px_per_m
    return (place.u_px - half, place.v_px - half, place.u_px + half, place.v_px + half)


def sample_at(t_s: float, place: FacePlace, yaw_deg: float = 0.0) -> PoseSample:
    features = FaceFeatures(
        x_left_px=0.0,
        x_right_px=1.0,
        x_center_px=0.5,
        roll_deg=0.0,
        box_px=box_of(place),
        quality=1.0,
        landmarks_px=np.zeros((0, 3), np.float32),
    )
    return PoseSample(
        t_s=t_s,
        frame=round(t_s * FPS),
        face=True,
        yaw_raw_deg=yaw_deg,
        yaw_deg=yaw_deg,
        yaw_rate_dps=0.0,
        yaw_std_deg=1.0,
        features=features,
        n_faces=1,
        pitch_raw_deg=0.0,
        pitch_deg=0.0,
        eyes=open_eyes(),
    )


def test_the_face_box_gives_the_face_place() -> None:
    place = face_place(sample_at(0.0, REFERENCE))
    assert place == pytest.approx(REFERENCE)
    assert face_place(replace(sample_at(0.0, REFERENCE), face=False)) is None


def test_the_driving_place_is_learned_on_the_road_and_a_lean_read_against_it() -> None:
    config = MonitorConfig()
    place = HeadPlace()
    for frame in range(30):
        place = step_place(
            config, FRONT, place, sample_at(frame / FPS, REFERENCE), (0.0, 0.0), True
        )
    assert place.reference == pytest.approx(REFERENCE)
    assert place.lean_m == pytest.approx((0.0, 0.0, 0.0))
    leaned = face_seen(FRONT, 0.7, REFERENCE, (0.0, -0.25, -0.1))
    after = step_place(config, FRONT, place, sample_at(1.0, leaned), (0.0, 0.0), True)
    assert after.lean_m == pytest.approx((0.0, -0.25, -0.1))
    assert leaning(config, after.lean_m)
    assert after.reference == place.reference  # a lean teaches nothing once settled
    assert place.learned_s >= SETTLE_S
    assert not leaning(config, (0.0, -0.1, -0.1))
    assert not leaning(MonitorConfig(lean_limit_m=10.0), after.lean_m)


@pytest.mark.parametrize(
    ("head_m", "warns"), [((0.0, -0.25, -0.15), True), ((0.0, -0.08, 0.0), False)]
)
def test_a_lean_facing_the_road_is_off_road_and_warns(
    head_m: tuple[float, float, float], warns: bool
) -> None:
    # Face pointed at the road (yaw 0) all along; from 3 s the head moves to `head_m` (front
    # camera 0.7 m away). A lean past 0.15 m is off road: long distraction 3 s into it at 70 km/h.
    monitor = Monitor(MonitorConfig(neutral_yaw_deg=0.0))
    leaned = face_seen(FRONT, 0.7, REFERENCE, head_m)
    kinds: list[tuple[AlertKind, float]] = []
    for frame in range(round(8.0 * FPS)):
        t_s = frame / FPS
        place = REFERENCE if t_s < 3.0 or t_s >= 7.0 else leaned
        alerts = monitor.update(sample_at(t_s, place), 70.0)
        kinds.extend((alert.kind, alert.t_s) for alert in alerts)
    distraction = [t for kind, t in kinds if kind is AlertKind.LONG_DISTRACTION]
    if warns:
        assert distraction and distraction[0] == pytest.approx(6.0, abs=1.5 / FPS)
        assert monitor.verdict.zone == "road"
    else:
        assert distraction == []


def test_a_turned_head_from_a_mounted_camera_is_no_lean() -> None:
    # A 60 deg turn seen by an A-pillar camera moves the face in the image; the pivot's
    # correction leaves the head in its place.
    mounting = mounting_for("a_pillar")
    seen = face_seen(mounting, 0.86, REFERENCE, (0.0, 0.0, 0.0), 60.0, 0.0)
    place = HeadPlace(REFERENCE, 10.0, 0.0)
    after = step_place(MonitorConfig(), mounting, place, sample_at(0.1, seen), (60.0, 0.0), False)
    assert after.lean_m == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)


def test_a_first_face_seen_leaning_is_learned_away_while_settling() -> None:
    # The first face is seen 0.3 m to the side (the driver getting in); within the first second
    # of road time the driving place follows the driver, so the driving posture is no lean.
    config = MonitorConfig()
    aside = face_seen(FRONT, 0.7, REFERENCE, (0.0, -0.3, 0.0))
    place = step_place(config, FRONT, HeadPlace(), sample_at(0.0, aside), (0.0, 0.0), True)
    for frame in range(1, round(3.0 * FPS)):
        place = step_place(
            config, FRONT, place, sample_at(frame / FPS, REFERENCE), (0.0, 0.0), True
        )
    assert place.lean_m is not None and not leaning(config, place.lean_m)
