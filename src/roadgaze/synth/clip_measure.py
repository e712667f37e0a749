"""Pose, smoothing and zones on a rendered clip against its exact truth.

`measure_clip` renders a timeline to an mp4 (as the demo does), runs the landmark stage over it
in VIDEO mode and the pose stage's raw yaw and pitch models on every frame, then compares with
the truth: the raw series, the online smoother (what the monitor and the bus get) and the offline
RTS pass (replay reports), per angle; pitch per |pitch| range; and the monitor's zones against
the zones of the true pose. With `noise_deg` the same is repeated on the raw series plus white
noise (several seeds), the case the smoothers are for.

The neutral pose (yaw and pitch) is the median estimate over the clip's opening road segment (at
most 3 s), i.e. what the monitor learns at the start of a drive; pitch is measured relative to
it, yaw as it is (the truth's zero is the photo's own pose).
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roadgaze.config import Config, SmoothingConfig
from roadgaze.evaluation.stats import ErrorStats, RangeStats, range_stats
from roadgaze.synth.clip import DEFAULT_FPS, render_clip
from roadgaze.synth.measure import PITCH_RANGES_DEG, zone_agreement
from roadgaze.synth.renderer import DEFAULT_SIZE, FaceRenderer, load_photo
from roadgaze.synth.timeline import Timeline, parse_timeline
from roadgaze.types import FaceFeatures, FloatArray, PoseSample

__all__ = [
    "POSE_TIMELINE",
    "ChannelErrors",
    "ClipMeasurement",
    "format_clip_measurement",
    "measure_clip",
]

POSE_TIMELINE = (
    "0/0:3,0/-40:3,0/0:2,0/-25:2,0/0:2,40/0:2.5,0/0:2,-35/-20:2,0/0:2,0/20:2,0/0:2,"
    "-20/-35:2.5,0/0:2,30/10:2,0/0:3"
)
"""A 33 s yaw/pitch drive: glances into the lap (-40, -25), to the left mirror, down and right,
up, to the centre stack (-20/-35) and up-left, each from the road."""

NEUTRAL_WINDOW_S = 3.0
EXCURSION_WINDOW_S = 0.5


@dataclass(frozen=True, slots=True)
class ChannelErrors:
    """One angle's MAE against the truth (over frames with a raw value) and its excursions."""

    raw_mae_deg: float
    online_mae_deg: float
    offline_mae_deg: float
    online_excursion_deg: float
    offline_excursion_deg: float

    @property
    def online_ratio(self) -> float:
        return self.online_mae_deg / self.raw_mae_deg if self.raw_mae_deg > 0 else math.nan

    @property
    def offline_ratio(self) -> float:
        return self.offline_mae_deg / self.raw_mae_deg if self.raw_mae_deg > 0 else math.nan


def _smooth_online(t_s: FloatArray, raw: FloatArray, config: SmoothingConfig) -> FloatArray:
    from roadgaze.pose import AngleSmoother

    smoother = AngleSmoother(config)
    out = np.full(raw.shape, np.nan)
    for i, (time_s, value) in enumerate(zip(t_s, raw, strict=True)):
        result = smoother.update(float(time_s), None if np.isnan(value) else float(value))
        if result is not None:
            out[i] = result.angle_deg
    return out


def _channel(
    t_s: FloatArray, raw: FloatArray, truth: FloatArray, config: SmoothingConfig
) -> tuple[ChannelErrors, FloatArray]:
    from roadgaze.pose import excursion_deg, rts_smooth

    online = _smooth_online(t_s, raw, config)
    offline = rts_smooth(t_s, raw, config)
    measured = np.isfinite(raw)

    def mae(values: FloatArray) -> float:
        errors = np.abs(values[measured] - truth[measured])
        errors = errors[np.isfinite(errors)]
        return float(errors.mean()) if errors.size else math.nan

    errors = ChannelErrors(
        raw_mae_deg=mae(raw),
        online_mae_deg=mae(online),
        offline_mae_deg=mae(offline),
        online_excursion_deg=excursion_deg(online, raw, t_s, EXCURSION_WINDOW_S),
        offline_excursion_deg=excursion_deg(offline, raw, t_s, EXCURSION_WINDOW_S),
    )
    return errors, online


@dataclass(frozen=True, slots=True)
class ClipMeasurement:
    """Everything `format_clip_measurement` prints."""

    timeline: str
    size: tuple[int, int]
    fps: float
    frames: int
    found: int
    neutral_yaw_deg: float
    neutral_pitch_deg: float
    yaw: ChannelErrors
    pitch: ChannelErrors
    pitch_ranges: tuple[tuple[RangeStats, RangeStats], ...]
    """Per |true pitch| range (and all): the raw and the online pitch's errors."""
    truth_zone: tuple[str, ...]
    zone: tuple[str | None, ...]
    noise_deg: float
    seeds: int
    noisy_yaw: ChannelErrors | None
    """Means over the seeds (excursions: the largest)."""
    noisy_pitch: ChannelErrors | None


def _mean_errors(items: list[ChannelErrors]) -> ChannelErrors:
    return ChannelErrors(
        raw_mae_deg=float(np.mean([e.raw_mae_deg for e in items])),
        online_mae_deg=float(np.mean([e.online_mae_deg for e in items])),
        offline_mae_deg=float(np.mean([e.offline_mae_deg for e in items])),
        online_excursion_deg=max(e.online_excursion_deg for e in items),
        offline_excursion_deg=max(e.offline_excursion_deg for e in items),
    )


def _detect_clip(path: Path, config: Config) -> tuple[FloatArray, list[FaceFeatures | None]]:
    from roadgaze.capture import open_source
    from roadgaze.landmarks import Landmarker

    times: list[float] = []
    faces: list[FaceFeatures | None] = []
    with (
        open_source(str(path), config) as source,
        Landmarker.from_config(config, video=True) as detector,
    ):
        for frame in source:
            faces.append(detector.detect(frame.image, frame.t_s).driver)
            times.append(frame.t_s)
    return np.asarray(times, dtype=np.float64), faces


def _series(
    faces: list[FaceFeatures | None], value: Callable[[FaceFeatures], float | None]
) -> FloatArray:
    out = np.full(len(faces), np.nan)
    for i, face in enumerate(faces):
        if face is not None:
            measured = value(face)
            out[i] = math.nan if measured is None else measured
    return out


def measure_clip(
    timeline: Timeline | str = POSE_TIMELINE,
    config: Config | None = None,
    photo: Path | None = None,
    size: tuple[int, int] = DEFAULT_SIZE,
    fps: float = DEFAULT_FPS,
    noise_deg: float = 0.0,
    seeds: int = 5,
    renderer: FaceRenderer | None = None,
) -> ClipMeasurement:
    """Render `timeline`, run the landmark and pose stages over it and measure against the truth.

    Raises ConfigError for a bad timeline, SourceError for an unusable photo and ModelError
    when the landmarker model is unavailable.
    """
    from roadgaze.monitor import Monitor, ZoneMap
    from roadgaze.pose import PoseEstimator

    config = config if config is not None else Config()
    spec = timeline if isinstance(timeline, str) else ""
    timeline = parse_timeline(timeline) if isinstance(timeline, str) else timeline
    renderer = (
        renderer if renderer is not None else FaceRenderer(load_photo(photo), size, config=config)
    )
    with tempfile.TemporaryDirectory(prefix="roadgaze-measure-") as folder:
        clip = Path(folder) / "clip.mp4"
        truth = render_clip(timeline, clip, fps=fps, renderer=renderer)
        t_s, faces = _detect_clip(clip, config)
    count = min(len(faces), len(truth))
    t_s, faces, truth = t_s[:count], faces[:count], truth[:count]
    true_yaw, true_pitch = truth[:, 1], truth[:, 2]

    pose = PoseEstimator.from_config(config)
    yaw_raw = _series(faces, pose.raw_yaw_deg)
    still = (true_yaw == 0.0) & (true_pitch == 0.0)
    opening = np.cumprod(still).astype(bool) & (t_s < NEUTRAL_WINDOW_S)
    road = opening if np.any(opening & np.isfinite(yaw_raw)) else np.isfinite(yaw_raw)
    neutral_yaw = float(np.nanmedian(yaw_raw[road])) if np.any(road) else 0.0
    if config.pose.pitch_model == "matrix":  # the down gain starts at the learned neutral
        matrix = _series(faces, lambda face: face.mediapipe_pitch_deg)
        neutral_pitch = float(np.nanmedian(matrix[road])) if np.any(road) else 0.0
        pitch_raw = _series(faces, lambda face: pose.raw_pitch_deg(face, neutral_pitch))
    else:
        pitch_raw = _series(faces, pose.raw_pitch_deg)
        neutral_pitch = float(np.nanmedian(pitch_raw[road])) if np.any(road) else 0.0
    pitch_relative = pitch_raw - neutral_pitch

    smoothing = config.smoothing
    yaw_errors, yaw_online = _channel(t_s, yaw_raw, true_yaw, smoothing)
    pitch_errors, pitch_online = _channel(t_s, pitch_relative, true_pitch, smoothing)
    last = len(PITCH_RANGES_DEG) - 1
    bounds = (*PITCH_RANGES_DEG, (0.0, PITCH_RANGES_DEG[-1][1]))
    pitch_ranges = tuple(
        (
            range_stats("raw", true_pitch, pitch_relative, low, high, i >= last),
            range_stats("online", true_pitch, pitch_online, low, high, i >= last),
        )
        for i, (low, high) in enumerate(bounds)
    )

    monitor_config = config.monitor.model_copy(
        update={"neutral_yaw_deg": neutral_yaw, "neutral_pitch_deg": neutral_pitch}
    )
    monitor = Monitor(monitor_config)
    zones_seen: list[str | None] = []
    for i, face in enumerate(faces):
        found = face is not None
        monitor.update(
            PoseSample(
                t_s=float(t_s[i]),
                frame=i,
                face=found,
                yaw_raw_deg=None if np.isnan(yaw_raw[i]) else float(yaw_raw[i]),
                yaw_deg=None if np.isnan(yaw_online[i]) else float(yaw_online[i]),
                yaw_rate_dps=None,
                yaw_std_deg=None,
                pitch_deg=(
                    None if np.isnan(pitch_online[i]) else float(pitch_online[i] + neutral_pitch)
                ),
            )
        )
        zones_seen.append(monitor.verdict.zone if found else None)
    zone_map = ZoneMap.from_config(monitor_config)
    truth_zone: list[str] = []
    previous = "road"
    for yaw_deg, pitch_deg in zip(true_yaw, true_pitch, strict=True):
        previous = zone_map.classify(float(yaw_deg), float(pitch_deg), previous)
        truth_zone.append(previous)

    noisy_yaw = noisy_pitch = None
    if noise_deg > 0 and seeds > 0:
        yaw_runs, pitch_runs = [], []
        for seed in range(seeds):
            rng = np.random.default_rng(seed)
            yaw_runs.append(
                _channel(t_s, yaw_raw + rng.normal(0, noise_deg, count), true_yaw, smoothing)[0]
            )
            noisy = pitch_relative + rng.normal(0, noise_deg, count)
            pitch_runs.append(_channel(t_s, noisy, true_pitch, smoothing)[0])
        noisy_yaw, noisy_pitch = _mean_errors(yaw_runs), _mean_errors(pitch_runs)
    return ClipMeasurement(
        timeline=spec,
        size=renderer.size,
        fps=fps,
        frames=count,
        found=int(sum(face is not None for face in faces)),
        neutral_yaw_deg=neutral_yaw,
        neutral_pitch_deg=neutral_pitch,
        yaw=yaw_errors,
        pitch=pitch_errors,
        pitch_ranges=pitch_ranges,
        truth_zone=tuple(truth_zone),
        zone=tuple(zones_seen),
        noise_deg=noise_deg,
        seeds=seeds,
        noisy_yaw=noisy_yaw,
        noisy_pitch=noisy_pitch,
    )


def _channel_line(name: str, errors: ChannelErrors) -> str:
    return (
        f"  {name:<6} raw {errors.raw_mae_deg:6.3f} | online {errors.online_mae_deg:6.3f} "
        f"({errors.online_ratio:5.3f} x raw, leaves the raw range by "
        f"{errors.online_excursion_deg:4.2f}) | offline {errors.offline_mae_deg:6.3f} "
        f"({errors.offline_ratio:5.3f} x raw, {errors.offline_excursion_deg:4.2f})"
    )


def format_clip_measurement(result: ClipMeasurement) -> str:
    """The smoother table, pitch per |pitch| range and the zones, as plain text."""
    lines = [
        f"clip {result.timeline or '(timeline)'}: {result.size[0]}x{result.size[1]} at "
        f"{result.fps:g} fps, {result.frames} frames, face in {result.found}; neutral yaw "
        f"{result.neutral_yaw_deg:+.2f}, pitch {result.neutral_pitch_deg:+.2f} deg (median of the "
        "opening road segment)",
        "MAE against the truth in degrees (over frames with a raw value); the smoothers' largest "
        f"distance outside the raw range within +-{EXCURSION_WINDOW_S:g} s:",
        _channel_line("yaw", result.yaw),
        _channel_line("pitch", result.pitch),
    ]
    if result.noisy_yaw is not None and result.noisy_pitch is not None:
        lines.append(
            f"with white noise of {result.noise_deg:g} deg added to the raw series "
            f"(mean of {result.seeds} seeds; excursions: the largest):"
        )
        lines.append(_channel_line("yaw", result.noisy_yaw))
        lines.append(_channel_line("pitch", result.noisy_pitch))
    lines.append("pitch error per |true pitch| range (relative to the neutral): MAE / mean error")

    def cell(stats: ErrorStats) -> str:
        if not stats.n_valid:
            return f"{'-':>5} / {'-':>6}"
        return f"{stats.mae_deg:5.2f} / {stats.bias_deg:+6.2f}"

    for raw, online in result.pitch_ranges:
        label = f"{raw.low_deg:g}-{raw.high_deg:g}"
        lines.append(
            f"  {label:>6} frames {raw.stats.n_images:>4} | raw {cell(raw.stats)} | "
            f"online {cell(online.stats)}"
        )
    lines.extend(zone_agreement(result.truth_zone, result.zone))
    return "\n".join(lines)
