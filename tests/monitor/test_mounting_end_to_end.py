"""A camera on the A-pillar, end to end on a rendered face: the road pose the camera sees 35 deg
to the side is the road, and a look beyond 55 deg from the driver's forward direction warns."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from roadgaze.config import Config, load_config
from roadgaze.monitor.zones import ZoneMap
from roadgaze.pose.mounting import gaze_to_camera, mounting_for
from test_pipeline_synthetic import run_pipeline

SyntheticClip = Callable[[str], tuple[Path, Any]]


@pytest.mark.slow
def test_an_a_pillar_camera_sees_the_road_and_a_look_beyond_55_degrees(
    synthetic_clip: SyntheticClip,
) -> None:
    mounting = mounting_for("a_pillar", "lhd")
    road_yaw, road_pitch = gaze_to_camera(mounting, 0.0, 0.0)  # (-35.1, -4.1) in the camera
    far_yaw, far_pitch = gaze_to_camera(mounting, 65.0, 0.0)  # (30.1, -4.3): 65 deg left
    spec = (
        f"{road_yaw:.1f}/{road_pitch:.1f}:3,{far_yaw:.1f}/{far_pitch:.1f}:4,"
        f"{road_yaw:.1f}/{road_pitch:.1f}:1"
    )
    path, _ = synthetic_clip(spec)
    config = load_config(overrides={"monitor.camera_mounting": "a_pillar"}, environ={})
    records = run_pipeline(path, config).records
    road = [r.verdict for r in records if 1.0 <= r.sample.t_s < 3.0]
    assert road and all(v.zone == "road" for v in road)
    assert all(abs(v.neutral_yaw_deg) < 10.0 for v in road)  # the driver's own offset only
    far = [r.verdict.zone for r in records if 4.0 <= r.sample.t_s < 7.0]
    assert far.count("far_left") >= 0.9 * len(far)
    alerts = [a for r in records for a in r.alerts]
    assert [a.kind.value for a in alerts][:1] == ["long_distraction"]
    assert 3.0 + 1.5 <= alerts[0].t_s <= 3.0 + 3.6  # from the start of the turn
    assert alerts[0].rule == "euroncap.long_distraction"
    # Judged as if the camera were in front, the road pose (-35 deg) would be off the road.
    assert ZoneMap.from_config(Config().monitor).classify(road_yaw, 0.0, "road") != "road"
