"""Timelines of head poses: `YAW[/PITCH]:SECONDS` keyframes with eased turns between them.

A timeline such as `0:2,40:3.5,0:2,-35:1,0:2` lists keyframes: in each segment the head turns to
YAW (and PITCH, default 0) degrees during the first `transition_s` seconds with a cosine ease,
then holds it for the rest of the segment; the first segment starts already at its pose. Yaw > 0
turns the head to the person's own left (the nose moves to the image right), pitch > 0 looks up.
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


@dataclass(frozen=True, slots=True)
class Keyframe:
    """Turn to `yaw_deg`/`pitch_deg` at the start of a segment of `duration_s` and hold it."""

    yaw_deg: float
    pitch_deg: float
    duration_s: float


@dataclass(frozen=True, slots=True)
class Timeline:
    """Keyframes with cosine-eased transitions of `transition_s` between them."""

    keyframes: tuple[Keyframe, ...]
    transition_s: float = DEFAULT_TRANSITION_S

    @property
    def duration_s(self) -> float:
        return sum(k.duration_s for k in self.keyframes)

    def pose_at(self, t_s: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Yaw and pitch in degrees at times `t_s` (seconds; clamped to the timeline)."""
        t = np.asarray(t_s, dtype=np.float64)
        yaw = np.full(t.shape, self.keyframes[0].yaw_deg)
        pitch = np.full(t.shape, self.keyframes[0].pitch_deg)
        start_s = 0.0
        previous = self.keyframes[0]
        for keyframe in self.keyframes:
            ramp_s = min(self.transition_s, keyframe.duration_s / 2.0)
            if ramp_s > 0.0:
                progress = np.clip((t - start_s) / ramp_s, 0.0, 1.0)
            else:
                progress = np.ones_like(t)
            ease = 0.5 - 0.5 * np.cos(np.pi * progress)
            in_segment = t >= start_s
            yaw = np.where(
                in_segment, previous.yaw_deg + (keyframe.yaw_deg - previous.yaw_deg) * ease, yaw
            )
            pitch = np.where(
                in_segment,
                previous.pitch_deg + (keyframe.pitch_deg - previous.pitch_deg) * ease,
                pitch,
            )
            start_s += keyframe.duration_s
            previous = keyframe
        return yaw, pitch

    def truth(self, fps: float) -> FloatArray:
        """(N, 3) rows `t_s, yaw_deg, pitch_deg` at `i / fps`; N = round(duration * fps)."""
        n_frames = max(1, round(self.duration_s * fps))
        t = np.arange(n_frames, dtype=np.float64) / fps
        yaw, pitch = self.pose_at(t)
        return np.column_stack([t, yaw, pitch])


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


def parse_timeline(spec: str, transition_s: float = DEFAULT_TRANSITION_S) -> Timeline:
    """Parse `YAW[/PITCH]:SECONDS,...` (degrees, seconds); raises ConfigError naming the bad item.

    Yaw must lie within +-80 deg, pitch within +-40 deg, each duration must be positive and the
    whole timeline at most an hour.
    """
    if not math.isfinite(transition_s) or transition_s < 0:
        raise ConfigError(f"transition must be a finite number >= 0 s, found {transition_s}")
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
                f"timeline keyframe '{item}' must be YAW[/PITCH]:SECONDS (one colon), e.g. 40:3.5"
            )
        yaw_text, slash, pitch_text = pose.partition("/")
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
        keyframes.append(Keyframe(yaw_deg, pitch_deg, duration_s))
    timeline = Timeline(tuple(keyframes), transition_s)
    if timeline.duration_s > MAX_CLIP_S:
        raise ConfigError(
            f"timeline lasts {timeline.duration_s:g} s; at most {MAX_CLIP_S:g} s is allowed"
        )
    return timeline
