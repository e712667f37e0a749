"""Timelines of head and eye poses: `YAW[/PITCH][;FIELD=VALUE...]:SECONDS` keyframes.

A timeline such as `0:2,40:3.5,0:2,-35:1,0:2` lists keyframes: in each segment the head turns to
YAW (and PITCH, default 0) degrees during the first `transition_s` seconds with a cosine ease,
then holds it for the rest of the segment; the first segment starts already at its pose. Yaw > 0
turns the head to the person's own left (the nose moves to the image right), pitch > 0 looks up.

Optional eye fields, each keyframe stating the whole pose (a field not given takes its default):
`eyes=open|closed|half|0..1` (openness as a fraction of the photo's own, default open),
`eye_yaw=DEG` and `eye_pitch=DEG` (eye-in-head direction, default 0, within +-35). The eyes move
and the lids close over `eye_transition_s` (0.1 s: a lid closes in about 100 ms, a saccade takes
30-80 ms). E.g. `0:2,0;eyes=closed:1.5,0;eye_yaw=-25;eye_pitch=-30:2`. Timelines without eye
fields parse and render exactly as before.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.errors import ConfigError
from roadgaze.types import FloatArray

MAX_ABS_YAW_DEG = 80.0
MAX_ABS_PITCH_DEG = 40.0
MAX_CLIP_S = 3600.0
DEFAULT_TRANSITION_S = 0.5
MAX_ABS_EYE_DEG = 35.0
DEFAULT_EYE_TRANSITION_S = 0.1
EYES_WORDS = {"open": 1.0, "closed": 0.0, "half": 0.5}


@dataclass(frozen=True, slots=True)
class Keyframe:
    """Turn to `yaw_deg`/`pitch_deg` at the start of a segment of `duration_s` and hold it; the
    eyes turn to `eye_yaw_deg`/`eye_pitch_deg` and open to `openness` (0 closed, 1 open)."""

    yaw_deg: float
    pitch_deg: float
    duration_s: float
    eye_yaw_deg: float = 0.0
    eye_pitch_deg: float = 0.0
    openness: float = 1.0


def _eased(
    targets: list[float], durations: list[float], ramp_s: float, t: FloatArray
) -> FloatArray:
    """Piecewise holds with cosine-eased ramps of `ramp_s` (at most half a segment) between."""
    values = np.full(t.shape, targets[0])
    start_s, previous = 0.0, targets[0]
    for target, duration_s in zip(targets, durations, strict=True):
        ramp = min(ramp_s, duration_s / 2.0)
        progress = np.clip((t - start_s) / ramp, 0.0, 1.0) if ramp > 0.0 else np.ones_like(t)
        ease = 0.5 - 0.5 * np.cos(np.pi * progress)
        values = np.where(t >= start_s, previous + (target - previous) * ease, values)
        start_s += duration_s
        previous = target
    return values


def eased(
    targets: list[float], durations: list[float], ramp_s: float, t_s: npt.ArrayLike
) -> FloatArray:
    """Holds of `targets` for `durations` with the timeline's cosine-eased ramps between."""
    return _eased(targets, durations, ramp_s, np.asarray(t_s, dtype=np.float64))


@dataclass(frozen=True, slots=True)
class Timeline:
    """Keyframes with cosine-eased transitions: `transition_s` for the head, `eye_transition_s`
    for the eyes and lids."""

    keyframes: tuple[Keyframe, ...]
    transition_s: float = DEFAULT_TRANSITION_S
    eye_transition_s: float = DEFAULT_EYE_TRANSITION_S

    @property
    def duration_s(self) -> float:
        return sum(k.duration_s for k in self.keyframes)

    @property
    def has_eyes(self) -> bool:
        """Whether any keyframe moves the eyes or the lids."""
        return any(
            (k.eye_yaw_deg, k.eye_pitch_deg, k.openness) != (0.0, 0.0, 1.0) for k in self.keyframes
        )

    def _channel(self, name: str, ramp_s: float, t_s: npt.ArrayLike) -> FloatArray:
        targets = [float(getattr(k, name)) for k in self.keyframes]
        durations = [k.duration_s for k in self.keyframes]
        return _eased(targets, durations, ramp_s, np.asarray(t_s, dtype=np.float64))

    def pose_at(self, t_s: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Yaw and pitch in degrees at times `t_s` (seconds; clamped to the timeline)."""
        return (
            self._channel("yaw_deg", self.transition_s, t_s),
            self._channel("pitch_deg", self.transition_s, t_s),
        )

    def eyes_at(self, t_s: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Eye-in-head yaw and pitch (degrees) and openness (0..1) at times `t_s`."""
        return (
            self._channel("eye_yaw_deg", self.eye_transition_s, t_s),
            self._channel("eye_pitch_deg", self.eye_transition_s, t_s),
            self._channel("openness", self.eye_transition_s, t_s),
        )

    def truth(self, fps: float) -> FloatArray:
        """(N, 3) rows `t_s, yaw_deg, pitch_deg` at `i / fps`; N = round(duration * fps)."""
        n_frames = max(1, round(self.duration_s * fps))
        t = np.arange(n_frames, dtype=np.float64) / fps
        yaw, pitch = self.pose_at(t)
        return np.column_stack([t, yaw, pitch])

    def eye_truth(self, fps: float) -> FloatArray:
        """(N, 6) rows `t_s, yaw_deg, pitch_deg, eye_yaw_deg, eye_pitch_deg, openness`."""
        truth = self.truth(fps)
        return np.column_stack([truth, *self.eyes_at(truth[:, 0])])


def _number(text: str, what: str, item: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ConfigError(
            f"timeline keyframe '{item}': {what} '{text}' is not a number "
            "(expected YAW[/PITCH]:SECONDS, e.g. 40:3.5 or 30/-10:2)"
        ) from None
    if not math.isfinite(value):
        raise ConfigError(f"timeline keyframe '{item}': {what} must be finite, found '{text}'")
    return value


def _eye_fields(fields: list[str], item: str) -> tuple[float, float, float]:
    """eye_yaw, eye_pitch and openness from `FIELD=VALUE` texts; ConfigError naming the item."""
    values = {"eye_yaw": 0.0, "eye_pitch": 0.0, "eyes": 1.0}
    seen: set[str] = set()
    for field in fields:
        key, equals, text = (part.strip() for part in field.partition("="))
        if not equals or key not in values:
            raise ConfigError(
                f"timeline keyframe '{item}': unknown field '{field}' "
                "(expected eyes=open|closed|half|0..1, eye_yaw=DEG or eye_pitch=DEG)"
            )
        if key in seen:
            raise ConfigError(f"timeline keyframe '{item}': field '{key}' given twice")
        seen.add(key)
        if key == "eyes":
            value = EYES_WORDS.get(text, math.nan)
            if text not in EYES_WORDS:
                try:
                    value = float(text)
                except ValueError:
                    value = math.nan
            if not 0.0 <= value <= 1.0:
                raise ConfigError(
                    f"timeline keyframe '{item}': eyes must be open, closed, half or a number "
                    f"within 0..1, found '{text}'"
                )
        else:
            value = _number(text, key, item)
            if abs(value) > MAX_ABS_EYE_DEG:
                raise ConfigError(
                    f"timeline keyframe '{item}': {key} {value:g} deg is outside "
                    f"+-{MAX_ABS_EYE_DEG:g} deg"
                )
        values[key] = value
    return values["eye_yaw"], values["eye_pitch"], values["eyes"]


def parse_timeline(
    spec: str,
    transition_s: float = DEFAULT_TRANSITION_S,
    eye_transition_s: float = DEFAULT_EYE_TRANSITION_S,
) -> Timeline:
    """Parse `YAW[/PITCH][;FIELD=VALUE...]:SECONDS,...` (degrees, seconds; the fields in the
    module docstring); raises ConfigError naming the bad item.

    Yaw must lie within +-80 deg, pitch within +-40 deg, eye angles within +-35 deg, each
    duration must be positive and the whole timeline at most an hour.
    """
    for name, value in (("transition", transition_s), ("eye transition", eye_transition_s)):
        if not math.isfinite(value) or value < 0:
            raise ConfigError(f"{name} must be a finite number >= 0 s, found {value}")
    items = [item.strip() for item in spec.split(",")]
    if not spec.strip() or any(not item for item in items):
        raise ConfigError(
            f"timeline '{spec}' has an empty keyframe; expected comma-separated YAW[/PITCH]:SECONDS"
            " items, e.g. '0:2,40:3.5,0:2'"
        )
    keyframes = []
    for item in items:
        pose, sep, seconds = item.partition(":")
        if not sep or ":" in seconds:
            raise ConfigError(
                f"timeline keyframe '{item}' must be YAW[/PITCH][;FIELD=VALUE...]:SECONDS "
                "(one colon), e.g. 40:3.5 or 0;eyes=closed:1.5"
            )
        head, *fields = pose.split(";")
        yaw_text, slash, pitch_text = head.partition("/")
        yaw_deg = _number(yaw_text, "yaw", item)
        pitch_deg = _number(pitch_text, "pitch", item) if slash else 0.0
        duration_s = _number(seconds, "duration", item)
        if abs(yaw_deg) > MAX_ABS_YAW_DEG:
            raise ConfigError(
                f"timeline keyframe '{item}': yaw {yaw_deg:g} deg is outside "
                f"+-{MAX_ABS_YAW_DEG:g} deg (a face mesh seen from the side cannot be rendered)"
            )
        if abs(pitch_deg) > MAX_ABS_PITCH_DEG:
            raise ConfigError(
                f"timeline keyframe '{item}': pitch {pitch_deg:g} deg is outside "
                f"+-{MAX_ABS_PITCH_DEG:g} deg"
            )
        if duration_s <= 0:
            raise ConfigError(
                f"timeline keyframe '{item}': duration must be > 0 s, found {duration_s:g}"
            )
        eye_yaw, eye_pitch, openness = _eye_fields(fields, item)
        keyframes.append(Keyframe(yaw_deg, pitch_deg, duration_s, eye_yaw, eye_pitch, openness))
    timeline = Timeline(tuple(keyframes), transition_s, eye_transition_s)
    if timeline.duration_s > MAX_CLIP_S:
        raise ConfigError(
            f"timeline lasts {timeline.duration_s:g} s; at most {MAX_CLIP_S:g} s is allowed"
        )
    return timeline
