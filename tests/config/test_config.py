"""Configuration precedence and the one-line errors for bad values."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from repo_paths import REPO
from roadgaze.config import Config, load_config, parse_overrides
from roadgaze.errors import ConfigError
from roadgaze.monitor.zones import ZoneMap


def test_defaults_are_the_documented_ones() -> None:
    config = load_config(environ={})
    assert config.geometry.model == "full_range"
    assert config.geometry.full_range_cue_deg == (20.0, 90.0)
    assert config.pose.pitch_model == "matrix"
    assert config.pose.pitch_down_gain == 1.48
    assert config.geometry.beta == 1.25
    assert config.monitor.long_distraction_s == 3.0
    assert config.monitor.min_speed_kmh == 20.0
    assert config.zenoh.multicast_scouting is False
    assert all("127.0.0.1" in endpoint for endpoint in config.zenoh.listen)


def test_file_then_environment_then_overrides(tmp_path: Path) -> None:
    path = tmp_path / "roadgaze.toml"
    path.write_text(
        "[monitor]\nmin_speed_kmh = 30\nlong_distraction_s = 2.5\n[zenoh]\nvehicle_id = 'a'\n"
    )
    environ = {"ROADGAZE__MONITOR__MIN_SPEED_KMH": "40", "ROADGAZE__ZENOH__VEHICLE_ID": "b"}
    config = load_config(path, {"zenoh.vehicle_id": "c"}, environ)
    assert config.monitor.long_distraction_s == 2.5  # file
    assert config.monitor.min_speed_kmh == 40.0  # environment beats file
    assert config.zenoh.vehicle_id == "c"  # override beats environment


def test_override_values_parse_as_toml_values() -> None:
    config = load_config(
        overrides=parse_overrides(
            ["zenoh.connect=['tcp/127.0.0.1:7447']", "logging.json_format=true", "model.path=/x"]
        ),
        environ={},
    )
    assert config.zenoh.connect == ["tcp/127.0.0.1:7447"]
    assert config.logging.json_format is True
    assert config.model.path == Path("/x")


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"monitor.min_speed_kmh": "-5"}, "monitor.min_speed_kmh"),
        ({"geometry.model": "sphere"}, "geometry.model"),
        ({"geometry.beta": "0.5"}, "geometry.beta"),
        ({"monitor.no_such_field": "1"}, "no_such_field"),
        ({"nosection.field": "1"}, "unknown section 'nosection'"),
        ({"toplevel": "1"}, "expected 'section.field'"),
        ({"zenoh.vehicle_id": "'has space'"}, "zenoh.vehicle_id"),
        ({"pose.pitch_model": "'sphere'"}, "pose.pitch_model"),
        ({"pose.pitch_down_gain": "0.5"}, "pose.pitch_down_gain"),
        ({"geometry.full_range_cue_deg": "[60, 30]"}, "geometry.full_range_cue_deg"),
        ({"smoothing.min_noise_samples": "40"}, "min_noise_samples"),
        ({"monitor.road_pitch_deg": "[10, -10]"}, "monitor.road_pitch_deg"),
        ({"monitor.hysteresis_deg": "25"}, "hysteresis_deg"),
        (
            {"monitor.zones": "[{name = 'lap', yaw_deg = [5, -5], pitch_deg = [-90, -18]}]"},
            "yaw_deg",
        ),
        ({"monitor.zones": "[{name = 'Lap!', yaw_deg = [-5, 5], pitch_deg = [-90, -18]}]"}, "name"),
        ({"monitor.zones": "[{name = 'road', yaw_deg = [-5, 5], pitch_deg = [-9, 9]}]"}, "road"),
        ({"monitor.driving_related_zones": "['sunroof']"}, "sunroof"),
    ],
)
def test_bad_values_raise_config_error_naming_the_field(
    overrides: dict[str, str], message: str
) -> None:
    with pytest.raises(ConfigError, match=message) as caught:
        load_config(overrides=overrides, environ={})
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize(
    ("content", "message"),
    [("[monitor\n", "not valid TOML"), ("[monitor]\nunknown = 1\n", "monitor.unknown")],
)
def test_bad_files_raise_config_error(tmp_path: Path, content: str, message: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(content)
    with pytest.raises(ConfigError, match=message):
        load_config(path, environ={})


def test_missing_file_raises_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="not found"):
        load_config(tmp_path / "absent.toml", environ={})


def test_zones_come_from_the_configuration_road_first() -> None:
    config = load_config(
        overrides={
            "monitor.road_half_width_deg": "30",
            # pitch up to 20 (30 before ADDW's roof: a driving-related zone may not reach it)
            "monitor.zones": "[{name = 'rear_mirror', yaw_deg = [-40, -15], pitch_deg = [5, 20]}]",
            "monitor.driving_related_zones": "['rear_mirror']",
        },
        environ={},
    )
    zones = ZoneMap.from_config(config.monitor)
    assert [zone.name for zone in zones.zones] == ["road", "rear_mirror"]
    road = zones.zones[0]
    assert (road.yaw_min_deg, road.yaw_max_deg) == (-25.0, 25.0)  # left at 30, entered at 25
    assert (road.pitch_min_deg, road.pitch_max_deg) == (-10.0, 15.0)
    assert zones.driving_related == frozenset({"rear_mirror"})
    assert zones.names == ("road", "rear_mirror", "far_left", "far_right", "roof", "away")


def test_bad_set_syntax_is_reported() -> None:
    with pytest.raises(ConfigError, match=r"section\.field=value"):
        parse_overrides(["monitor.min_speed_kmh"])


def test_shipped_default_config_loads_and_equals_the_built_in_defaults() -> None:
    shipped = load_config(REPO / "config" / "roadgaze.toml", environ={})
    assert shipped == Config()


def test_shipped_default_config_mentions_every_field() -> None:
    text = (REPO / "config" / "roadgaze.toml").read_text()
    for section_name, section in Config.model_fields.items():
        assert f"[{section_name}]" in text
        assert section.annotation is not None
        for field in section.annotation.model_fields:
            assert f"{field} =" in text, (
                f"config/roadgaze.toml does not mention {section_name}.{field}"
            )


FIELDS = sorted(
    f"{section}.{field}"
    for section, model in Config.model_fields.items()
    if model.annotation is not None
    for field in model.annotation.model_fields
)
VALUE_TEXTS = (
    st.sampled_from(["inf", "-inf", "nan", "true", "false", "''", "[]", "{}", "1e999", "-0"])
    | st.integers().map(str)
    | st.floats(allow_nan=True, allow_infinity=True).map(repr)
    | st.integers(4000, 6000).map(lambda n: "9" * n)
    | st.text(max_size=30)
    | st.lists(st.integers(), max_size=3).map(str)
)


@settings(max_examples=250, deadline=None)
@given(st.sampled_from(FIELDS), VALUE_TEXTS)
def test_fuzz_any_value_in_any_field_is_a_config_error_or_a_finite_config(
    field: str, text: str
) -> None:
    for origin in ("set", "env"):
        try:
            if origin == "set":
                config = load_config(overrides={field: text}, environ={})
            else:
                name = "ROADGAZE__" + field.upper().replace(".", "__")
                config = load_config(environ={name: text})
        except ConfigError as exc:
            assert "\n" not in str(exc) and len(str(exc)) < 1000
            continue
        for section in config.model_dump().values():
            for value in section.values():
                assert not isinstance(value, float) or math.isfinite(value)
