"""The monitor's limits as drawn: the road zone's yaw and pitch bands around the learned neutral
and the timers' thresholds (the plot, the annotated video's panel and the Foxglove channels)."""

from __future__ import annotations

from typing import TypeVar

from roadgaze.config import MonitorConfig
from roadgaze.types import FloatArray

Degrees = TypeVar("Degrees", float, FloatArray)
"""One frame's angle (a float) or every frame's (an array): the band functions take either."""


def road_bands_deg(
    neutral_deg: Degrees, monitor: MonitorConfig
) -> tuple[tuple[Degrees, Degrees], tuple[Degrees, Degrees]]:
    """The monitor's yaw limits per frame, degrees: the road-ahead band (neutral +-
    `road_half_width_deg`, left on crossing it) and the narrower band a head off road must come
    back into (neutral +- (`road_half_width_deg` - `hysteresis_deg`))."""
    half = monitor.road_half_width_deg
    back = max(0.0, half - monitor.hysteresis_deg)
    return (neutral_deg - half, neutral_deg + half), (neutral_deg - back, neutral_deg + back)


def road_pitch_bands_deg(
    neutral_deg: Degrees, monitor: MonitorConfig
) -> tuple[tuple[Degrees, Degrees], tuple[Degrees, Degrees]]:
    """The road zone's pitch limits per frame, degrees: left beyond neutral + `road_pitch_deg`
    grown by `hysteresis_deg`, entered again within neutral + `road_pitch_deg`."""
    low, high = monitor.road_pitch_deg
    grow = monitor.hysteresis_deg
    return (neutral_deg + low - grow, neutral_deg + high + grow), (
        neutral_deg + low,
        neutral_deg + high,
    )


TIMER_THRESHOLDS: tuple[tuple[str, str, str], ...] = (
    ("long_distraction_s", "long distraction", "tab:orange"),
    ("critical_distraction_s", "critical", "tab:red"),
    ("vats_threshold_s", "VATS", "tab:purple"),
    ("microsleep_s", "microsleep", "tab:brown"),
    ("sleep_s", "sleep", "tab:brown"),
)
"""The timers' thresholds drawn with them: the monitor setting, its label, its colour."""


def timer_thresholds(monitor: MonitorConfig) -> list[tuple[str, float, str, str]]:
    """(setting, seconds, label, colour) of each threshold in `TIMER_THRESHOLDS`."""
    return [
        (key, float(getattr(monitor, key)), label, colour)
        for key, label, colour in TIMER_THRESHOLDS
    ]


def threshold_labels(monitor: MonitorConfig) -> list[tuple[float, str, str]]:
    """(seconds, label, colour) per threshold value: thresholds with equal values (long
    distraction and sleep, both 3 s by default) share one label, so none prints over another;
    the colour is the first one's."""
    grouped: dict[float, tuple[list[str], str]] = {}
    for _, seconds, name, colour in timer_thresholds(monitor):
        grouped.setdefault(seconds, ([], colour))[0].append(name)
    return [
        (seconds, f"{', '.join(names)} {seconds:g} s", colour)
        for seconds, (names, colour) in grouped.items()
    ]
