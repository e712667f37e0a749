"""Glance zones: ordered rectangles relative to the neutral pose, first match wins, hysteresis."""

from __future__ import annotations

import pytest

from roadgaze.config import MonitorConfig
from roadgaze.monitor.zones import AWAY, DEFAULT_ZONES, ROAD, Zone, ZoneMap, classify_zone

DEFAULTS = ZoneMap.from_config(MonitorConfig())


def test_the_configured_defaults_are_the_documented_table() -> None:
    assert DEFAULTS.zones == DEFAULT_ZONES
    assert DEFAULTS.names == (
        "road", "lap", "cluster", "centre_stack", "left_mirror", "right_mirror",
        "far_left", "far_right", "roof", "away",
    )  # fmt: skip
    assert DEFAULTS.driving_related == frozenset({"left_mirror", "right_mirror"})


@pytest.mark.parametrize(
    ("yaw_deg", "pitch_deg", "zone"),
    [
        (0.0, 0.0, "road"),
        (20.0, 15.0, "road"),  # edges belong to the rectangle
        (0.0, -40.0, "lap"),  # phone in the lap: about 30 deg of gaze, 20-30 of head pitch
        (24.0, -18.0, "lap"),
        (0.0, -14.0, "cluster"),
        (-30.0, -20.0, "centre_stack"),
        (-20.0, -30.0, "lap"),  # lap is tested before the centre stack
        (45.0, 0.0, "left_mirror"),
        (-45.0, 0.0, "right_mirror"),
        (-27.0, 0.0, "away"),  # rear-view mirror: not a configured zone
        (0.0, 18.0, "away"),  # looking up, below the roof
        (52.0, 0.0, "away"),  # past the left mirror, short of 55 deg
    ],
)
def test_first_match_wins_else_away(yaw_deg: float, pitch_deg: float, zone: str) -> None:
    assert classify_zone(yaw_deg, pitch_deg, None) == zone
    assert DEFAULTS.classify(yaw_deg, pitch_deg, None) == zone


@pytest.mark.parametrize(
    ("previous", "yaw_deg", "pitch_deg", "zone"),
    [
        ("road", 24.9, 0.0, "road"),  # kept within the grown rectangle
        ("road", 25.1, 0.0, "left_mirror"),
        ("road", 0.0, -14.9, "road"),
        ("road", 0.0, -15.1, "cluster"),
        ("left_mirror", 19.0, 0.0, "road"),  # back to the road as soon as inside its rectangle
        ("left_mirror", 0.0, -30.0, "lap"),
        ("lap", 0.0, -14.0, "lap"),  # the lap is left above -13
        ("lap", 0.0, -12.0, "cluster"),
        ("cluster", 0.0, -20.0, "cluster"),
        ("away", -22.0, 0.0, "away"),  # away is not sticky, but nothing else matches
        ("right_mirror", -26.0, 0.0, "right_mirror"),
        ("right_mirror", -24.0, 0.0, "away"),
        ("left_mirror", 54.0, 0.0, "left_mirror"),
        ("left_mirror", 56.0, 0.0, "far_left"),  # ADDW's area 1 beats hysteresis
    ],
)
def test_hysteresis_keeps_the_previous_zone(
    previous: str, yaw_deg: float, pitch_deg: float, zone: str
) -> None:
    assert DEFAULTS.classify(yaw_deg, pitch_deg, previous) == zone


def test_zone_maps_are_validated() -> None:
    road = Zone(ROAD, -20.0, 20.0, -10.0, 15.0)
    lap = Zone("lap", -25.0, 25.0, -90.0, -18.0)
    with pytest.raises(ValueError, match="first zone"):
        ZoneMap(zones=(lap, road))
    with pytest.raises(ValueError, match="unique"):
        ZoneMap(zones=(road, lap, lap))
    with pytest.raises(ValueError, match="unique"):
        ZoneMap(zones=(road, Zone(AWAY, 0.0, 1.0, 0.0, 1.0)))
    with pytest.raises(ValueError, match="driving-related"):
        ZoneMap(zones=(road, lap), driving_related=frozenset({"left_mirror"}))
    assert (
        ZoneMap(zones=(road, lap), driving_related=frozenset()).classify(0.0, -30.0, None) == "lap"
    )
