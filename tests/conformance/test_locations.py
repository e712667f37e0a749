"""The gaze-location scenarios (roadgaze.conformance.locations) and the leaning picture
(roadgaze.synth.lean)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from repo_paths import child_env
from roadgaze.cabin import (
    FACE_WIDTH_M,
    FacePlace,
    camera_distance_m,
    direction_deg,
    face_seen,
    location,
)
from roadgaze.config import MonitorConfig
from roadgaze.conformance.locations import EYE_REACH_DEG, LEANS_M, location_scenarios, look_at
from roadgaze.conformance.matrix import PITCH_LIMITS_DEG, scenario_matrix
from roadgaze.mounting import FRONT, mounting_for
from roadgaze.synth.lean import FACE_CENTRE_HEIGHT, lean_affine

LHD, RHD = MonitorConfig(), MonitorConfig(cabin="rhd")


def test_an_owl_look_turns_the_head_to_the_location() -> None:
    look = look_at(LHD, "passenger_footwell", "owl", 4.0)
    yaw, _ = location("passenger_footwell").direction_deg()
    assert (look.yaw_deg, look.pitch_deg) == pytest.approx((yaw, PITCH_LIMITS_DEG[0]))
    assert (look.eye_yaw_deg, look.eye_pitch_deg) == (0.0, 0.0)
    assert look_at(LHD, "passenger_face", "owl", 4.0).yaw_deg == -80.0  # as far as rendered


@pytest.mark.parametrize("name", ["infotainment", "glovebox", "passenger_footwell"])
def test_a_lizard_look_moves_the_eyes_and_keeps_the_head_on_the_road(name: str) -> None:
    look = look_at(LHD, name, "lizard", 2.2)
    yaw, pitch = location(name).direction_deg()
    assert look.yaw_deg + look.eye_yaw_deg == pytest.approx(yaw)
    assert look.pitch_deg + look.eye_pitch_deg == pytest.approx(pitch)
    assert max(abs(look.eye_yaw_deg), abs(look.eye_pitch_deg)) <= EYE_REACH_DEG
    assert abs(look.yaw_deg) < 20.0 and abs(look.pitch_deg) < 10.0  # inside the road's entry
    mirrored = look_at(RHD, name, "lizard", 2.2)
    assert mirrored.eye_yaw_deg == pytest.approx(-look.eye_yaw_deg)


def test_a_lean_moves_the_head_and_looks_from_there() -> None:
    look = look_at(LHD, "passenger_footwell", "lean", 4.0)
    assert look.lean_m == LEANS_M["passenger_footwell"]
    yaw, _ = location("passenger_footwell").direction_deg(look.lean_m)
    assert look.yaw_deg == pytest.approx(yaw)
    assert look_at(RHD, "rear_passenger", "lean", 4.0).lean_m[1] == -LEANS_M["rear_passenger"][1]
    road = look_at(LHD, "road", "lean", 4.0)
    assert (road.yaw_deg, road.pitch_deg, road.lean_m) == (0.0, 0.0, LEANS_M["road"])


def test_the_location_scenarios_are_in_the_matrix_with_their_requirements() -> None:
    names = {s.name for s in scenario_matrix(LHD)}
    scenarios = location_scenarios(LHD)
    assert {s.name for s in scenarios} <= names
    keys = {r.key for s in scenarios for r in s.requirements}
    assert "lizard_glovebox_70.warns" in keys
    assert "vats_lizard_multi_target_70.no_long" in keys
    assert all(s.zoom < 1.0 for s in scenarios if s.name.startswith("lean_"))


@pytest.mark.parametrize("preset", ["front", "a_pillar"])
def test_the_leaning_picture_moves_the_face_where_the_camera_sees_it(preset: str) -> None:
    mounting = mounting_for(preset)
    size, width_px, head = (320, 320), 100.0, (0.1, -0.2, -0.15)
    matrix = lean_affine(size, width_px, mounting, head, 0.7)
    centre = (160.0, FACE_CENTRE_HEIGHT * 320.0)
    moved = tuple(row[0] * centre[0] + row[1] * centre[1] + row[2] for row in matrix)
    reference = FacePlace(*centre, 0.7 * width_px / FACE_WIDTH_M)
    seen = face_seen(mounting, camera_distance_m(mounting), reference, head)
    assert moved == pytest.approx((seen.u_px, seen.v_px))
    assert matrix[0][0] == pytest.approx(0.7 * seen.k_px_per_m / reference.k_px_per_m)
    still = lean_affine(size, width_px, FRONT, (0.0, 0.0, 0.0))
    assert still[0] == pytest.approx((1.0, 0.0, 0.0))
    assert still[1] == pytest.approx((0.0, 1.0, 0.0))


@pytest.mark.parametrize(
    ("toml", "says"),
    [
        (
            '[monitor]\nlocations = [{ name = "sunroof", point_m = [0.5, 0.0, 0.4] }]\n',
            "unknown gaze location 'sunroof'",
        ),
        ('[monitor]\nprotocol = "ncap"\n', "monitor.protocol"),
    ],
    ids=["location", "protocol"],
)
def test_an_unknown_location_or_protocol_is_one_line_and_exit_2(
    tmp_path: Path, toml: str, says: str
) -> None:
    config = tmp_path / "roadgaze.toml"
    config.write_text(toml, encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-m", "roadgaze", "conformance", "--config", str(config), "--only",
         "lean_road_70", "--out", str(tmp_path / "out")],
        capture_output=True, text=True, env=child_env(), timeout=120, check=False,
    )  # fmt: skip
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and says in lines[0] and "Traceback" not in done.stderr


def test_a_cabin_s_own_location_is_where_the_scenarios_look() -> None:
    own = MonitorConfig(locations=[{"name": "glovebox", "point_m": (0.6, -0.9, -0.6)}])  # type: ignore[list-item]
    look = look_at(own, "glovebox", "owl", 4.0)
    assert (look.yaw_deg, look.pitch_deg) == pytest.approx(direction_deg((0.6, -0.9, -0.6)))
    with pytest.raises(ValueError, match="at most once"):
        MonitorConfig(locations=[{"name": "glovebox", "point_m": (0.6, -0.9, -0.6)}] * 2)  # type: ignore[list-item]


def test_each_phone_row_looks_at_a_phone_off_the_road_where_the_long_distraction_runs() -> None:
    """Rows 51-61 (`PHONE_LOOKS`): each is a 4 s look at the phone by the head or the eyes; the
    phone's direction from the driving place lies off the road in a zone that is not driving-
    related (so the long distraction runs), in both cabins."""
    from roadgaze.cabin import LOCATIONS
    from roadgaze.conformance.dossier_rows import ROWS
    from roadgaze.conformance.locations import PHONE_LOOKS
    from roadgaze.monitor.zones import ZoneMap

    rows = {row.row: row for row in ROWS}
    assert sorted(PHONE_LOOKS) == list(range(51, 62))
    for row, (movement, name) in PHONE_LOOKS.items():
        assert rows[row].movement.lower() == movement
        assert rows[row].location == location(name).sheet
        assert rows[row].cells[0] == (f"{movement}_{name}_70.warns",)
    phones = {name for _, name in PHONE_LOOKS.values()}
    assert phones == {loc.name for loc in LOCATIONS[-6:]}
    for config in (LHD, RHD):
        zones = ZoneMap.from_config(config)
        for name in phones:
            yaw, pitch = location(name, config.cabin).direction_deg()
            zone = zones.classify(yaw, pitch, None)
            assert zone != "road" and not zones.is_driving_related(zone), (name, zone)
    names = {s.name for s in scenario_matrix(LHD)}
    assert {f"{movement}_{name}_70" for movement, name in PHONE_LOOKS.values()} <= names


@pytest.mark.slow
def test_a_look_at_the_phone_in_the_lap_warns_and_raises_support_through_the_service(
    tmp_path: Path,
) -> None:
    """Through the real service: the head down to the phone in the lap (row 53) and the eyes
    down to a phone at the wheel's centre (row 60) warn within the long distraction's window
    and raise support within 0.5 s (measured 3.20 s and 3.13 s; support 0.20 s and 0.13 s)."""
    import json

    from roadgaze.cli import main

    only = ["--only", "owl_driver_lap_70", "--only", "lizard_phone_wheel_centre_70"]
    code = main(["conformance", "--protocol", "euroncap", *only, "--out", str(tmp_path)])
    results = json.loads((tmp_path / "conformance.json").read_text(encoding="utf-8"))
    outcomes = {r["requirement"]: r for r in results["outcomes"]}
    assert len(outcomes) == 6 and {r["result"] for r in outcomes.values()} == {"PASS"}
    assert code == 0
    for scenario in ("owl_driver_lap_70", "lizard_phone_wheel_centre_70"):
        assert 3.0 <= outcomes[f"{scenario}.warns"]["measured_s"] <= 3.6
        assert outcomes[f"{scenario}.support_forward"]["measured_s"] <= 0.5
