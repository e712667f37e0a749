"""The offline pass: fixed-interval (RTS) smoothing of a whole recording's yaw and pitch.

For reports of a finished recording (`roadgaze replay` fills `yaw_offline_deg` and
`pitch_offline_deg` at the end; the fleet batch calls `offline_pose` per drive). It looks at the
future as well as the past, so it is more accurate than the online smoother, but alerts are never
computed from it: they stay on the causal estimate, so a replay and the vehicle agree.

Per angle: samples further than `gate_sigma` noise levels from the median of their five-sample
neighbourhood are dropped as outliers (a median of five keeps steps and removes spikes of one or
two samples); the series is split into tracks at gaps longer than `reinit_gap_s`; each track runs
through filterpy's `batch_filter` (missing samples predicted) and `rts_smoother` with the
constant-velocity model of the online smoother and the track's own measured noise; the result is
clamped to the raw range within +-`clamp_window_s`/2 of each sample. Pure numpy + filterpy.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.config import SmoothingConfig
from roadgaze.pose.smoothing import constant_velocity_model, robust_noise_std_deg
from roadgaze.types import FloatArray

__all__ = ["OfflinePose", "excursion_deg", "offline_pose", "rts_smooth"]

_NEIGHBOURHOOD = 5


@dataclass(frozen=True, slots=True)
class OfflinePose:
    """The offline estimates, aligned with the input samples; NaN where there is no track."""

    yaw_deg: FloatArray
    pitch_deg: FloatArray


def _tracks(t_s: FloatArray, finite: npt.NDArray[np.bool_], gap_s: float) -> list[slice]:
    """Index ranges from a finite sample to the last one before a gap longer than `gap_s`."""
    index = np.flatnonzero(finite)
    if index.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(t_s[index]) > gap_s) + 1
    return [slice(int(run[0]), int(run[-1]) + 1) for run in np.split(index, breaks)]


def _rolling_median(values: FloatArray, width: int) -> FloatArray:
    """Median of the finite values in a centred window of `width` samples (NaN if none)."""
    half = width // 2
    padded = np.pad(values, half, constant_values=np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(padded, width)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an all-NaN window gives NaN
        return np.asarray(np.nanmedian(windows, axis=1), dtype=np.float64)


def _window_bounds(
    values: FloatArray, t_s: FloatArray, half_window_s: float
) -> tuple[FloatArray, FloatArray]:
    """Min and max of the finite values within +-`half_window_s` of each sample (sparse table)."""
    n = values.size
    low_fill = np.where(np.isfinite(values), values, np.inf)
    high_fill = np.where(np.isfinite(values), values, -np.inf)
    start = np.searchsorted(t_s, t_s - half_window_s, side="left")
    stop = np.searchsorted(t_s, t_s + half_window_s, side="right")  # exclusive
    lows, highs = [low_fill], [high_fill]
    span = 1
    while 2 * span <= n:
        lows.append(np.minimum(lows[-1][:-span], lows[-1][span:]))
        highs.append(np.maximum(highs[-1][:-span], highs[-1][span:]))
        span *= 2
    length = np.maximum(stop - start, 1)
    level = np.floor(np.log2(length)).astype(np.int64)
    low = np.empty(n)
    high = np.empty(n)
    for k in np.unique(level):
        rows = np.flatnonzero(level == k)
        width = 1 << int(k)
        low[rows] = np.minimum(lows[k][start[rows]], lows[k][stop[rows] - width])
        high[rows] = np.maximum(highs[k][start[rows]], highs[k][stop[rows] - width])
    return low, high


def excursion_deg(
    estimate_deg: npt.ArrayLike,
    raw_deg: npt.ArrayLike,
    t_s: npt.ArrayLike,
    half_window_s: float = 0.5,
) -> float:
    """Largest distance (degrees) of a smoothed series outside [min, max] of the raw values
    within +-`half_window_s` of each sample, over the samples with both values; 0 if it never
    leaves. The measure of overshoot and ringing. `t_s` must increase."""
    estimate = np.asarray(estimate_deg, dtype=np.float64)
    raw = np.asarray(raw_deg, dtype=np.float64)
    low, high = _window_bounds(raw, np.asarray(t_s, dtype=np.float64), half_window_s)
    both = np.isfinite(estimate) & np.isfinite(raw)
    if not np.any(both):
        return 0.0
    outside = np.maximum(estimate[both] - high[both], low[both] - estimate[both])
    return max(0.0, float(np.max(outside)))


def _smooth_track(t_s: FloatArray, values: FloatArray, config: SmoothingConfig) -> FloatArray:
    measured = robust_noise_std_deg(t_s, values)
    noise_std = max(
        measured if math.isfinite(measured) else config.measurement_std_deg,
        config.min_measurement_std_deg,
    )
    # Imported here: filterpy pulls in scipy.stats (about 2 s of CPU), which every command that
    # imports the pose stage (`roadgaze --help`, `listen`, `run`) would pay at start otherwise.
    from filterpy.kalman import KalmanFilter

    kalman = KalmanFilter(dim_x=2, dim_z=1)
    kalman.H = np.array([[1.0, 0.0]])
    kalman.R = np.array([[noise_std**2]])
    first = int(np.flatnonzero(np.isfinite(values))[0])
    kalman.x = np.array([[values[first]], [0.0]])
    kalman.P = np.diag([noise_std**2, config.initial_rate_std_dps**2])
    steps = np.diff(t_s, prepend=t_s[0])
    steps[0] = steps[1] if steps.size > 1 else 1.0
    models = {
        float(dt): constant_velocity_model(float(dt), config.acceleration_std_dps2)
        for dt in np.unique(steps)
    }
    transitions = [models[float(dt)][0] for dt in steps]
    noises = [models[float(dt)][1] for dt in steps]
    measurements = [np.array([[v]]) if math.isfinite(v) else None for v in values]
    means, covariances, _, _ = kalman.batch_filter(measurements, Fs=transitions, Qs=noises)
    smoothed, _, _, _ = kalman.rts_smoother(means, covariances, Fs=transitions, Qs=noises)
    return np.asarray(smoothed[:, 0, 0], dtype=np.float64)


def rts_smooth(
    t_s: npt.ArrayLike, values_deg: npt.ArrayLike, config: SmoothingConfig | None = None
) -> FloatArray:
    """Fixed-interval smoothing of one angle series (degrees, NaN = no measurement).

    `t_s` must increase strictly. Returns an array aligned with the input: NaN before the first
    and after the last measurement of each track and in gaps longer than `reinit_gap_s`.
    Raises ValueError for arrays of different shapes or times that do not increase.
    """
    config = config if config is not None else SmoothingConfig()
    t = np.asarray(t_s, dtype=np.float64)
    z = np.asarray(values_deg, dtype=np.float64)
    if t.shape != z.shape or t.ndim != 1:
        raise ValueError(f"t_s and values must be 1-D of one length, found {t.shape}, {z.shape}")
    if t.size > 1 and not np.all(np.diff(t) > 0):
        raise ValueError("t_s must increase strictly for the offline smoother")
    out = np.full(z.shape, np.nan)
    if not np.any(np.isfinite(z)):
        return out
    z = np.where(np.isfinite(z), z, np.nan)
    median = _rolling_median(z, _NEIGHBOURHOOD)
    noise = robust_noise_std_deg(t, z)
    gate_deg = config.gate_sigma * max(
        noise if math.isfinite(noise) else 0.0, config.measurement_std_deg
    )
    with np.errstate(invalid="ignore"):
        kept = np.where(np.abs(z - median) > gate_deg, np.nan, z)
    for track in _tracks(t, np.isfinite(kept), config.reinit_gap_s):
        out[track] = _smooth_track(t[track], kept[track], config)
    low, high = _window_bounds(z, t, config.clamp_window_s / 2.0)
    bounded = np.isfinite(out) & np.isfinite(low) & np.isfinite(high)
    out[bounded] = np.clip(out[bounded], low[bounded], high[bounded])
    return out


def offline_pose(
    t_s: npt.ArrayLike,
    yaw_raw_deg: npt.ArrayLike,
    pitch_raw_deg: npt.ArrayLike,
    config: SmoothingConfig | None = None,
) -> OfflinePose:
    """The offline pass over one recording: RTS-smoothed yaw and pitch from the raw series
    (degrees, NaN = no measurement), aligned with `t_s` (seconds, strictly increasing)."""
    return OfflinePose(
        yaw_deg=rts_smooth(t_s, yaw_raw_deg, config),
        pitch_deg=rts_smooth(t_s, pitch_raw_deg, config),
    )
