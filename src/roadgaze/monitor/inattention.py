"""Inattention monitor: a pure state machine over per-frame pose samples.

`step(config, state, sample, speed_kmh) -> (state, alerts)` is a pure function: it reads time
only from `sample.t_s` (the source timeline), never from the wall clock, so a replay produces the
same alerts at the same video times on every run. `Monitor` is the pipeline's monitor stage: it
holds the current `MonitorState` and turns each sample into the frame's `Verdict` and alerts.

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
  (`camera_mounting`, `cabin`: roadgaze.pose.mounting) before anything else.
- `long_distraction`: the current off-road episode has spent the protocol's distraction time
  (`roadgaze.monitor.protocols`: the earliest of the configured protocols' at this speed) outside
  the driving-related zones (`driving_related_zones`, the mirrors: their time pauses the timer, up
  to `driving_glance_max_s` per continuous stay when that is set; ADDW's area 1 never is); level
  warning, raised to critical `critical_after_warning_s` later (not before
  `critical_distraction_s`).
- `temporary_failure` (roadgaze.monitor.failures): blocked, black, saturated or frozen frames,
  no judgeable face, unjudgeable eyes, each for its time while moving; cleared once recovered.
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
  distraction alert; a closure's alerts once the eyes are open on the road again; `drowsy` once
  re-armed; `degraded` once the eyes are back.
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

from roadgaze.config import MonitorConfig
from roadgaze.monitor.escalation import split_cleared, unresponsive_check
from roadgaze.monitor.eyes import step_eyes
from roadgaze.monitor.failures import frame_issue, step_failures
from roadgaze.monitor.look import classify, finite, to_driver_frame
from roadgaze.monitor.neutral import learn_neutral
from roadgaze.monitor.protocols import Rule, distraction_trigger, moving_at, rule_of, uses
from roadgaze.monitor.state import (
    EPS_S,
    MonitorState,
    distraction_s,
    initial_state,
    segment_distraction_s,
    window_total,
)
from roadgaze.monitor.zones import ROAD, ZoneMap
from roadgaze.pose.mounting import CameraMounting, gaze_to_camera
from roadgaze.types import (
    Alert,
    AlertKind,
    AlertLevel,
    EyeStatus,
    Gaze,
    PoseSample,
    Verdict,
)

__all__ = ["Monitor", "MonitorState", "initial_state", "step", "verdict_of"]


def _count(counts: tuple[tuple[str, int], ...], alerts: list[Alert]) -> tuple[tuple[str, int], ...]:
    if not alerts:
        return counts
    table = dict(counts)
    for alert in alerts:
        key = alert.label
        table[key] = table.get(key, 0) + 1
    return tuple(sorted(table.items()))


def step(
    config: MonitorConfig,
    state: MonitorState,
    sample: PoseSample,
    speed_kmh: float | None,
    zones: ZoneMap | None = None,
    mounting: CameraMounting | None = None,
) -> tuple[MonitorState, tuple[Alert, ...]]:
    """Advance the monitor by one sample; returns the new state and the alerts it raised.

    `speed_kmh` None means no speed is known and the vehicle is taken as moving. A sample whose
    `t_s` is not after the previous one is ignored (the state is returned unchanged). `zones`
    defaults to `ZoneMap.from_config(config)` and `mounting` to
    `CameraMounting.from_config(config)` (pass them to avoid
    rebuilding them every sample). The sample's angles are in the camera's frame; they are
    mapped into the driver's frame first.
    """
    t_s = sample.t_s
    if not math.isfinite(t_s) or (state.t_s is not None and t_s <= state.t_s):
        return state, ()
    zones = zones if zones is not None else ZoneMap.from_config(config)
    mounting = mounting if mounting is not None else CameraMounting.from_config(config)
    sample = to_driver_frame(mounting, sample)
    moving = moving_at(config, speed_kmh)
    head_pitch = finite(sample.pitch_deg, sample.pitch_raw_deg)
    eyes, eye_events = step_eyes(
        config,
        state.eyes,
        sample,
        moving,
        state.on_road,
        finite(sample.yaw_deg, sample.yaw_raw_deg) if sample.face else None,
        state.neutral_pitch_deg if head_pitch is None else head_pitch,
    )
    look = classify(config, zones, state, sample, t_s, eyes.verdict)
    gaze, yaw = look.gaze, look.yaw_deg
    alerts: list[Alert] = []
    # The protocols' distraction warning at this speed (ADDW's allowance when the service knows
    # conditions are non-nominal: eyes hidden, or a poor frame).
    non_nominal = eyes.verdict.reason == "eyes hidden" or bool(
        frame_issue(config, sample.frame_check)
    )
    trigger = distraction_trigger(config, speed_kmh, non_nominal) if moving else None
    ncap = uses(config, "euroncap")

    # Continuous off-road episode, its distraction time and the VATS window (while moving). A
    # face lost while the image works is not seen on the road: its time counts too (fail-safe: a
    # still cut from ahead to a profile the landmarker cannot find is a look away; a failed camera
    # is a temporary failure instead).
    unseen = gaze is Gaze.UNKNOWN and not frame_issue(config, sample.frame_check)
    counted_off = (gaze is Gaze.OFF_ROAD or unseen) and moving
    driving = zones.is_driving_related(look.zone)
    off_since = state.off_since_s
    segment_since, segment_driving = state.segment_since_s, state.segment_driving
    distraction_before = state.distraction_before_s
    intervals = state.off_intervals
    long_level = state.long_level
    last_off_road_s = state.last_off_road_s
    if counted_off and off_since is None:
        off_since = segment_since = t_s
        segment_driving, distraction_before = driving, 0.0
    elif counted_off and driving != segment_driving:
        distraction_before += segment_distraction_s(config, segment_since, t_s, segment_driving)
        segment_since, segment_driving = t_s, driving
    elif not counted_off and off_since is not None:
        intervals = (*intervals, (off_since, t_s))
        last_off_road_s = t_s - off_since
        off_since = segment_since = None
        segment_driving, distraction_before, long_level = False, 0.0, None
    intervals = tuple(iv for iv in intervals if iv[1] > t_s - config.vats_window_s)
    off_road_s = 0.0 if off_since is None else t_s - off_since
    distraction_now_s = (
        0.0
        if off_since is None
        else distraction_before + segment_distraction_s(config, segment_since, t_s, segment_driving)
    )
    window_s = window_total(intervals, off_since, t_s, config.vats_window_s)

    # Unavailable: no face, not turned away, while moving.
    unknown = gaze is Gaze.UNKNOWN and moving
    unavailable_since = state.unavailable_since_s
    unavailable_alerted = state.unavailable_alerted
    if unknown and unavailable_since is None:
        unavailable_since = t_s
    elif not unknown:
        unavailable_since = None
        if sample.face:
            unavailable_alerted = False
    unavailable_s = 0.0 if unavailable_since is None else t_s - unavailable_since

    def alert(
        kind: AlertKind,
        level: AlertLevel,
        clears: tuple[AlertKind, ...] = (),
        reason: str = "",
        rule: Rule | None = None,
    ) -> Alert:
        rule = rule if rule is not None else rule_of(kind, level, reason)
        return Alert(
            kind=kind,
            level=level,
            t_s=t_s,
            yaw_deg=yaw,
            off_road_s=off_road_s if kind is not AlertKind.CLEARED else last_off_road_s,
            window_off_road_s=window_s,
            unavailable_s=unavailable_s,
            speed_kmh=speed_kmh,
            clears=clears,
            closure_s=eyes.closure_s(),
            perclos=eyes.verdict.perclos,
            reason=reason,
            rule="" if rule is None else rule.key,
            source="" if rule is None else rule.source,
        )

    active = list(state.active)
    if counted_off and trigger is not None:
        critical_s = max(
            config.critical_distraction_s, trigger.warn_s + config.critical_after_warning_s
        )
        if distraction_now_s >= critical_s - EPS_S and long_level is not AlertLevel.CRITICAL:
            alerts.append(alert(AlertKind.LONG_DISTRACTION, AlertLevel.CRITICAL, reason=look.why))
            long_level = AlertLevel.CRITICAL
        elif distraction_now_s >= trigger.warn_s - EPS_S and long_level is None:
            alerts.append(
                alert(
                    AlertKind.LONG_DISTRACTION,
                    AlertLevel.WARNING,
                    reason=look.why,
                    rule=trigger.rule,
                )
            )
            long_level = AlertLevel.WARNING

    vats_armed = state.vats_armed
    on_since = state.on_since_s
    on_with_face = gaze is Gaze.ON_ROAD and sample.face
    looking = on_with_face and eyes.status is not EyeStatus.CLOSED
    if on_with_face:
        on_since = t_s if on_since is None else on_since
        if not vats_armed and t_s - on_since >= config.vats_rearm_s - EPS_S:
            vats_armed = True
    else:
        on_since = None
    # Evaluated on every sample: an episode that ends exactly at the threshold is counted at the
    # sample that ends it, i.e. when the driver looks back; it is cleared at the next one.
    just_ended = state.off_since_s is not None and off_since is None
    vats_due = counted_off or (just_ended and moving)
    if ncap and vats_due and vats_armed and window_s >= config.vats_threshold_s - EPS_S:
        alerts.append(alert(AlertKind.VATS, AlertLevel.WARNING))
        vats_armed = False

    if unknown and not unavailable_alerted and unavailable_s >= config.unavailable_s - EPS_S:
        alerts.append(alert(AlertKind.DRIVER_UNAVAILABLE, AlertLevel.WARNING))
        unavailable_alerted = True

    for kind, level, reason in eye_events:
        alerts.append(alert(kind, level, reason=reason))
    away_unresponsive = state.away_unresponsive and off_since is not None
    warned_since, away_unresponsive, unresponsive = unresponsive_check(
        config, state, alerts, t_s, moving and ncap, looking, distraction_now_s, away_unresponsive
    )
    if unresponsive:
        alerts.append(alert(AlertKind.UNRESPONSIVE, AlertLevel.CRITICAL, reason=unresponsive))
    failures, failure_events, failure_ended = step_failures(
        config, state.failures, sample, moving, ncap and eyes.degraded
    )
    for kind, level, reason in failure_events:
        alerts.append(alert(kind, level, reason=reason))
    # Cleared once looking at the road for `clear_on_road_s` (0: at once).
    looked_s = 0.0 if on_since is None else t_s - on_since
    cleared, active = split_cleared(
        active, eyes, looking and looked_s >= config.clear_on_road_s - EPS_S
    )
    if failure_ended and AlertKind.TEMPORARY_FAILURE in active:
        cleared = (*cleared, AlertKind.TEMPORARY_FAILURE)
        active.remove(AlertKind.TEMPORARY_FAILURE)
    if cleared:
        alerts.append(alert(AlertKind.CLEARED, AlertLevel.INFO, clears=cleared))
    for raised in alerts:
        if raised.kind is not AlertKind.CLEARED and raised.kind not in active:
            active.append(raised.kind)

    neutral_yaw, neutral_pitch, yaw_learned_s, pitch_learned_s = learn_neutral(
        config,
        state,
        look.yaw_deg,
        look.pitch_deg,
        t_s,
        sample.yaw_rate_dps,
        judged_on_road=look.zone == ROAD,
    )
    new_state = replace(
        state,
        neutral_yaw_deg=neutral_yaw,
        neutral_pitch_deg=neutral_pitch,
        neutral_yaw_learned_s=yaw_learned_s,
        neutral_pitch_learned_s=pitch_learned_s,
        t_s=t_s,
        gaze=gaze,
        zone=look.zone,
        face_zone=look.face_zone,
        yaw_deg=yaw,
        pitch_deg=look.pitch_deg,
        last_face_yaw_deg=yaw if yaw is not None else state.last_face_yaw_deg,
        face_lost_since_s=look.lost_since_s,
        face_lost_turned_away=look.turned_away,
        moving=moving,
        speed_kmh=speed_kmh,
        off_since_s=off_since,
        segment_since_s=segment_since,
        segment_driving=segment_driving,
        distraction_before_s=distraction_before,
        long_level=long_level,
        last_off_road_s=last_off_road_s,
        off_intervals=intervals,
        vats_armed=vats_armed,
        on_since_s=on_since,
        unavailable_since_s=unavailable_since,
        unavailable_alerted=unavailable_alerted,
        active=tuple(active),
        samples=state.samples + 1,
        alert_counts=_count(state.alert_counts, alerts),
        eyes=eyes,
        warned_since_s=warned_since,
        away_unresponsive=away_unresponsive,
        failures=failures,
        warn_s=None if trigger is None else trigger.warn_s,
        warn_rule="" if trigger is None else trigger.rule.key,
    )
    return new_state, tuple(alerts)


def verdict_of(config: MonitorConfig, state: MonitorState) -> Verdict:
    """The monitor's view after the last sample, as the frame record carries it."""
    return Verdict(
        eyes=state.eyes.verdict,
        gaze=state.gaze,
        on_road=None if state.gaze is Gaze.UNKNOWN else state.zone == ROAD,
        yaw_deg=state.yaw_deg,
        neutral_yaw_deg=state.neutral_yaw_deg,
        off_road_s=state.off_road_s(),
        window_off_road_s=state.window_off_road_s(config.vats_window_s),
        unavailable_s=state.unavailable_s(),
        vats_armed=state.vats_armed,
        moving=state.moving,
        speed_kmh=state.speed_kmh,
        active=state.active,
        alert_counts=state.alert_counts,
        zone=state.zone,
        pitch_deg=state.pitch_deg,
        neutral_pitch_deg=state.neutral_pitch_deg,
        distraction_s=distraction_s(config, state),
        failure=state.failures.reason,
        distraction_warn_s=state.warn_s,
        distraction_rule=state.warn_rule,
        camera_neutral_deg=_camera_neutral(config, state),
    )


def _camera_neutral(config: MonitorConfig, state: MonitorState) -> tuple[float, float] | None:
    mounting = CameraMounting.from_config(config)
    if mounting.is_identity:
        return None
    return gaze_to_camera(mounting, state.neutral_yaw_deg, state.neutral_pitch_deg)


class Monitor:
    """The monitor stage: holds the configuration and the current state; `update` calls `step`."""

    def __init__(self, config: MonitorConfig, state: MonitorState | None = None) -> None:
        self.config = config
        self.zones = ZoneMap.from_config(config)
        self.mounting = CameraMounting.from_config(config)
        self.state = initial_state(config) if state is None else state

    def update(self, sample: PoseSample, speed_kmh: float | None = None) -> tuple[Alert, ...]:
        """Advance by one sample; returns the alerts it raised (the verdict is `verdict`)."""
        self.state, alerts = step(
            self.config, self.state, sample, speed_kmh, self.zones, self.mounting
        )
        return alerts

    @property
    def camera_neutral_pitch_deg(self) -> float:
        """The learned road-ahead pitch as the camera sees it (the pose stage's down gain starts
        there); the neutral itself is in the driver's frame."""
        camera = _camera_neutral(self.config, self.state)
        return self.state.neutral_pitch_deg if camera is None else camera[1]

    @property
    def verdict(self) -> Verdict:
        return verdict_of(self.config, self.state)
