"""What every behaviour may read at one sample: the `Context`, built once per sample, and the
`Behaviour` protocol each behaviour module implements. Pure.

A behaviour reads the sample's shared facts here (time, the sample in the driver's frame, speed,
where the driver looks, the eyes, the timers, the distraction trigger, the protocols, the alerts
active before this sample, and the events the behaviours before it raised at this sample); it
never reads another behaviour's state.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, TypeVar

from roadgaze.config import MonitorConfig
from roadgaze.monitor.episode import EPS_S, Episode
from roadgaze.monitor.events import Event, Raise, Resolve, Trigger
from roadgaze.monitor.eyes import EyeMonitorState
from roadgaze.monitor.look import Look
from roadgaze.monitor.zones import ZoneMap
from roadgaze.types import AlertKind, AlertLevel, EyeStatus, Gaze, PoseSample

__all__ = ["Behaviour", "Context", "SliceT"]

SliceT = TypeVar("SliceT")


@dataclass(frozen=True, slots=True)
class Context:
    """One sample's facts, measured before the behaviours run (`roadgaze.monitor.observe`)."""

    config: MonitorConfig
    zones: ZoneMap
    protocols: frozenset[str]
    """The configured protocols: `addw`, `euroncap` or both."""
    sample: PoseSample
    """The sample, its angles in the driver's frame."""
    speed_kmh: float | None
    moving: bool
    """Fast enough for a configured protocol to warn (unknown speed: moving)."""
    look: Look
    """Where the driver looks (zone, gaze, the yaw and pitch judged)."""
    eyes: EyeMonitorState
    """The eyes measured at this sample: status, closure, PERCLOS, blinks, gaze, degraded."""
    episode: Episode
    """The timers after this sample: off-road episode, distraction time, on-road and unavailable
    times."""
    episode_ended: bool
    """A counted off-road episode ended at this sample."""
    frame_issue: str
    """What is wrong with the image ('' for nothing): `black`, `saturated`, `blocked`."""
    trigger: Trigger | None
    """The distraction warning the configured protocols ask for at this speed (None: none)."""
    active: tuple[AlertKind, ...]
    """Alerts raised before this sample and not yet cleared, in the order they were raised."""
    events: tuple[Event, ...] = ()
    """What the behaviours before this one handed back at this sample."""

    @property
    def t_s(self) -> float:
        return self.sample.t_s

    def uses(self, protocol: str) -> bool:
        """Whether `protocol` (`addw` or `euroncap`) is configured."""
        return protocol in self.protocols

    @property
    def on_road_with_face(self) -> bool:
        return self.look.gaze is Gaze.ON_ROAD and self.sample.face

    @property
    def looking(self) -> bool:
        """On the road with a face and the eyes not closed."""
        return self.on_road_with_face and self.eyes.status is not EyeStatus.CLOSED

    @property
    def back_on_road(self) -> bool:
        """Looking at the road (with a face, the eyes not closed) for `clear_on_road_s`: what
        clears an alert whose cause was the driver's attention."""
        return self.looking and self.held(self.episode.on_since_s, self.config.clear_on_road_s)

    def held(self, since_s: float | None, duration_s: float) -> bool:
        """A run of samples that started at `since_s` (None: none runs) has lasted `duration_s`."""
        return since_s is not None and self.t_s - since_s >= duration_s - EPS_S

    def raised(self, kind: AlertKind, level: AlertLevel | None = None) -> bool:
        """An alert of `kind` (and `level`, if given) was raised at this sample before now."""
        return any(
            isinstance(e, Raise) and e.kind is kind and (level is None or e.level is level)
            for e in self.events
        )

    def resolved(self, recovery: bool) -> frozenset[AlertKind]:
        """The kinds whose cause ended at this sample (`recovery`: the failures that ended)."""
        return frozenset(
            kind
            for e in self.events
            if isinstance(e, Resolve) and e.recovery is recovery
            for kind in e.kinds
        )


class Behaviour(Protocol[SliceT]):
    """One behaviour of the monitor (roadgaze.monitor.behaviours): its state slice (a frozen
    dataclass of its own) and a pure step."""

    def initial(self) -> SliceT:
        """The slice before the first sample."""
        ...

    def step(self, context: Context, state: SliceT) -> tuple[SliceT, tuple[Event, ...]]:
        """The slice after this sample and the events it hands back."""
        ...
