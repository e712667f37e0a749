"""Protocols as data: speed bands, the earlier of two protocols, escalation, clearing, the
rule each alert names, ADDW's area 1 and the camera mounting in the monitor."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from fakes import drive_monitor, open_eyes
from roadgaze.config import MonitorConfig, load_config
from roadgaze.errors import ConfigError
from roadgaze.monitor import Monitor
from roadgaze.monitor.protocols import ALL_RULES, addw, distraction_trigger, euroncap, moving_at
from roadgaze.pose.mounting import gaze_to_camera, mounting_for
from roadgaze.types import Alert, PoseSample

FPS = 15.0
BOTH, ADDW, NCAP = (MonitorConfig(protocol=p) for p in ("both", "addw", "euroncap"))  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("config", "speed_kmh", "warn_s", "rule"),
    [
        (ADDW, 10.0, None, None),
        (ADDW, 20.0, None, None),  # active only above 20
        (ADDW, 20.1, 6.0, "addw.distraction.20_50kmh"),
        (ADDW, 50.0, 6.0, "addw.distraction.20_50kmh"),
        (ADDW, 50.1, 3.5, "addw.distraction.above_50kmh"),
        (ADDW, None, 3.5, "addw.distraction.above_50kmh"),  # unknown: moving, highest band
        (NCAP, 10.0, None, None),
        (NCAP, 30.0, 3.0, "euroncap.long_distraction"),
        (BOTH, 10.0, None, None),  # both protocols inactive at 10 km/h by default
        (BOTH, 30.0, 3.0, "euroncap.long_distraction"),  # the earlier of 6 and 3
        (BOTH, 130.0, 3.0, "euroncap.long_distraction"),
    ],
)
def test_speed_bands_pick_the_trigger(
    config: MonitorConfig, speed_kmh: float | None, warn_s: float | None, rule: str | None
) -> None:
    trigger = distraction_trigger(config, speed_kmh)
    assert (None if trigger is None else (trigger.warn_s, trigger.rule.key)) == (
        None if warn_s is None else (warn_s, rule)
    )
    assert moving_at(config, speed_kmh) is (warn_s is not None)


def test_non_nominal_allowance_is_added_to_addw_only() -> None:
    trigger = distraction_trigger(ADDW, 70.0, non_nominal=True)
    assert trigger is not None and (trigger.warn_s, trigger.allowance_s) == (5.0, 1.5)
    both = distraction_trigger(BOTH, 70.0, non_nominal=True)
    assert both is not None and both.warn_s == 3.0  # Euro NCAP's 3 s still warns first


def test_every_rule_names_a_setting_with_a_value_and_a_source() -> None:
    config = MonitorConfig()
    keys = [rule.key for rule in ALL_RULES]
    assert len(keys) == len(set(keys))
    for rule in ALL_RULES:
        assert rule.config_key in MonitorConfig.model_fields, rule
        assert rule.value(config) is not None and rule.source and rule.unit
    assert addw.DISTRACTION_HIGH.value(config) == 3.5 and addw.DISTRACTION_LOW.value(config) == 6
    assert euroncap.VATS.value(config) == 10.0 and addw.AREA_YAW.value(config) == 55.0


def run(
    config: MonitorConfig,
    pose_at: Callable[[float], tuple[float | None, float]],
    speed_kmh: float | None,
    duration_s: float,
) -> list[Alert]:
    return drive_monitor(Monitor(config), pose_at, speed_kmh, duration_s, FPS)


def look(
    yaw: float, pitch: float, start_s: float = 3.0, length_s: float = 4.0
) -> Callable[[float], tuple[float | None, float]]:
    return lambda t: (yaw, pitch) if start_s <= t < start_s + length_s else (0.0, 0.0)


@pytest.mark.parametrize(
    ("yaw", "pitch", "zone"),
    [(65.0, 0.0, "far_left"), (-65.0, 0.0, "far_right"), (0.0, -35.0, "lap"), (0.0, 25.0, "roof")],
)
def test_a_four_second_look_at_70_kmh_warns_three_seconds_in(
    yaw: float, pitch: float, zone: str
) -> None:
    alerts = run(BOTH, look(yaw, pitch), 70.0, 10.0)
    warning = alerts[0]
    assert (warning.kind.value, warning.level.value) == ("long_distraction", "warning")
    assert warning.t_s == pytest.approx(6.0, abs=1 / FPS)  # 3.0 s after the look starts
    assert warning.rule == "euroncap.long_distraction" and warning.reason == f"head in {zone}"
    assert "Euro NCAP" in warning.source
    assert [a.kind.value for a in alerts] == ["long_distraction", "cleared"]


def test_mirror_glances_and_slow_lap_glances_raise_nothing() -> None:
    assert run(BOTH, look(40.0, 0.0, length_s=1.5), 70.0, 8.0) == []  # left mirror
    assert run(BOTH, look(-45.0, 0.0, length_s=1.5), 70.0, 8.0) == []  # right mirror
    assert run(BOTH, look(0.0, -35.0, length_s=8.0), 10.0, 14.0) == []  # lap at 10 km/h


def test_addw_bands_escalation_and_clearing() -> None:
    lap = look(0.0, -35.0, length_s=8.0)
    alerts = run(ADDW, lap, 30.0, 14.0)
    assert [(a.kind.value, a.level.value, a.rule) for a in alerts] == [
        ("long_distraction", "warning", "addw.distraction.20_50kmh"),
        ("cleared", "info", "roadgaze.clear"),
    ]
    assert alerts[0].t_s == pytest.approx(9.0, abs=1 / FPS)
    alerts = run(ADDW, lap, 90.0, 14.0)
    assert [(a.level.value, round(a.t_s, 2)) for a in alerts[:2]] == [
        ("warning", 6.53),  # 3.5 s (first frame at or after it)
        ("critical", 9.53),  # critical_after_warning_s later
    ]
    assert alerts[1].rule == "roadgaze.escalation.critical"
    slow_clear = ADDW.model_copy(update={"clear_on_road_s": 1.0})
    cleared = [a for a in run(slow_clear, lap, 90.0, 14.0) if a.kind.value == "cleared"]
    assert cleared[0].t_s == pytest.approx(11.0 + 1.0, abs=1 / FPS)


def test_vats_and_away_unresponsive_are_euro_ncap_rules() -> None:
    def glances(t: float) -> tuple[float, float]:
        return (-27.0, 0.0) if (t % 4.0) < 2.5 and t > 1.0 else (0.0, 0.0)

    ncap = [a for a in run(NCAP, glances, 70.0, 20.0) if a.kind.value == "vats"]
    assert ncap and ncap[0].rule == "euroncap.vats"
    assert [a for a in run(ADDW, glances, 70.0, 20.0) if a.kind.value == "vats"] == []


@pytest.mark.parametrize(
    ("update", "message"),
    [
        ({"distraction_yaw_deg": 60}, "less than or equal to 55"),
        (
            {
                "driving_related_zones": ["side"],
                "zones": [{"name": "side", "yaw_deg": [40, 70], "pitch_deg": [-10, 10]}],
            },
            "area 1",
        ),
        (
            {
                "zones": [{"name": "roof", "yaw_deg": [-5, 5], "pitch_deg": [20, 40]}],
                "driving_related_zones": [],
            },
            "reserved",
        ),
        ({"addw_band_kmh": 10}, "addw_band_kmh"),
        ({"camera_mounting": "dashboard"}, "camera_mounting"),
        ({"cabin": "center"}, "cabin"),
    ],
)
def test_configuration_cannot_make_area_one_driving_related(
    update: dict[str, object], message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        MonitorConfig.model_validate(update)
    if "cabin" in update:  # and from the command line, one clear line
        with pytest.raises(ConfigError, match=r"monitor\.cabin"):
            load_config(overrides={"monitor.cabin": "center"}, environ={})


@pytest.mark.parametrize("preset", ["steering_column", "a_pillar", "centre_console"])
@pytest.mark.parametrize("cabin", ["lhd", "rhd"])
def test_the_mounting_maps_the_road_pose_to_the_driver_frame(preset: str, cabin: str) -> None:
    """The road ahead seen by a camera off the axis is road; the learned neutral stays near 0."""
    config = MonitorConfig(camera_mounting=preset, cabin=cabin)  # type: ignore[arg-type]
    mounting = mounting_for(preset, cabin)  # type: ignore[arg-type]
    road = gaze_to_camera(mounting, 0.0, 0.0)
    left = gaze_to_camera(mounting, 65.0, 0.0)  # a look beyond 55 deg, as the camera sees it
    monitor = Monitor(config)
    alerts: list[Alert] = []
    for frame in range(round(10 * FPS)):
        t_s = frame / FPS
        yaw, pitch = left if 3.0 <= t_s < 7.0 else road
        sample = PoseSample(t_s, frame, True, yaw, yaw, 0.0, 1.0, None, 1, pitch, pitch,
                            eyes=open_eyes())  # fmt: skip
        alerts.extend(monitor.update(sample, 70.0))
        if frame == round(2.5 * FPS):
            assert monitor.verdict.zone == "road"
            assert abs(monitor.verdict.neutral_yaw_deg) < 1e-6
            assert monitor.camera_neutral_pitch_deg == pytest.approx(road[1], abs=1e-6)
    assert [a.kind.value for a in alerts] == ["long_distraction", "cleared"]
    assert alerts[0].reason == "head in far_left"
