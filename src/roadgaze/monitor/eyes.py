"""The eyes in the monitor: open, closed or unavailable per frame, closures, blinks, PERCLOS, gaze.

Pure and time-based like the rest of the monitor: `step_eyes` reads time only from `sample.t_s`.
Definitions (thresholds in `MonitorConfig`; defaults and sources in docs/monitor.md):

- **Closed / open** (`classify_eyes`), from the widest judged eye's openness o (lid gap / eye
  width), its eyeBlink score b and the head's MediaPipe pitch relative to its road pitch:
  closed when o < `eyes_hard_close_below`, or o < `eyes_close_below` and b >= `eyes_blink_min`;
  once closed, open again only above `eyes_open_above`. Narrowed lids with the head lowered more
  than `look_down_head_deg` read as *looking down* (open: from a camera in front, the open eyes of
  a lowered head look closed), unless the closure began with the head up. Both thresholds scale
  with the driver's learned open-eye openness (factor 0.7-1.3 of the population's 0.30).
- **Unavailable**: no face, no eye that can be judged (a turned head, small eyes, low landmark
  quality), or the eyes hidden (sunglasses). Up to `closure_gap_s` of it inside a closure does
  not end the closure.
- **Closure** episodes start at the first closed sample. One that ends open before
  `microsleep_s` is a **blink**; blinks of `long_blink_s` or more are long blinks. Blinks are
  kept for `perclos_window_s`.
- **PERCLOS**: the closed share of the judged time in the last `perclos_window_s`, kept in 1 s
  bins (memory bounded whatever the frame rate), reported once `perclos_min_judged_s` is judged.
- **Gaze** = head pose + the eye direction's deviation from the driver's resting eye direction,
  soft-thresholded per axis beyond the driver's measured noise (`roadgaze.monitor.eye_calibration`);
  the head pose alone until the eyes are calibrated, or when they give no direction or are closed.
  The calibration, the road pitch and the open-eye baseline learn from open-eyed samples on the
  road with a steady head (|yaw rate| <= `neutral_max_rate_dps`).

Events (raised only while moving): `microsleep` (warning) at a closure of `microsleep_s`,
`sleep` (critical) at `sleep_s`, `unresponsive` (critical) at `unresponsive_closed_s`; `drowsy`
(warning) at PERCLOS >= `perclos_drowsy` or `long_blinks_drowsy` long blinks in the window,
re-armed below `perclos_rearm` and fewer long blinks; `degraded` (warning) after the eyes were
unavailable for `degraded_after_s`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from roadgaze.config import MonitorConfig
from roadgaze.monitor.eye_calibration import EyeCalibration, eye_shift_deg, learn_calibration
from roadgaze.monitor.eye_rules import POPULATION_OPEN, classify_eyes, gaze_deg, soft_threshold
from roadgaze.types import AlertKind, AlertLevel, EyeStatus, EyesVerdict, PoseSample

__all__ = [
    "CLOSURE_KINDS",
    "POPULATION_OPEN",
    "EyeEvent",
    "EyeMonitorState",
    "classify_eyes",
    "clearable_eye_kinds",
    "eyes_verdict",
    "gaze_deg",
    "soft_threshold",
    "step_eyes",
]

EyeEvent = tuple[AlertKind, AlertLevel, str]
"""An alert the eyes call for: kind, level and reason (the monitor stamps the rest)."""
CLOSURE_KINDS = (AlertKind.MICROSLEEP, AlertKind.SLEEP)
"""Alerts of a closure; `unresponsive` may come from a closure too (then it is in
`EyeMonitorState.closure_raised`)."""
_EPS_S = 1e-6
_MAX_GAP_S = 0.5
"""A longer gap between samples is not judged time (PERCLOS) and ends a closure."""
_BIN_S = 1.0
_MAX_BLINKS = 256
_LEARN_TIME_CONSTANT_S = 60.0
_BASELINE_TIME_CONSTANT_S = 120.0


@dataclass(frozen=True, slots=True)
class EyeMonitorState:
    """What the eye monitor remembers between samples; replace, never mutate. Bounded: blinks
    and PERCLOS bins older than the window are dropped."""

    t_s: float | None = None
    status: EyeStatus = EyeStatus.UNAVAILABLE
    reason: str = "no eyes yet"
    judged_at_s: float | None = None
    """Last sample with the eyes judged open or closed."""
    closure_since_s: float | None = None
    closure_raised: tuple[AlertKind, ...] = ()
    """Alerts already raised for the current closure."""
    blinks: tuple[tuple[float, float], ...] = ()
    """(end time, duration) of the blinks within the window."""
    bins: tuple[tuple[int, float, float], ...] = ()
    """PERCLOS bins within the window: (index of the second, closed s, judged s)."""
    drowsy_armed: bool = True
    road_pitch_deg: float | None = None
    """The head's MediaPipe pitch looking at the road (learned)."""
    calibration: EyeCalibration = field(default_factory=EyeCalibration)
    """The driver's resting eye-in-head direction and its noise (learned)."""
    learned_s: float = 0.0
    """Road time the road pitch has learned from (a running mean until the time constant)."""
    open_baseline: float | None = None
    unavailable_since_s: float | None = None
    degraded: bool = False
    verdict: EyesVerdict = field(default_factory=EyesVerdict)

    @property
    def eye_neutral_deg(self) -> tuple[float, float]:
        """The driver's resting eye-in-head yaw and pitch (degrees; unclamped)."""
        return self.calibration.yaw_deg, self.calibration.pitch_deg

    def closure_s(self) -> float:
        if self.closure_since_s is None or self.t_s is None:
            return 0.0
        return self.t_s - self.closure_since_s

    def unavailable_s(self) -> float:
        if self.unavailable_since_s is None or self.t_s is None:
            return 0.0
        return self.t_s - self.unavailable_since_s


def _perclos(config: MonitorConfig, bins: tuple[tuple[int, float, float], ...]) -> float | None:
    closed = sum(b[1] for b in bins)
    judged = sum(b[2] for b in bins)
    if judged <= 0 or judged < config.perclos_min_judged_s - _EPS_S:
        return None
    return closed / judged


def _add_judged_time(
    bins: tuple[tuple[int, float, float], ...], start_s: float, end_s: float, closed: bool
) -> tuple[tuple[int, float, float], ...]:
    """[start, end) of judged time, closed or open, added to the 1 s bins."""
    table = {index: (c, j) for index, c, j in bins}
    t = start_s
    while t < end_s - _EPS_S:
        index = math.floor(t / _BIN_S)
        upto = min(end_s, (index + 1) * _BIN_S)
        c, j = table.get(index, (0.0, 0.0))
        table[index] = (c + (upto - t if closed else 0.0), j + (upto - t))
        t = upto
    return tuple((i, c, j) for i, (c, j) in sorted(table.items()))


def _learn(value: float, target: float, dt_s: float, learned_s: float, limit: float) -> float:
    """One step of the neutral's filter: a running mean at first, then a 60 s first-order lag."""
    step_s = min(dt_s, 1.0)
    weight = max(
        step_s / max(learned_s + step_s, 1e-9), 1.0 - math.exp(-step_s / _LEARN_TIME_CONSTANT_S)
    )
    return max(-limit, min(limit, value + min(1.0, weight) * (target - value)))


def step_eyes(
    config: MonitorConfig,
    state: EyeMonitorState,
    sample: PoseSample,
    moving: bool,
    on_road: bool,
    head_yaw_deg: float | None,
    head_pitch_deg: float | None,
) -> tuple[EyeMonitorState, tuple[EyeEvent, ...]]:
    """Advance by one sample; returns the new state and the events it calls for.

    `on_road`: the monitor's road decision at the previous sample (the neutral values learn only
    on road). `head_yaw_deg`, `head_pitch_deg`: the head pose the gaze is built on (None without
    one). A sample not after the previous one is ignored.
    """
    t = sample.t_s
    if not math.isfinite(t) or (state.t_s is not None and t <= state.t_s):
        return state, ()
    dt = 0.0 if state.t_s is None else t - state.t_s
    eyes = sample.eyes if sample.face else None
    features = sample.features if sample.face else None
    mp_pitch = None if features is None else features.mediapipe_pitch_deg
    below = (
        None
        if mp_pitch is None or state.road_pitch_deg is None
        else state.road_pitch_deg - mp_pitch
    )
    was_closed = state.status is EyeStatus.CLOSED if state.judged_at_s is not None else None
    status, reason = classify_eyes(config, eyes, below, was_closed, state.open_baseline)
    if not sample.face:
        reason = "no face"
    judged_at = state.judged_at_s
    if status is EyeStatus.UNAVAILABLE:
        bridging = (
            state.status is EyeStatus.CLOSED
            and judged_at is not None
            and t - judged_at <= config.closure_gap_s + _EPS_S
            and dt <= _MAX_GAP_S
        )
        if bridging:
            status, reason = EyeStatus.CLOSED, "eyes closed"
    else:
        judged_at = t

    # PERCLOS: the interval since the last sample, at the last sample's judgement.
    bins = state.bins
    if state.t_s is not None and state.status is not EyeStatus.UNAVAILABLE and dt <= _MAX_GAP_S:
        bins = _add_judged_time(bins, state.t_s, t, state.status is EyeStatus.CLOSED)
    oldest = math.floor((t - config.perclos_window_s) / _BIN_S)
    bins = tuple(b for b in bins if b[0] > oldest)

    # Closure episodes and blinks.
    closure_since, raised = state.closure_since_s, state.closure_raised
    blinks = tuple(b for b in state.blinks if b[0] > t - config.perclos_window_s)
    if status is EyeStatus.CLOSED:
        closure_since = t if closure_since is None or dt > _MAX_GAP_S else closure_since
    elif closure_since is not None:
        duration = t - closure_since
        if status is EyeStatus.OPEN and duration < config.microsleep_s - _EPS_S:
            blinks = (*blinks, (t, duration))[-_MAX_BLINKS:]
        closure_since, raised = None, ()
    closure_s = 0.0 if closure_since is None else t - closure_since

    # Neutral values, learned from open-eyed samples on the road with a steady head.
    road_pitch, calibration, learned_s = state.road_pitch_deg, state.calibration, state.learned_s
    baseline = state.open_baseline
    rate, max_rate = sample.yaw_rate_dps, config.neutral_max_rate_dps
    steady = rate is None or max_rate is None or not math.isfinite(rate) or abs(rate) <= max_rate
    open_on_road = status is EyeStatus.OPEN and not reason and on_road and eyes is not None
    if open_on_road and steady and dt > 0 and eyes is not None:
        if mp_pitch is not None:
            road_pitch = (
                mp_pitch
                if road_pitch is None
                else _learn(road_pitch, mp_pitch, dt, learned_s, 90.0)
            )
        if eyes.yaw_deg is not None and eyes.pitch_deg is not None:
            calibration = learn_calibration(config, calibration, eyes.yaw_deg, eyes.pitch_deg, dt)
        if eyes.openness is not None:
            gain = 1.0 - math.exp(-min(dt, 1.0) / _BASELINE_TIME_CONSTANT_S)
            baseline = (
                eyes.openness if baseline is None else baseline + gain * (eyes.openness - baseline)
            )
        learned_s += min(dt, 1.0)

    # Unavailable eyes while moving -> degraded.
    unavailable_since, degraded = state.unavailable_since_s, state.degraded
    if status is EyeStatus.UNAVAILABLE and moving:
        unavailable_since = t if unavailable_since is None else unavailable_since
    else:
        unavailable_since = None
        if status is not EyeStatus.UNAVAILABLE:
            degraded = False

    events: list[EyeEvent] = []
    if moving and closure_since is not None:
        for kind, level, threshold_s in (
            (AlertKind.MICROSLEEP, AlertLevel.WARNING, config.microsleep_s),
            (AlertKind.SLEEP, AlertLevel.CRITICAL, config.sleep_s),
            (AlertKind.UNRESPONSIVE, AlertLevel.CRITICAL, config.unresponsive_closed_s),
        ):
            if closure_s >= threshold_s - _EPS_S and kind not in raised:
                events.append((kind, level, f"eyes closed {closure_s:.1f} s"))
                raised = (*raised, kind)
    perclos = _perclos(config, bins)
    long_blinks = sum(1 for _, d in blinks if d >= config.long_blink_s - _EPS_S)
    drowsy_armed = state.drowsy_armed
    by_perclos = perclos is not None and perclos >= config.perclos_drowsy - _EPS_S
    by_blinks = long_blinks >= config.long_blinks_drowsy
    if moving and drowsy_armed and (by_perclos or by_blinks):
        why = f"PERCLOS {perclos:.2f}" if by_perclos and perclos is not None else "long blinks"
        events.append((AlertKind.DROWSY, AlertLevel.WARNING, why))
        drowsy_armed = False
    elif not drowsy_armed and not by_blinks and (perclos is None or perclos < config.perclos_rearm):
        drowsy_armed = True
    unavailable_s = 0.0 if unavailable_since is None else t - unavailable_since
    if (
        unavailable_since is not None
        and not degraded
        and unavailable_s >= config.degraded_after_s - _EPS_S
    ):
        events.append((AlertKind.DEGRADED, AlertLevel.WARNING, f"eyes unavailable: {reason}"))
        degraded = True

    # Gaze: the calibrated eyes when open and giving a direction, else the head pose.
    gaze_yaw = gaze_pitch = None
    source = "none"
    if head_yaw_deg is not None:
        gaze_yaw, gaze_pitch = head_yaw_deg, head_pitch_deg if head_pitch_deg is not None else 0.0
        source = "head"
        shift = (
            eye_shift_deg(config, calibration, eyes.yaw_deg, eyes.pitch_deg)
            if status is EyeStatus.OPEN and eyes is not None
            else None
        )
        if shift is not None:
            gaze_yaw, gaze_pitch, source = gaze_yaw + shift[0], gaze_pitch + shift[1], "eyes"
    judged = status is not EyeStatus.UNAVAILABLE
    verdict = EyesVerdict(
        status=status,
        reason=reason,
        openness=None if eyes is None or not judged else eyes.openness,
        eye_yaw_deg=None if eyes is None else eyes.yaw_deg,
        eye_pitch_deg=None if eyes is None else eyes.pitch_deg,
        gaze_yaw_deg=gaze_yaw,
        gaze_pitch_deg=gaze_pitch,
        gaze_source=source,
        closure_s=closure_s,
        perclos=perclos,
        blinks=len(blinks),
        long_blinks=long_blinks,
        last_blink_s=blinks[-1][1] if blinks else None,
        unavailable_s=unavailable_s,
        degraded=degraded,
        calibration=calibration.status(),
    )
    new_state = replace(
        state,
        t_s=t,
        status=status,
        reason=reason,
        judged_at_s=judged_at,
        closure_since_s=closure_since,
        closure_raised=raised,
        blinks=blinks,
        bins=bins,
        drowsy_armed=drowsy_armed,
        road_pitch_deg=road_pitch,
        calibration=calibration,
        learned_s=learned_s,
        open_baseline=baseline,
        unavailable_since_s=unavailable_since,
        degraded=degraded,
        verdict=verdict,
    )
    return new_state, tuple(events)


def eyes_verdict(state: EyeMonitorState) -> EyesVerdict:
    """The eyes' part of the frame's verdict after the last sample."""
    return state.verdict


def clearable_eye_kinds(state: EyeMonitorState, on_road: bool) -> frozenset[AlertKind]:
    """The eye alerts whose cause has ended at the last sample: a closure once the eyes are
    open on the road again, `drowsy` once re-armed, `degraded` once the eyes are back."""
    kinds: set[AlertKind] = set()
    if state.status is EyeStatus.OPEN and on_road:
        kinds.update(CLOSURE_KINDS)
        kinds.add(AlertKind.UNRESPONSIVE)
    if state.drowsy_armed:
        kinds.add(AlertKind.DROWSY)
    if not state.degraded:
        kinds.add(AlertKind.DEGRADED)
    return frozenset(kinds)
