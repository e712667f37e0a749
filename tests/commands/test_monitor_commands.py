"""The schema and listen commands (their Zenoh round trips: test_transport, test_daemon)."""

from __future__ import annotations

import json

import jsonschema
import pytest

from roadgaze.cli import main
from roadgaze.commands.listen import _vehicle_of, format_pretty

pytestmark = pytest.mark.usefixtures("restore_logging")


def test_schema_prints_every_schema(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema"]) == 0
    schemas = json.loads(capsys.readouterr().out)
    assert sorted(schemas) == ["alert", "state", "support", "yaw"]
    for schema in schemas.values():
        jsonschema.Draft202012Validator.check_schema(schema)
    required = set(schemas["alert"]["required"])
    assert {"schema", "vehicle_id", "seq", "kind", "level", "t_s", "wall_time"} <= required
    assert {"yaw_deg", "off_road_s"} <= set(schemas["alert"]["properties"])
    yaw_fields = {"schema", "vehicle_id", "seq", "t_s", "frame", "face", "yaw_deg", "yaw_raw_deg"}
    assert yaw_fields | {"on_road"} <= set(schemas["yaw"]["properties"])
    assert schemas["alert"]["properties"]["schema"]["const"] == "roadgaze.alert/4"
    # roadgaze.yaw/2 extends /1 with the pose and the zone; every field is always published
    new_fields = {"pitch_deg", "pitch_raw_deg", "roll_deg", "zone", "eyes_on_road"}
    assert new_fields | {"neutral_pitch_deg"} | yaw_fields <= set(schemas["yaw"]["required"])
    assert schemas["yaw"]["properties"]["schema"]["const"] == "roadgaze.yaw/3"
    assert schemas["state"]["properties"]["schema"]["const"] == "roadgaze.state/6"
    snapshot = schemas["state"]["$defs"]["MonitorSnapshot"]
    assert {"zone", "neutral_pitch_deg", "pitch_deg"} <= set(snapshot["required"])
    # yaw/3 and state/3 add the eyes; alert/2 the closure and drowsiness kinds
    eye_fields = {"eyes", "eye_openness", "gaze_yaw_deg", "gaze_pitch_deg", "gaze_source"}
    eye_fields |= {"closure_s", "perclos", "blinks", "eyes_unavailable_s", "degraded"}
    assert eye_fields <= set(schemas["yaw"]["required"])
    assert eye_fields <= set(snapshot["required"])
    # state/4 adds the eye calibration to the monitor
    assert "eye_calibration" in snapshot["required"]
    kinds = set(schemas["alert"]["$defs"]["AlertKind"]["enum"])
    assert {"microsleep", "sleep", "drowsy", "unresponsive", "degraded"} <= kinds
    assert {"closure_s", "perclos", "reason"} <= set(schemas["alert"]["required"])
    # alert/3: the failure kinds and the protocol rule; state/4: protocol, failures
    assert {"temporary_failure", "permanent_failure"} <= kinds
    assert {"rule", "source"} <= set(schemas["alert"]["required"])
    assert {"protocol", "distraction_warn_s", "distraction_rule", "failure"} <= set(
        snapshot["required"]
    )
    # state/5: why the driver cannot be told from another face
    assert "driver_ambiguous" in schemas["state"]["required"]
    assert "permanent_failure" in schemas["state"]["required"]
    # state/6: forward and lane support in the monitor
    assert {"support_forward", "support_lane"} <= set(snapshot["required"])


def test_schema_of_one_message(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema", "yaw"]) == 0
    assert json.loads(capsys.readouterr().out)["title"] == "YawMessage"


@pytest.mark.parametrize(
    ("kind", "payload", "expected"),
    [
        ("alive", {"alive": False}, "alive  car-1 left"),
        (
            "alert",
            {
                "seq": 3,
                "kind": "vats",
                "level": "warning",
                "t_s": 15.0,
                "off_road_s": 0.0,
                "window_off_road_s": 10.0,
                "yaw_deg": None,
            },
            "ALERT  car-1 #3 vats warning t=15.00s off_road=0.00s window=10.00s no face",
        ),
        (
            "yaw",
            {"seq": 9, "t_s": 0.3, "yaw_deg": -12.34, "gaze": "on_road"},
            "yaw    car-1 #9      t=0.30s      -12.3° on_road",
        ),
        (
            "yaw",
            {"seq": 9, "t_s": 0.3, "yaw_deg": 1.0, "pitch_deg": -41.26, "zone": "lap"},
            "yaw    car-1 #9      t=0.30s       +1.0° pitch   -41.3° lap",
        ),
        (
            "yaw",
            {
                "seq": 9,
                "t_s": 0.3,
                "yaw_deg": None,
                "pitch_deg": None,
                "zone": None,
                "gaze": "unknown",
            },
            "yaw    car-1 #9      t=0.30s        --   pitch     --   unknown",
        ),
        (
            "yaw",
            {
                "seq": 9,
                "t_s": 0.3,
                "yaw_deg": -1.2,
                "pitch_deg": -11.1,
                "zone": "centre_stack",
                "eyes": "open",
                "eye_openness": 0.171,
                "gaze_yaw_deg": -20.8,
                "gaze_pitch_deg": -22.8,
                "gaze_source": "eyes",
                "closure_s": 0.0,
                "perclos": 0.04,
                "degraded": False,
            },
            "yaw    car-1 #9      t=0.30s       -1.2° pitch   -11.1° centre_stack eyes open 0.17 "
            "gaze -20.8°/-22.8° perclos 0.04",
        ),
        (
            "yaw",
            {"seq": 9, "t_s": 0.3, "yaw_deg": -1.0, "pitch_deg": -11.0, "zone": "road"}
            | {"eyes": "closed", "eye_openness": 0.02, "closure_s": 1.8, "degraded": True},
            "yaw    car-1 #9      t=0.30s       -1.0° pitch   -11.0° road eyes closed 0.02 "
            "closed 1.8s DEGRADED",
        ),
        (
            "alert",
            {"seq": 4, "kind": "sleep", "level": "critical", "t_s": 12.6, "yaw_deg": -1.0}
            | {"off_road_s": 0.0, "window_off_road_s": 0.0, "closure_s": 3.0}
            | {"reason": "eyes closed 3.0 s"},
            "ALERT  car-1 #4 sleep critical t=12.60s off_road=0.00s window=0.00s yaw=-1.0° "
            "closure=3.00s (eyes closed 3.0 s)",
        ),
        ("state", None, "state  car-1 undecodable payload: garbage"),
    ],
)
def test_listen_pretty_lines(kind: str, payload: dict[str, object] | None, expected: str) -> None:
    assert format_pretty(kind, "car-1", payload, "garbage") == expected


def test_listen_vss_line() -> None:
    from roadgaze.commands.listen import format_vss

    assert format_vss("Vehicle/Driver/FatigueLevel", "60.0") == (
        "vss    Vehicle/Driver/FatigueLevel = 60.0"
    )


def test_listen_finds_the_vehicle_in_the_key() -> None:
    assert _vehicle_of("vehicle/car-9/dms/alert", "vehicle/{vehicle_id}/dms") == "car-9"
    assert _vehicle_of("fleet/x/alert", "fleet/dms") == "?"


def test_bad_zenoh_option_is_a_one_line_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["listen", "--vehicle-id", "bad id!", "--timeout", "0.1"]) == 2
    assert "vehicle id must be 1-64" in capsys.readouterr().err
