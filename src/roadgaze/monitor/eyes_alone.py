"""The eyes alone: the eye measurement and the eye behaviours (closure, drowsiness, degraded) run
without the rest of the monitor, for tests and tools that study the eyes. Pure.

`step_eyes` is what `roadgaze.monitor.eyes.step_eyes` was before the behaviours had modules of
their own: one sample in, the eyes' state and the alerts they call for out.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from roadgaze.config import MonitorConfig
from roadgaze.monitor.behaviours import (
    CLOSURE_ALERTS,
    Degraded,
    DegradedState,
    Drowsy,
    DrowsyState,
    EyeClosure,
    EyeClosureState,
)
from roadgaze.monitor.context import Context
from roadgaze.monitor.episode import Episode
from roadgaze.monitor.events import Raise, Resolve
from roadgaze.monitor.eyes import EyeMonitorState, measure_eyes
from roadgaze.monitor.look import Look
from roadgaze.monitor.protocols import configured, euroncap, roadgaze
from roadgaze.monitor.zones import ZoneMap
from roadgaze.types import AlertKind, EyesVerdict, Gaze, PoseSample

__all__ = ["EyesAlone", "clearable_eye_kinds", "step_eyes"]

_CLOSURE = EyeClosure(euroncap.MICROSLEEP, euroncap.SLEEP, euroncap.UNRESPONSIVE_CLOSED)
_DROWSY = Drowsy(roadgaze.DROWSY)
_DEGRADED = Degraded(euroncap.IMPAIRED)
_EYE_KINDS = (*CLOSURE_ALERTS, AlertKind.DROWSY, AlertKind.DEGRADED)


@dataclass(frozen=True, slots=True)
class EyesAlone:
    """The eyes' measurement and the eye behaviours' slices; replace, never mutate."""

    eyes: EyeMonitorState = field(default_factory=EyeMonitorState)
    closure: EyeClosureState = field(default_factory=EyeClosureState)
    drowsy: DrowsyState = field(default_factory=DrowsyState)
    degraded: DegradedState = field(default_factory=DegradedState)

    @property
    def verdict(self) -> EyesVerdict:
        return self.eyes.verdict


def _context(
    config: MonitorConfig,
    sample: PoseSample,
    eyes: EyeMonitorState,
    moving: bool,
    on_road: bool,
    active: tuple[AlertKind, ...] = (),
) -> Context:
    return Context(
        config=config,
        zones=ZoneMap(),
        protocols=configured(config.protocol),
        sample=sample,
        speed_kmh=None,
        moving=moving,
        look=Look(gaze=Gaze.ON_ROAD if on_road else Gaze.OFF_ROAD),
        eyes=eyes,
        episode=Episode(on_since_s=sample.t_s - config.clear_on_road_s if on_road else None),
        episode_ended=False,
        frame_issue="",
        trigger=None,
        active=active,
    )


def step_eyes(
    config: MonitorConfig,
    state: EyesAlone,
    sample: PoseSample,
    moving: bool,
    on_road: bool,
    head_yaw_deg: float | None,
    head_pitch_deg: float | None,
) -> tuple[EyesAlone, tuple[Raise, ...]]:
    """Advance the eyes by one sample; returns the new state and the alerts they call for.

    `on_road`: the monitor's road decision at the previous sample. A sample not after the
    previous one is ignored."""
    eyes = measure_eyes(config, state.eyes, sample, moving, on_road, head_yaw_deg, head_pitch_deg)
    if eyes is state.eyes:
        return state, ()
    context = _context(config, sample, eyes, moving, on_road)
    closure, closure_events = _CLOSURE.step(context, state.closure)
    drowsy, drowsy_events = _DROWSY.step(context, state.drowsy)
    degraded, degraded_events = _DEGRADED.step(context, state.degraded)
    events = (*closure_events, *drowsy_events, *degraded_events)
    raised = tuple(e for e in events if isinstance(e, Raise))
    return EyesAlone(eyes, closure, drowsy, degraded), raised


def clearable_eye_kinds(
    state: EyesAlone, on_road: bool, config: MonitorConfig | None = None
) -> frozenset[AlertKind]:
    """The eye alerts whose cause has ended at the last sample, as the eye behaviours resolve
    them (`on_road`: looking at the road with a face; `config`: the one the eyes ran with)."""
    sample = PoseSample(
        t_s=state.eyes.t_s or 0.0,
        frame=0,
        face=True,
        yaw_raw_deg=0.0,
        yaw_deg=0.0,
        yaw_rate_dps=None,
        yaw_std_deg=None,
    )
    config = config if config is not None else MonitorConfig()
    context = _context(config, sample, state.eyes, False, on_road, _EYE_KINDS)
    events = (
        *_CLOSURE.step(context, state.closure)[1],
        *_DROWSY.step(context, state.drowsy)[1],
        *_DEGRADED.step(context, state.degraded)[1],
    )
    return frozenset(kind for e in events if isinstance(e, Resolve) for kind in e.kinds)
