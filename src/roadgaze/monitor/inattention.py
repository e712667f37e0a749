"""Inattention monitor: a pure state machine over per-frame pose samples.

`step(config, state, sample, speed_kmh) -> (state, alerts)` is a pure function: it reads time
only from `sample.t_s` (the source timeline), never from the wall clock, so a replay produces the
same alerts at the same video times on every run. `Monitor` is the pipeline's monitor stage: it
holds the current `MonitorState` and turns each sample into the frame's `Verdict` and alerts.

`step` is a fold: it measures the sample's facts once (`roadgaze.monitor.observe`: the
`Context`), runs each behaviour the configured protocols ask for (`roadgaze.monitor.protocols`
`TABLE`, one module each in `roadgaze.monitor.behaviours`) on its own state slice, and turns their
events into the frame's alerts (`Raise`: stamped with the sample's timers), the `cleared` alert
and the verdict's `outputs` (`Publish`).

Definitions (thresholds from `MonitorConfig`; defaults and sources in docs/monitor.md):

- zone: each sample with a face gets a glance zone from its yaw and pitch relative to the neutral
  pose (`roadgaze.monitor.zones`: ordered rectangles, first match wins, else `away`, with
  hysteresis). `road` is on road; every other zone is off road. `neutral` (yaw and pitch) is
  fixed by `neutral_yaw_deg` / `neutral_pitch_deg` or learned from samples that look roughly
  ahead (yaw within `road_half_width_deg` of the neutral, pitch within
  +-`neutral_pitch_limit_deg`): a running mean at first, then a first-order filter of time
  constant `neutral_time_constant_s`, clamped to +-`neutral_limit_deg` /
  `neutral_pitch_limit_deg`.
- face lost: while the head was off road (or, with `turn_away_deg` set, past that yaw), the
  driver is taken as still turned away, i.e. off road (zone: the last zone, `away` if that was
  driving-related); otherwise where they look is unknown (zone None) and, after
  `unavailable_s`, the driver is `driver_unavailable`; while the image works (no black, blocked
  or saturated frame) that unknown time also runs the long-distraction timer: a driver not seen
  is not seen on the road.
- frames: the sample's yaw and pitch are mapped from the camera's frame into the driver's
  (`camera_mounting`, `cabin`: roadgaze.mounting) before anything else.
- `long_distraction`: the current off-road episode has spent the protocol's distraction time
  (`roadgaze.monitor.protocols`: the earliest of the configured protocols' at this speed) outside
  the driving-related zones (`driving_related_zones`, the mirrors: their time pauses the timer, up
  to `driving_glance_max_s` per continuous stay when that is set; ADDW's area 1 never is); level
  warning, raised to critical `critical_after_warning_s` later (not before
  `critical_distraction_s`).
- `temporary_failure` (roadgaze.monitor.failures, .behaviours.temporary_failure): blocked,
  black, saturated or frozen frames, no judgeable face, unjudgeable eyes, each for its time while
  moving; cleared once recovered.
- `vats` (Euro NCAP only): off-road time (every zone but road) within the last `vats_window_s`
  reaches `vats_threshold_s`; fires once and is re-armed after `vats_rearm_s` continuously on
  road.
- eyes (`roadgaze.monitor.eyes`): open, closed or unavailable per sample; with the eyes open and
  giving a direction the zone is judged on the gaze (head + eyes beyond `gaze_deadband_deg`)
  against a road `eyes_road_margin_deg` narrower, so an eyes-only glance counts; otherwise
  (eyes closed or unavailable) on the head pose. Closures raise `microsleep`, `sleep` and
  `unresponsive`; PERCLOS and long blinks `drowsy`; eyes unavailable `degraded`.
- `unresponsive` on the distraction path (Euro NCAP only): away (outside the road and
  driving-related zones) `unresponsive_away_s`, or not back on the road
  `unresponsive_after_warning_s` after a `long_distraction` or `vats` warning.
- `cleared`: on the road with a face and eyes not closed for `clear_on_road_s` after any
  distraction alert; a closure's alerts once the eyes are open and back on the road (the same
  time); `drowsy` once re-armed; `degraded` once the eyes are back.
- speed gating: time off road or unavailable counts only while a configured protocol is active
  (ADDW above `addw_min_speed_kmh`, Euro NCAP above `min_speed_kmh`; `speed_kmh` None means
  unknown and is taken as moving, in the highest band), so no alert fires below that speed.

Time accounting is sample-based: an off-road episode starts at the first off-road sample and its
duration at a later sample is the difference of their timestamps, so each alert fires on the
first sample at or after its threshold, i.e. within one frame period of its definition.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from roadgaze.config import MonitorConfig
from roadgaze.monitor.behaviours import FailureState, VatsState
from roadgaze.monitor.context import Behaviour, Context
from roadgaze.monitor.events import Event, Raise, published
from roadgaze.monitor.observe import observe
from roadgaze.monitor.protocols import behaviours as configured_behaviours
from roadgaze.monitor.state import MonitorState, distraction_s, initial_state
from roadgaze.monitor.zones import ROAD, ZoneMap
from roadgaze.mounting import CameraMounting, gaze_to_camera
from roadgaze.types import Alert, AlertKind, Gaze, PoseSample, Verdict

__all__ = ["Monitor", "MonitorState", "initial_state", "step", "verdict_of"]


def step(
    config: MonitorConfig,
    state: MonitorState,
    sample: PoseSample,
    speed_kmh: float | None,
    zones: ZoneMap | None = None,
    mounting: CameraMounting | None = None,
    behaviours: tuple[Behaviour[Any], ...] | None = None,
) -> tuple[MonitorState, tuple[Alert, ...]]:
    """Advance the monitor by one sample; returns the new state and the alerts it raised.

    `speed_kmh` None means no speed is known and the vehicle is taken as moving. A sample whose
    `t_s` is not after the previous one is ignored (the state is returned unchanged). `zones`
    defaults to `ZoneMap.from_config(config)` and `mounting` to
    `CameraMounting.from_config(config)` (pass them to avoid rebuilding them every sample). The
    sample's angles are in the camera's frame; they are mapped into the driver's frame first.
    `behaviours` defaults to those the configured protocols run; `state.slices` holds their
    slices in the same order (`initial_state(config, behaviours)`).
    """
    t_s = sample.t_s
    if not math.isfinite(t_s) or (state.t_s is not None and t_s <= state.t_s):
        return state, ()
    zones = zones if zones is not None else ZoneMap.from_config(config)
    mounting = mounting if mounting is not None else CameraMounting.from_config(config)
    context, neutral = observe(config, zones, mounting, state, sample, speed_kmh)
    slices: list[Any] = []
    events: list[Event] = []
    if behaviours is None:
        behaviours = configured_behaviours(config.protocol)
    for behaviour, before in zip(behaviours, state.slices, strict=True):
        after, handed_back = behaviour.step(context, before)
        slices.append(after)
        if handed_back:
            events.extend(handed_back)
            context = replace(context, events=tuple(events))
    alerts = tuple(alert_of(context, e) for e in events if isinstance(e, Raise))
    new_state = MonitorState(
        neutral=neutral,
        look=context.look,
        eyes=context.eyes,
        episode=context.episode,
        slices=tuple(slices),
        t_s=t_s,
        moving=context.moving,
        speed_kmh=speed_kmh,
        trigger=context.trigger,
        active=_active(state.active, alerts),
        outputs=published(tuple(events)),
        samples=state.samples + 1,
        alert_counts=_count(state.alert_counts, alerts),
    )
    return new_state, alerts


def alert_of(context: Context, event: Raise) -> Alert:
    """The alert `event` asks for, stamped with the sample's time and timers."""
    config, episode, t_s = context.config, context.episode, context.t_s
    cleared = event.kind is AlertKind.CLEARED
    return Alert(
        kind=event.kind,
        level=event.level,
        t_s=t_s,
        yaw_deg=context.look.yaw_deg,
        off_road_s=episode.last_off_road_s if cleared else episode.off_road_s(t_s),
        window_off_road_s=episode.window_s(t_s, config.vats_window_s),
        unavailable_s=episode.unavailable_s(t_s),
        speed_kmh=context.speed_kmh,
        clears=event.clears,
        closure_s=context.eyes.closure_s(),
        perclos=context.eyes.verdict.perclos,
        reason=event.reason,
        rule=event.rule.key,
        source=event.rule.source,
    )


def _active(active: tuple[AlertKind, ...], alerts: tuple[Alert, ...]) -> tuple[AlertKind, ...]:
    """The alerts active after this sample: those it cleared removed, those it raised added."""
    cleared = {kind for alert in alerts for kind in alert.clears}
    kept = [kind for kind in active if kind not in cleared]
    for alert in alerts:
        if alert.kind is not AlertKind.CLEARED and alert.kind not in kept:
            kept.append(alert.kind)
    return tuple(kept)


def _count(
    counts: tuple[tuple[str, int], ...], alerts: tuple[Alert, ...]
) -> tuple[tuple[str, int], ...]:
    if not alerts:
        return counts
    table = dict(counts)
    for alert in alerts:
        table[alert.label] = table.get(alert.label, 0) + 1
    return tuple(sorted(table.items()))


def verdict_of(config: MonitorConfig, state: MonitorState) -> Verdict:
    """The monitor's view after the last sample, as the frame record carries it."""
    look, vats, failure = state.look, state.slice(VatsState), state.slice(FailureState)
    return Verdict(
        eyes=state.eyes.verdict,
        gaze=look.gaze,
        on_road=None if look.gaze is Gaze.UNKNOWN else look.zone == ROAD,
        yaw_deg=look.yaw_deg,
        neutral_yaw_deg=state.neutral.yaw_deg,
        off_road_s=state.off_road_s(),
        window_off_road_s=state.window_off_road_s(config.vats_window_s),
        unavailable_s=state.unavailable_s(),
        vats_armed=vats is None or vats.armed,
        moving=state.moving,
        speed_kmh=state.speed_kmh,
        active=state.active,
        alert_counts=state.alert_counts,
        zone=look.zone,
        pitch_deg=look.pitch_deg,
        neutral_pitch_deg=state.neutral.pitch_deg,
        distraction_s=distraction_s(config, state),
        failure="" if failure is None else failure.reason,
        distraction_warn_s=None if state.trigger is None else state.trigger.warn_s,
        distraction_rule="" if state.trigger is None else state.trigger.rule.key,
        camera_neutral_deg=_camera_neutral(CameraMounting.from_config(config), state),
        outputs=state.outputs,
    )


def _camera_neutral(mounting: CameraMounting, state: MonitorState) -> tuple[float, float] | None:
    if mounting.is_identity:
        return None
    return gaze_to_camera(mounting, state.neutral.yaw_deg, state.neutral.pitch_deg)


class Monitor:
    """The monitor stage: holds the configuration and the current state; `update` calls `step`."""

    def __init__(
        self,
        config: MonitorConfig,
        state: MonitorState | None = None,
        behaviours: tuple[Behaviour[Any], ...] | None = None,
    ) -> None:
        """`behaviours`: the behaviours to run, in order (default: those the configured
        protocols run, `roadgaze.monitor.protocols.TABLE`)."""
        self.config = config
        self.zones = ZoneMap.from_config(config)
        self.mounting = CameraMounting.from_config(config)
        self.behaviours = (
            configured_behaviours(config.protocol) if behaviours is None else behaviours
        )
        self.state = initial_state(config, self.behaviours) if state is None else state

    def update(self, sample: PoseSample, speed_kmh: float | None = None) -> tuple[Alert, ...]:
        """Advance by one sample; returns the alerts it raised (the verdict is `verdict`)."""
        self.state, alerts = step(
            self.config, self.state, sample, speed_kmh, self.zones, self.mounting, self.behaviours
        )
        return alerts

    @property
    def camera_neutral_pitch_deg(self) -> float:
        """The learned road-ahead pitch as the camera sees it (the pose stage's down gain starts
        there); the neutral itself is in the driver's frame."""
        camera = _camera_neutral(self.mounting, self.state)
        return self.state.neutral.pitch_deg if camera is None else camera[1]

    @property
    def verdict(self) -> Verdict:
        return verdict_of(self.config, self.state)
