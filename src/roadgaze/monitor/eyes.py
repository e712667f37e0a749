"""The eyes in the monitor: open, closed or unavailable per frame, closures, blinks, PERCLOS, gaze.

Pure and time-based like the rest of the monitor: `step_eyes` reads time only from `sample.t_s`.
Definitions (thresholds in `MonitorConfig`; defaults and sources in docs/monitor.md):

- **Closed / open** (`classify_eyes`), from the widest judged eye's openness o (lid gap / eye
  width), its eyeBlink score b and the head's MediaPipe pitch relative to its road pitch:
  closed when o < `eyes_hard_close_below`, or o < `eyes_close_below` and b >= `eyes_blink_min`;
  once closed, open again only above `eyes_open_above`. Narrowed lids with the head lowered more
  than `look_down_head_deg` read as *looking down* (open: from a camera in front, the open eyes of
  a lowered head look closed), unless the closure began with the head up; so do narrowed lids
  with the iris read turned sideways off both its calibrated rest and the eye's centre, as
  *looking aside* (`iris_aside`: a shut lid's iris reads near one of them), unless the closure
  began with it centred. Both thresholds scale with the driver's learned open-eye openness
  (factor 0.7-1.3 of the population's 0.30).
- **Unavailable**: no face, no eye that can be judged (a turned head, small eyes, low landmark
  quality), or the eyes hidden (sunglasses). Up to `closure_gap_s` of it inside a closure does
  not end the closure.
- **Closure** episodes start at the first closed sample. One that ends open before
  `microsleep_s` is a **blink**; blinks of `long_blink_s` or more are long blinks. Blinks are
  kept for `perclos_window_s`.
- **PERCLOS**: the closed share of the judged time in the last `perclos_window_s`, kept in 1 s
  bins (memory bounded whatever the frame rate), reported once `perclos_min_judged_s` is judged.
- **Gaze** = head pose + the eye direction's deviation from the driver's resting eye direction,
  thresholded beyond the driver's measured noise (`roadgaze.monitor.eye_calibration`);
  the head pose alone until the eyes are calibrated, or when they give no direction or are closed.
  The calibration, the road pitch and the open-eye baseline learn from open-eyed samples on the
  road with a steady head (|yaw rate| <= `neutral_max_rate_dps`).

- **Degraded**: the eyes unavailable while moving for `degraded_after_s` (monitoring on the head
  pose alone), until they are judged again.

`measure_eyes` measures all this once per sample, before the behaviours run; the alerts are the
behaviours' (roadgaze.monitor.behaviours: `eye_closure`, `drowsy`, `degraded`). `step_eyes` runs
the eyes alone: the measurement and those three behaviours (roadgaze.monitor.eyes_alone).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

from roadgaze.config import MonitorConfig
from roadgaze.monitor.eye_calibration import (
    EyeCalibration,
    eye_shift_deg,
    iris_aside,
    learn_calibration,
)
from roadgaze.monitor.eye_rules import POPULATION_OPEN, classify_eyes, gaze_deg, soft_threshold
from roadgaze.types import AlertKind, EyesFeatures, EyeStatus, EyesVerdict, PoseSample

__all__ = [
    "CLOSURE_KINDS",
    "POPULATION_OPEN",
    "EyeMonitorState",
    "classify_eyes",
    "eyes_verdict",
    "gaze_deg",
    "measure_eyes",
    "soft_threshold",
]

CLOSURE_KINDS = (AlertKind.MICROSLEEP, AlertKind.SLEEP)
"""Alerts of a closure only (a closure may raise `unresponsive` too: roadgaze.monitor.behaviours
.eye_closure)."""
_EPS_S = 1e-6
_MAX_GAP_S = 0.5
"""A longer gap between samples is not judged time (PERCLOS) and ends a closure."""
_BIN_S = 1.0
_MAX_BLINKS = 256
_LEARN_TIME_CONSTANT_S = 60.0
_BASELINE_TIME_CONSTANT_S = 120.0


@dataclass(frozen=True, slots=True)
class EyeMonitorState:
    """What the eye measurement remembers between samples; replace, never mutate. Bounded:
    blinks and PERCLOS bins older than the window are dropped."""

    t_s: float | None = None
    status: EyeStatus = EyeStatus.UNAVAILABLE
    reason: str = "no eyes yet"
    judged_at_s: float | None = None
    """Last sample with the eyes judged open or closed."""
    closure_since_s: float | None = None
    blinks: tuple[tuple[float, float], ...] = ()
    """(end time, duration) of the blinks within the window."""
    bins: tuple[tuple[int, float, float], ...] = ()
    """PERCLOS bins within the window: (index of the second, closed s, judged s)."""
    road_pitch_deg: float | None = None
    """The head's MediaPipe pitch looking at the road (learned)."""
    calibration: EyeCalibration = field(default_factory=EyeCalibration)
    """The driver's resting eye-in-head direction and its noise (learned)."""
    learned_s: float = 0.0
    """Road time the road pitch has learned from (a running mean until the time constant)."""
    open_baseline: float | None = None
    unavailable_since_s: float | None = None
    degraded: bool = False
    """Monitoring degraded: the eyes unavailable `degraded_after_s` while moving, until judged."""
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


def measure_eyes(
    config: MonitorConfig,
    state: EyeMonitorState,
    sample: PoseSample,
    moving: bool,
    on_road: bool,
    head_yaw_deg: float | None,
    head_pitch_deg: float | None,
    neutral_deg: tuple[float, float] = (0.0, 0.0),
) -> EyeMonitorState:
    """Measure the eyes at one more sample; returns the new state.

    `on_road`: the monitor's road decision at the previous sample (the neutral values learn only
    on road). `head_yaw_deg`, `head_pitch_deg`: the head pose the gaze is built on (None without
    one); `neutral_deg`: the monitor's road-ahead yaw and pitch, which the eye shift measures the
    head's turn from (`eye_shift_deg`). A sample not after the previous one is ignored.
    """
    t = sample.t_s
    if not math.isfinite(t) or (state.t_s is not None and t <= state.t_s):
        return state
    dt = 0.0 if state.t_s is None else t - state.t_s
    eyes = sample.eyes if sample.face else None
    features = sample.features if sample.face else None
    mp_pitch = None if features is None else features.mediapipe_pitch_deg
    status, reason, judged_at = _judge(config, state, sample, eyes, mp_pitch, dt)
    # PERCLOS: the interval since the last sample, at the last sample's judgement.
    bins = state.bins
    if state.t_s is not None and state.status is not EyeStatus.UNAVAILABLE and dt <= _MAX_GAP_S:
        bins = _add_judged_time(bins, state.t_s, t, state.status is EyeStatus.CLOSED)
    oldest = math.floor((t - config.perclos_window_s) / _BIN_S)
    bins = tuple(b for b in bins if b[0] > oldest)
    closure_since, blinks = _closures(config, state, status, t, dt)
    steady = _steady(config, sample.yaw_rate_dps)
    open_on_road = status is EyeStatus.OPEN and not reason and on_road and eyes is not None
    learned = state
    if open_on_road and steady and dt > 0 and eyes is not None:
        learned = _learn_rest(config, state, eyes, mp_pitch, dt)
    unavailable_since, degraded = _unavailable(config, state, status, moving, t)
    measured = EyeMonitorState(
        t_s=t,
        status=status,
        reason=reason,
        judged_at_s=judged_at,
        closure_since_s=closure_since,
        blinks=blinks,
        bins=bins,
        road_pitch_deg=learned.road_pitch_deg,
        calibration=learned.calibration,
        learned_s=learned.learned_s,
        open_baseline=learned.open_baseline,
        unavailable_since_s=unavailable_since,
        degraded=degraded,
    )
    verdict = _verdict(config, measured, eyes, head_yaw_deg, head_pitch_deg, neutral_deg)
    return replace(measured, verdict=verdict)


def _judge(
    config: MonitorConfig,
    state: EyeMonitorState,
    sample: PoseSample,
    eyes: EyesFeatures | None,
    mp_pitch: float | None,
    dt: float,
) -> tuple[EyeStatus, str, float | None]:
    """Open, closed or unavailable at this sample, why, and the last time the eyes were judged
    (up to `closure_gap_s` of unavailable eyes inside a closure keeps it closed)."""
    t = sample.t_s
    below = (
        None
        if mp_pitch is None or state.road_pitch_deg is None
        else state.road_pitch_deg - mp_pitch
    )
    was_closed = state.status is EyeStatus.CLOSED if state.judged_at_s is not None else None
    aside = eyes is not None and iris_aside(config, state.calibration, eyes.yaw_deg)
    status, reason = classify_eyes(config, eyes, below, was_closed, state.open_baseline, aside)
    if not sample.face:
        reason = "no face"
    judged_at = state.judged_at_s
    if status is not EyeStatus.UNAVAILABLE:
        return status, reason, t
    bridging = (
        state.status is EyeStatus.CLOSED
        and judged_at is not None
        and t - judged_at <= config.closure_gap_s + _EPS_S
        and dt <= _MAX_GAP_S
    )
    if bridging:
        return EyeStatus.CLOSED, "eyes closed", judged_at
    return status, reason, judged_at


def _closures(
    config: MonitorConfig, state: EyeMonitorState, status: EyeStatus, t: float, dt: float
) -> tuple[float | None, tuple[tuple[float, float], ...]]:
    """The current closure's start (None: the eyes are not closed) and the blinks in the window:
    a closure that ends open before `microsleep_s` is a blink."""
    closure_since = state.closure_since_s
    blinks = tuple(b for b in state.blinks if b[0] > t - config.perclos_window_s)
    if status is EyeStatus.CLOSED:
        closure_since = t if closure_since is None or dt > _MAX_GAP_S else closure_since
    elif closure_since is not None:
        duration = t - closure_since
        if status is EyeStatus.OPEN and duration < config.microsleep_s - _EPS_S:
            blinks = (*blinks, (t, duration))[-_MAX_BLINKS:]
        closure_since = None
    return closure_since, blinks


def _steady(config: MonitorConfig, rate_dps: float | None) -> bool:
    limit = config.neutral_max_rate_dps
    return (
        rate_dps is None or limit is None or not math.isfinite(rate_dps) or abs(rate_dps) <= limit
    )


def _learn_rest(
    config: MonitorConfig,
    state: EyeMonitorState,
    eyes: EyesFeatures,
    mp_pitch: float | None,
    dt: float,
) -> EyeMonitorState:
    """The neutral values learned from an open-eyed sample on the road with a steady head: the
    road pitch, the eye calibration, the open-eye baseline."""
    road_pitch, calibration, learned_s = state.road_pitch_deg, state.calibration, state.learned_s
    baseline = state.open_baseline
    if mp_pitch is not None:
        road_pitch = (
            mp_pitch if road_pitch is None else _learn(road_pitch, mp_pitch, dt, learned_s, 90.0)
        )
    if eyes.yaw_deg is not None and eyes.pitch_deg is not None:
        calibration = learn_calibration(config, calibration, eyes.yaw_deg, eyes.pitch_deg, dt)
    if eyes.openness is not None:
        gain = 1.0 - math.exp(-min(dt, 1.0) / _BASELINE_TIME_CONSTANT_S)
        baseline = (
            eyes.openness if baseline is None else baseline + gain * (eyes.openness - baseline)
        )
    return replace(
        state,
        road_pitch_deg=road_pitch,
        calibration=calibration,
        learned_s=learned_s + min(dt, 1.0),
        open_baseline=baseline,
    )


def _unavailable(
    config: MonitorConfig, state: EyeMonitorState, status: EyeStatus, moving: bool, t: float
) -> tuple[float | None, bool]:
    """Since when the eyes have been unavailable while moving, and whether monitoring is
    degraded (`degraded_after_s` of it, until the eyes are judged again)."""
    unavailable_since, degraded = state.unavailable_since_s, state.degraded
    if status is EyeStatus.UNAVAILABLE and moving:
        unavailable_since = t if unavailable_since is None else unavailable_since
    else:
        unavailable_since = None
        if status is not EyeStatus.UNAVAILABLE:
            degraded = False
    unavailable_s = 0.0 if unavailable_since is None else t - unavailable_since
    if unavailable_since is not None and unavailable_s >= config.degraded_after_s - _EPS_S:
        degraded = True
    return unavailable_since, degraded


def _verdict(
    config: MonitorConfig,
    state: EyeMonitorState,
    eyes: EyesFeatures | None,
    head_yaw_deg: float | None,
    head_pitch_deg: float | None,
    neutral_deg: tuple[float, float],
) -> EyesVerdict:
    """The eyes' part of the frame's verdict. Gaze: the calibrated eyes when open and giving a
    direction, else the head pose."""
    status, calibration, blinks = state.status, state.calibration, state.blinks
    gaze_yaw = gaze_pitch = None
    source = "none"
    if head_yaw_deg is not None:
        gaze_yaw, gaze_pitch = head_yaw_deg, head_pitch_deg if head_pitch_deg is not None else 0.0
        source = "head"
        shift = (
            eye_shift_deg(
                config,
                calibration,
                eyes.yaw_deg,
                eyes.pitch_deg,
                (gaze_yaw - neutral_deg[0], gaze_pitch - neutral_deg[1]),
            )
            if status is EyeStatus.OPEN and eyes is not None
            else None
        )
        if shift is not None:
            gaze_yaw, gaze_pitch, source = gaze_yaw + shift[0], gaze_pitch + shift[1], "eyes"
    judged = status is not EyeStatus.UNAVAILABLE
    return EyesVerdict(
        status=status,
        reason=state.reason,
        openness=None if eyes is None or not judged else eyes.openness,
        eye_yaw_deg=None if eyes is None else eyes.yaw_deg,
        eye_pitch_deg=None if eyes is None else eyes.pitch_deg,
        gaze_yaw_deg=gaze_yaw,
        gaze_pitch_deg=gaze_pitch,
        gaze_source=source,
        closure_s=state.closure_s(),
        perclos=_perclos(config, state.bins),
        blinks=len(blinks),
        long_blinks=sum(1 for _, d in blinks if d >= config.long_blink_s - _EPS_S),
        last_blink_s=blinks[-1][1] if blinks else None,
        unavailable_s=state.unavailable_s(),
        degraded=state.degraded,
        calibration=calibration.status(),
    )


def eyes_verdict(state: EyeMonitorState) -> EyesVerdict:
    """The eyes' part of the frame's verdict after the last sample."""
    return state.verdict


def __getattr__(name: str) -> Any:
    """`step_eyes`, `EyesAlone` and `clearable_eye_kinds` live in roadgaze.monitor.eyes_alone
    (they run the eye behaviours, which read this module): importable from here as before."""
    if name in ("step_eyes", "EyesAlone", "clearable_eye_kinds"):
        from roadgaze.monitor import eyes_alone

        return getattr(eyes_alone, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
