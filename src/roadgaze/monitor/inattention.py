"""Inattention monitor: a pure state machine over per-frame pose samples.

`step(config, state, sample, speed_kmh) -> (state, alerts)` is a pure function: it reads time
only from `sample.t_s` (the source timeline), never from the wall clock, so a replay produces the
same alerts at the same video times on every run. `Monitor` is the pipeline's monitor stage: it
holds the current `MonitorState` and turns each sample into the frame's `Verdict` and alerts.

Definitions (thresholds from `MonitorConfig`; defaults and sources in docs/monitor.md):

- road ahead: `|yaw - neutral| <= road_half_width_deg`; once off road, the head must come back
  within `road_half_width_deg - hysteresis_deg` to be on road again. `neutral` is fixed by
  `neutral_yaw_deg` or learned slowly (time constant `neutral_time_constant_s`, clamped to
  `+-neutral_limit_deg`) from on-road samples.
- face lost: while the head was off road (or, with `turn_away_deg` set, past that angle), the
  driver is taken as still turned away, i.e. off road; otherwise where they look is unknown and,
  after `unavailable_s`, the driver is `driver_unavailable`.
- `long_distraction`: off road continuously for `long_distraction_s` (level warning), raised to
  critical at `critical_distraction_s`.
- `vats`: off-road time within the last `vats_window_s` reaches `vats_threshold_s`; fires once
  and is re-armed after `vats_rearm_s` continuously on road.
- `cleared`: the first on-road sample with a face after any of the above.
- speed gating: time off road or unavailable counts only while the vehicle moves faster than
  `min_speed_kmh` (`speed_kmh` None means unknown and is taken as moving), so no alert fires
  below that speed.

Time accounting is sample-based: an off-road episode starts at the first off-road sample and its
duration at a later sample is the difference of their timestamps, so each alert fires on the
first sample at or after its threshold, i.e. within one frame period of its definition.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from roadgaze.config import MonitorConfig
from roadgaze.types import Alert, AlertKind, AlertLevel, Gaze, PoseSample, Verdict

_EPS_S = 1e-6
"""Durations are sums of float timestamps: compare them with this tolerance."""
_MAX_LEARNING_STEP_S = 1.0
"""A longer gap between samples teaches the neutral yaw no more than one second would."""


@dataclass(frozen=True, slots=True)
class MonitorState:
    """Everything the monitor remembers between samples; replace, never mutate."""

    neutral_yaw_deg: float
    t_s: float | None = None
    """Timestamp of the last sample taken into account."""
    gaze: Gaze = Gaze.ON_ROAD
    on_road: bool = True
    """Hysteresis state of the head-pose classification (kept through face losses)."""
    yaw_deg: float | None = None
    last_face_yaw_deg: float | None = None
    face_lost_since_s: float | None = None
    face_lost_turned_away: bool = False
    moving: bool = True
    speed_kmh: float | None = None
    off_since_s: float | None = None
    """Start of the current counted (off road and moving) episode."""
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

    def off_road_s(self) -> float:
        """Length of the current counted off-road episode at the last sample."""
        if self.off_since_s is None or self.t_s is None:
            return 0.0
        return self.t_s - self.off_since_s

    def window_off_road_s(self, window_s: float) -> float:
        """Counted off-road time within `window_s` before the last sample."""
        if self.t_s is None:
            return 0.0
        return _window_total(self.off_intervals, self.off_since_s, self.t_s, window_s)

    def unavailable_s(self) -> float:
        if self.unavailable_since_s is None or self.t_s is None:
            return 0.0
        return self.t_s - self.unavailable_since_s


def initial_state(config: MonitorConfig) -> MonitorState:
    """The state before the first sample: on road, neutral at the configured value or 0."""
    neutral = 0.0 if config.neutral_yaw_deg is None else config.neutral_yaw_deg
    return MonitorState(neutral_yaw_deg=neutral)


def _window_total(
    intervals: tuple[tuple[float, float], ...],
    open_since_s: float | None,
    t_s: float,
    window_s: float,
) -> float:
    start_s = t_s - window_s
    total = sum(max(0.0, min(end, t_s) - max(begin, start_s)) for begin, end in intervals)
    if open_since_s is not None:
        total += max(0.0, t_s - max(open_since_s, start_s))
    return total


def _sample_yaw(sample: PoseSample) -> float | None:
    yaw = sample.yaw_deg if sample.yaw_deg is not None else sample.yaw_raw_deg
    if yaw is None or not math.isfinite(yaw):
        return None
    return yaw


def _classify(
    config: MonitorConfig, state: MonitorState, sample: PoseSample, t_s: float
) -> tuple[Gaze, bool, float | None, float | None, bool]:
    """Gaze, hysteresis flag, yaw, face-lost start and turned-away flag for this sample."""
    yaw = _sample_yaw(sample) if sample.face else None
    if sample.face:
        if yaw is None:  # a face whose yaw the model cannot explain: keep the last decision
            return (
                Gaze.ON_ROAD if state.on_road else Gaze.OFF_ROAD,
                state.on_road,
                None,
                None,
                False,
            )
        offset = abs(yaw - state.neutral_yaw_deg)
        if state.on_road:
            on_road = offset <= config.road_half_width_deg
        else:
            on_road = offset <= config.road_half_width_deg - config.hysteresis_deg
        return (Gaze.ON_ROAD if on_road else Gaze.OFF_ROAD), on_road, yaw, None, False
    if state.face_lost_since_s is not None:
        lost_since, turned = state.face_lost_since_s, state.face_lost_turned_away
    else:
        lost_since = t_s
        if config.turn_away_deg is None or state.last_face_yaw_deg is None:
            turned = not state.on_road
        else:
            turned = abs(state.last_face_yaw_deg - state.neutral_yaw_deg) > config.turn_away_deg
    gaze = Gaze.OFF_ROAD if turned else Gaze.UNKNOWN
    return gaze, (False if turned else state.on_road), None, lost_since, turned


def _learn_neutral(
    config: MonitorConfig, state: MonitorState, yaw: float | None, gaze: Gaze, t_s: float
) -> float:
    if config.neutral_yaw_deg is not None or yaw is None or gaze is not Gaze.ON_ROAD:
        return state.neutral_yaw_deg
    if state.t_s is None:
        return state.neutral_yaw_deg
    dt_s = min(t_s - state.t_s, _MAX_LEARNING_STEP_S)
    gain = 1.0 - math.exp(-dt_s / config.neutral_time_constant_s)
    neutral = state.neutral_yaw_deg + gain * (yaw - state.neutral_yaw_deg)
    return max(-config.neutral_limit_deg, min(config.neutral_limit_deg, neutral))


def _count(counts: tuple[tuple[str, int], ...], alerts: list[Alert]) -> tuple[tuple[str, int], ...]:
    if not alerts:
        return counts
    table = dict(counts)
    for alert in alerts:
        key = alert.label
        table[key] = table.get(key, 0) + 1
    return tuple(sorted(table.items()))


def step(
    config: MonitorConfig, state: MonitorState, sample: PoseSample, speed_kmh: float | None
) -> tuple[MonitorState, tuple[Alert, ...]]:
    """Advance the monitor by one sample; returns the new state and the alerts it raised.

    `speed_kmh` None means no speed is known and the vehicle is taken as moving. A sample whose
    `t_s` is not after the previous one is ignored (the state is returned unchanged).
    """
    t_s = sample.t_s
    if not math.isfinite(t_s) or (state.t_s is not None and t_s <= state.t_s):
        return state, ()
    gaze, on_road, yaw, lost_since, turned = _classify(config, state, sample, t_s)
    moving = speed_kmh is None or speed_kmh > config.min_speed_kmh
    alerts: list[Alert] = []

    # Continuous off-road episode and the VATS window (counted only while moving).
    counted_off = gaze is Gaze.OFF_ROAD and moving
    off_since = state.off_since_s
    intervals = state.off_intervals
    long_level = state.long_level
    last_off_road_s = state.last_off_road_s
    if counted_off and off_since is None:
        off_since = t_s
    elif not counted_off and off_since is not None:
        intervals = (*intervals, (off_since, t_s))
        last_off_road_s = t_s - off_since
        off_since, long_level = None, None
    intervals = tuple(iv for iv in intervals if iv[1] > t_s - config.vats_window_s)
    off_road_s = 0.0 if off_since is None else t_s - off_since
    window_s = _window_total(intervals, off_since, t_s, config.vats_window_s)

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

    def alert(kind: AlertKind, level: AlertLevel, clears: tuple[AlertKind, ...] = ()) -> Alert:
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
        )

    active = list(state.active)
    if counted_off:
        if (
            off_road_s >= config.critical_distraction_s - _EPS_S
            and long_level is not AlertLevel.CRITICAL
        ):
            alerts.append(alert(AlertKind.LONG_DISTRACTION, AlertLevel.CRITICAL))
            long_level = AlertLevel.CRITICAL
        elif off_road_s >= config.long_distraction_s - _EPS_S and long_level is None:
            alerts.append(alert(AlertKind.LONG_DISTRACTION, AlertLevel.WARNING))
            long_level = AlertLevel.WARNING

    vats_armed = state.vats_armed
    on_since = state.on_since_s
    on_with_face = gaze is Gaze.ON_ROAD and sample.face
    if on_with_face:
        on_since = t_s if on_since is None else on_since
        if not vats_armed and t_s - on_since >= config.vats_rearm_s - _EPS_S:
            vats_armed = True
    else:
        on_since = None
    # Evaluated on every sample: an episode that ends exactly at the threshold is counted at the
    # sample that ends it, i.e. when the driver looks back; it is cleared at the next one.
    just_ended = state.off_since_s is not None and off_since is None
    vats_due = counted_off or (just_ended and moving)
    if vats_due and vats_armed and window_s >= config.vats_threshold_s - _EPS_S:
        alerts.append(alert(AlertKind.VATS, AlertLevel.WARNING))
        vats_armed = False

    if unknown and not unavailable_alerted and unavailable_s >= config.unavailable_s - _EPS_S:
        alerts.append(alert(AlertKind.DRIVER_UNAVAILABLE, AlertLevel.WARNING))
        unavailable_alerted = True

    if on_with_face and active:
        alerts.append(alert(AlertKind.CLEARED, AlertLevel.INFO, clears=tuple(active)))
        active = []
    for raised in alerts:
        if raised.kind is not AlertKind.CLEARED and raised.kind not in active:
            active.append(raised.kind)

    new_state = replace(
        state,
        neutral_yaw_deg=_learn_neutral(config, state, yaw, gaze, t_s),
        t_s=t_s,
        gaze=gaze,
        on_road=on_road,
        yaw_deg=yaw,
        last_face_yaw_deg=yaw if yaw is not None else state.last_face_yaw_deg,
        face_lost_since_s=lost_since,
        face_lost_turned_away=turned,
        moving=moving,
        speed_kmh=speed_kmh,
        off_since_s=off_since,
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
    )
    return new_state, tuple(alerts)


def verdict_of(config: MonitorConfig, state: MonitorState) -> Verdict:
    """The monitor's view after the last sample, as the frame record carries it."""
    return Verdict(
        gaze=state.gaze,
        on_road=None if state.gaze is Gaze.UNKNOWN else state.on_road,
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
    )


class Monitor:
    """The monitor stage: holds the configuration and the current state; `update` calls `step`."""

    def __init__(self, config: MonitorConfig, state: MonitorState | None = None) -> None:
        self.config = config
        self.state = initial_state(config) if state is None else state

    def update(self, sample: PoseSample, speed_kmh: float | None = None) -> tuple[Alert, ...]:
        """Advance by one sample; returns the alerts it raised (the verdict is `verdict`)."""
        self.state, alerts = step(self.config, self.state, sample, speed_kmh)
        return alerts

    @property
    def verdict(self) -> Verdict:
        return verdict_of(self.config, self.state)
