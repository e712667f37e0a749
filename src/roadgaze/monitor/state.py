"""The monitor's state between samples: the measured facts and one slice per behaviour. Pure."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, TypeVar

from roadgaze.config import MonitorConfig
from roadgaze.monitor.context import Behaviour
from roadgaze.monitor.episode import EPS_S, Episode, segment_distraction_s, window_total
from roadgaze.monitor.events import Trigger
from roadgaze.monitor.eyes import EyeMonitorState
from roadgaze.monitor.look import Look
from roadgaze.monitor.neutral import NeutralPose
from roadgaze.monitor.protocols import behaviours as configured_behaviours
from roadgaze.types import AlertKind, Output

__all__ = [
    "EPS_S",
    "MonitorState",
    "distraction_s",
    "initial_state",
    "segment_distraction_s",
    "window_total",
]

SliceT = TypeVar("SliceT")


@dataclass(frozen=True, slots=True)
class MonitorState:
    """Everything the monitor remembers between samples; replace, never mutate.

    The facts measured at every sample (the neutral pose, where the driver looks, the eyes, the
    timers) and `slices`, the state of each behaviour in the order the configured protocols run
    them (`roadgaze.monitor.protocols.behaviours`); `slice` finds one by its type.
    """

    neutral: NeutralPose = field(default_factory=NeutralPose)
    look: Look = field(default_factory=Look)
    """Where the driver looked at the last sample (zone, gaze, hysteresis, face loss)."""
    eyes: EyeMonitorState = field(default_factory=EyeMonitorState)
    """The eyes: closure, blinks, PERCLOS, gaze, unavailable time (roadgaze.monitor.eyes)."""
    episode: Episode = field(default_factory=Episode)
    """The timers: off-road episode, distraction time, on-road and unavailable times."""
    slices: tuple[Any, ...] = ()
    t_s: float | None = None
    """Timestamp of the last sample taken into account."""
    moving: bool = True
    speed_kmh: float | None = None
    trigger: Trigger | None = None
    """The distraction warning due at the last sample's speed; None when none is active."""
    active: tuple[AlertKind, ...] = ()
    """Alerts raised and not yet cleared, in the order they were raised."""
    outputs: tuple[Output, ...] = ()
    """The behaviours' per-frame outputs at the last sample (`Publish` events)."""
    samples: int = 0
    alert_counts: tuple[tuple[str, int], ...] = ()

    @property
    def on_road(self) -> bool:
        """The hysteresis state: the last judged zone is the road."""
        return self.look.on_road

    def slice(self, kind: type[SliceT]) -> SliceT | None:
        """The slice of type `kind` (None: no configured behaviour keeps one)."""
        return next((s for s in self.slices if isinstance(s, kind)), None)

    def off_road_s(self) -> float:
        """Length of the current counted off-road episode at the last sample."""
        return self.episode.off_road_s(self.t_s)

    def window_off_road_s(self, window_s: float) -> float:
        """Counted off-road time within `window_s` before the last sample."""
        return self.episode.window_s(self.t_s, window_s)

    def unavailable_s(self) -> float:
        return self.episode.unavailable_s(self.t_s)


def initial_state(
    config: MonitorConfig, behaviours: tuple[Behaviour[Any], ...] | None = None
) -> MonitorState:
    """The state before the first sample: on road, neutral at the configured values or 0, the
    initial slice of each behaviour (default: those the configured protocols run)."""
    if behaviours is None:
        behaviours = configured_behaviours(config.protocol)
    return MonitorState(
        neutral=NeutralPose.from_config(config),
        slices=tuple(behaviour.initial() for behaviour in behaviours),
    )


def distraction_s(config: MonitorConfig, state: MonitorState) -> float:
    """The long-distraction timer at the last sample: the current episode's time outside the
    driving-related zones."""
    return state.episode.distraction_s(config, state.t_s)
