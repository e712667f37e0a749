"""The monitor's state between samples, and the durations derived from it. Pure."""

from __future__ import annotations

from dataclasses import dataclass, field

from roadgaze.config import MonitorConfig
from roadgaze.monitor.eyes import EyeMonitorState
from roadgaze.monitor.failures import FailureState
from roadgaze.monitor.zones import ROAD
from roadgaze.types import AlertKind, AlertLevel, Gaze

__all__ = [
    "EPS_S",
    "MonitorState",
    "distraction_s",
    "initial_state",
    "segment_distraction_s",
    "window_total",
]

EPS_S = 1e-6
"""Durations are sums of float timestamps: compare them with this tolerance."""


@dataclass(frozen=True, slots=True)
class MonitorState:
    """Everything the monitor remembers between samples; replace, never mutate."""

    neutral_yaw_deg: float
    neutral_pitch_deg: float = 0.0
    neutral_yaw_learned_s: float = 0.0
    """Road time the neutral yaw has learned from (its running mean's weight)."""
    neutral_pitch_learned_s: float = 0.0
    t_s: float | None = None
    """Timestamp of the last sample taken into account."""
    gaze: Gaze = Gaze.ON_ROAD
    zone: str | None = ROAD
    """This sample's zone; None when the gaze is unknown."""
    face_zone: str = ROAD
    """The zone of the last sample with a usable yaw: the hysteresis state, kept through face
    losses."""
    yaw_deg: float | None = None
    pitch_deg: float | None = None
    last_face_yaw_deg: float | None = None
    face_lost_since_s: float | None = None
    face_lost_turned_away: bool = False
    moving: bool = True
    speed_kmh: float | None = None
    off_since_s: float | None = None
    """Start of the current counted (off road and moving) episode."""
    segment_since_s: float | None = None
    """Start of the current run of driving-related (or of other) samples within the episode."""
    segment_driving: bool = False
    distraction_before_s: float = 0.0
    """Distraction time of the episode's runs before the current one."""
    long_level: AlertLevel | None = None
    """Level already raised for the current episode."""
    last_off_road_s: float = 0.0
    """Duration of the most recent finished episode."""
    off_intervals: tuple[tuple[float, float], ...] = ()
    """Finished counted episodes [start, end) that still overlap the VATS window."""
    vats_armed: bool = True
    on_since_s: float | None = None
    """Start of the current continuous on-road period (with a face)."""
    unavailable_since_s: float | None = None
    unavailable_alerted: bool = False
    active: tuple[AlertKind, ...] = ()
    """Alerts raised and not yet cleared, in the order they were raised."""
    samples: int = 0
    alert_counts: tuple[tuple[str, int], ...] = field(default=())
    eyes: EyeMonitorState = field(default_factory=EyeMonitorState)
    """The eyes: closure, blinks, PERCLOS, gaze, unavailable time (roadgaze.monitor.eyes)."""
    warned_since_s: float | None = None
    """When a distraction warning asked the driver to look back and they have not yet."""
    away_unresponsive: bool = False
    """`unresponsive` was raised for the current off-road episode."""
    failures: FailureState = field(default_factory=FailureState)
    """The failure timers (roadgaze.monitor.failures)."""
    warn_s: float | None = None
    """The distraction time that warns at the last sample's speed; None when none is active."""
    warn_rule: str = ""
    """The rule giving `warn_s`."""

    @property
    def on_road(self) -> bool:
        """The hysteresis state: the last judged zone is the road."""
        return self.face_zone == ROAD

    def off_road_s(self) -> float:
        """Length of the current counted off-road episode at the last sample."""
        if self.off_since_s is None or self.t_s is None:
            return 0.0
        return self.t_s - self.off_since_s

    def window_off_road_s(self, window_s: float) -> float:
        """Counted off-road time within `window_s` before the last sample."""
        if self.t_s is None:
            return 0.0
        return window_total(self.off_intervals, self.off_since_s, self.t_s, window_s)

    def unavailable_s(self) -> float:
        if self.unavailable_since_s is None or self.t_s is None:
            return 0.0
        return self.t_s - self.unavailable_since_s


def initial_state(config: MonitorConfig) -> MonitorState:
    """The state before the first sample: on road, neutral at the configured values or 0."""
    return MonitorState(
        neutral_yaw_deg=0.0 if config.neutral_yaw_deg is None else config.neutral_yaw_deg,
        neutral_pitch_deg=0.0 if config.neutral_pitch_deg is None else config.neutral_pitch_deg,
    )


def window_total(
    intervals: tuple[tuple[float, float], ...],
    open_since_s: float | None,
    t_s: float,
    window_s: float,
) -> float:
    """Time of `intervals` (and of an episode open since `open_since_s`) within `window_s`."""
    start_s = t_s - window_s
    total = sum(max(0.0, min(end, t_s) - max(begin, start_s)) for begin, end in intervals)
    if open_since_s is not None:
        total += max(0.0, t_s - max(open_since_s, start_s))
    return total


def segment_distraction_s(
    config: MonitorConfig, since_s: float | None, t_s: float, driving: bool
) -> float:
    """Distraction time of one run of samples: all of it, or none for a driving-related run
    (unless it outlasts `driving_glance_max_s`)."""
    if since_s is None:
        return 0.0
    length_s = t_s - since_s
    if not driving:
        return length_s
    limit_s = config.driving_glance_max_s
    return length_s if limit_s is not None and length_s >= limit_s - EPS_S else 0.0


def distraction_s(config: MonitorConfig, state: MonitorState) -> float:
    """The long-distraction timer at the last sample: the current episode's time outside the
    driving-related zones."""
    if state.off_since_s is None or state.t_s is None:
        return 0.0
    return state.distraction_before_s + segment_distraction_s(
        config, state.segment_since_s, state.t_s, state.segment_driving
    )
