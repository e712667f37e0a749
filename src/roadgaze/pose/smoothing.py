"""The online (causal) smoother of one head angle: a Kalman filter that never makes things worse.

Constant-velocity Kalman filter, state `[angle_deg, rate_dps]`, `dt` from the samples'
timestamps; the pose stage runs one per angle (yaw, pitch). The filter's equations are filterpy's
`KalmanFilter.predict`/`update` (Joseph form) for this 2-state, 1-measurement model written out in
plain floats (`ConstantVelocityFilter`), as openpilot's `KF1D` does: 3 us per update instead of
about 25 us (and ten times that after the idle time between camera frames, when numpy's code is
out of the caches). `tests/pose/test_smoothing.py` runs the smoother with filterpy's
`KalmanFilter` in its place and checks the two agree over long drives with gaps, outliers and
restarts; filterpy also runs the offline smoother (`roadgaze.pose.offline`). Four rules keep it from
doing harm where the raw series is already good (docs/pose.md has the measurements):

1. **Measured noise.** The measurement noise R is the robust (median absolute) spread of the raw
   series' linear-extrapolation residuals over the last `noise_window` frames (floor
   `min_measurement_std_deg`; `measurement_std_deg` until `min_noise_samples` residuals exist).
   A clean series passes through almost untouched, a noisy one is smoothed as its noise justifies.
2. **Bounded output.** The estimate is clamped to the range of the accepted raw values of the last
   `clamp_window_s`, and the clamp is written back into the state: the constant-velocity model's
   overshoot and ringing after a step cannot leave the raw range.
3. **No extrapolation through gaps.** Without a measurement the estimate holds (rate set to 0; the
   variance still grows, so the next measurement is trusted); after `reinit_gap_s` the track is
   dropped and restarts on the next measurement.
4. **Outlier gate.** A measurement further than `gate_sigma` standard deviations of the
   innovation from the prediction, the measurement noise taken as at least `measurement_std_deg`,
   is rejected (the prediction, kept within the raw range, stands in for it); `max_rejections`
   consecutive rejections mean the head really moved, and the track restarts on the measurement.
   A single-frame jump of tens of degrees is gated out; a head turn passes (its deviation from a
   constant rate within one frame is a few degrees).
"""

from __future__ import annotations

import math
import operator
import statistics
from collections import deque
from dataclasses import dataclass

import numpy as np

from roadgaze.config import SmoothingConfig
from roadgaze.types import FloatArray, SmoothedAngle

__all__ = [
    "MAD_TO_STD",
    "AngleSmoother",
    "ConstantVelocityFilter",
    "SmootherState",
    "constant_velocity_model",
    "extrapolation_residuals",
    "robust_noise_std_deg",
]

MAD_TO_STD = 1.4826
"""Median absolute deviation to standard deviation, for Gaussian noise."""


def extrapolation_residuals(t_s: FloatArray, values: FloatArray) -> FloatArray:
    """Residuals of predicting each value linearly from the two before it, scaled so that their
    standard deviation is that of white measurement noise; non-finite values are skipped.

    For a constant frame rate the residual is the second difference, whose variance is 6 sigma^2.
    """
    t = np.asarray(t_s, dtype=np.float64)
    z = np.asarray(values, dtype=np.float64)
    usable = np.isfinite(z) & np.isfinite(t)
    t, z = t[usable], z[usable]
    if z.size < 3:
        return np.zeros(0)
    ratio = (t[2:] - t[1:-1]) / (t[1:-1] - t[:-2])
    residual = z[2:] - z[1:-1] - (z[1:-1] - z[:-2]) * ratio
    return np.asarray(residual / np.sqrt(1.0 + (1.0 + ratio) ** 2 + ratio**2), dtype=np.float64)


def robust_noise_std_deg(t_s: FloatArray, values: FloatArray) -> float:
    """White-noise standard deviation of a series from its extrapolation residuals (MAD), degrees;
    NaN with fewer than three finite values. A smooth head turn barely moves it."""
    residual = extrapolation_residuals(t_s, values)
    if residual.size == 0:
        return math.nan
    return float(MAD_TO_STD * np.median(np.abs(residual)))


def constant_velocity_model(
    dt_s: float, acceleration_std_dps2: float
) -> tuple[FloatArray, FloatArray]:
    """Transition F and process noise Q of the constant-velocity model over `dt_s` seconds.

    Q is filterpy's `Q_discrete_white_noise(dim=2, dt, var)` (piecewise white acceleration),
    written out: var * [[dt^4/4, dt^3/2], [dt^3/2, dt^2]].
    """
    transition = np.array([[1.0, dt_s], [0.0, 1.0]])
    var = acceleration_std_dps2**2
    noise = var * np.array(
        [[dt_s**4 / 4.0, dt_s**3 / 2.0], [dt_s**3 / 2.0, dt_s**2]], dtype=np.float64
    )
    return transition, noise


@dataclass(frozen=True, slots=True)
class SmootherState:
    """A snapshot of the smoother's explicit state (for inspection, logging and tests)."""

    tracking: bool
    """False before the first measurement and after the track was dropped."""
    t_s: float | None
    """Time of the last update."""
    last_measurement_t_s: float | None
    """Time of the last accepted (or re-initialising) measurement."""
    angle_deg: float | None
    rate_dps: float | None
    std_deg: float | None
    measurement_std_deg: float
    """The measurement noise currently assumed (measured, or the configured value before that)."""
    consecutive_rejections: int
    """Measurements rejected by the gate since the last accepted one."""
    rejected_total: int
    reinitialisations: int
    """Restarts after a gap or after a run of rejections (the first start is not counted)."""


_value = operator.itemgetter(1)
"""The value of a (t_s, value) pair."""


class ConstantVelocityFilter:
    """The Kalman filter of one angle: state (angle, rate), covariance [[p00, p01], [p01, p11]].

    filterpy's `KalmanFilter(dim_x=2, dim_z=1)` with H = [1, 0], F = [[1, dt], [0, 1]] and
    `constant_velocity_model`'s Q, its matrix products written out: `predict` is x = F x,
    P = F P F' + Q; `update` is the gain K = P H' / (H P H' + R) and the Joseph form
    P = (I - K H) P (I - K H)' + K R K'.
    """

    __slots__ = ("angle", "p00", "p01", "p11", "rate")

    def __init__(self) -> None:
        self.angle = self.rate = 0.0
        self.p00 = self.p11 = 1.0
        self.p01 = 0.0

    def start(self, angle: float, angle_var: float, rate_var: float) -> None:
        """x = (angle, 0), P = diag(angle_var, rate_var)."""
        self.angle, self.rate = angle, 0.0
        self.p00, self.p01, self.p11 = angle_var, 0.0, rate_var

    def predict(self, dt_s: float, acceleration_var: float) -> None:
        p00, p01, p11 = self.p00, self.p01, self.p11
        dt2 = dt_s * dt_s
        self.angle += dt_s * self.rate
        # F P F' + Q, with Q = var [[dt^4/4, dt^3/2], [dt^3/2, dt^2]].
        self.p00 = p00 + dt_s * p01 + dt_s * (p01 + dt_s * p11) + acceleration_var * dt2 * dt2 / 4.0
        self.p01 = p01 + dt_s * p11 + acceleration_var * dt2 * dt_s / 2.0
        self.p11 = p11 + acceleration_var * dt2

    def update(self, measured: float, measurement_var: float) -> None:
        p00, p01, p11 = self.p00, self.p01, self.p11
        innovation_var = p00 + measurement_var
        k0, k1 = p00 / innovation_var, p01 / innovation_var
        innovation = measured - self.angle
        self.angle += k0 * innovation
        self.rate += k1 * innovation
        # (I - K H) P (I - K H)' + K R K', with I - K H = [[1 - k0, 0], [-k1, 1]].
        a00 = 1.0 - k0
        self.p00 = a00 * p00 * a00 + k0 * measurement_var * k0
        self.p01 = a00 * (p01 - k1 * p00) + k0 * measurement_var * k1
        self.p11 = -k1 * (p01 - k1 * p00) + (p11 - k1 * p01) + k1 * measurement_var * k1

    def hold(self) -> None:
        """Drop the rate (a gap: the angle holds)."""
        self.rate = 0.0

    def restart_rate(self, rate_var: float) -> None:
        """The rate unknown again (re-acquired after a gap): 0, uncorrelated, `rate_var`."""
        self.rate, self.p01, self.p11 = 0.0, 0.0, rate_var


class AngleSmoother:
    """Smooths one stream of raw angle measurements (degrees); `update` once per frame, in order."""

    def __init__(self, config: SmoothingConfig | None = None) -> None:
        self.config = config if config is not None else SmoothingConfig()
        self._filter = ConstantVelocityFilter()
        self._acceleration_var = self.config.acceleration_std_dps2**2
        self._tracking = False
        self._holding = False
        self._started = False
        self._t_s: float | None = None
        self._last_measurement_t_s: float | None = None
        self._recent: deque[tuple[float, float]] = deque()
        """Accepted (t_s, value) within `clamp_window_s`: bounded by the frame rate."""
        self._history: deque[tuple[float, float]] = deque(maxlen=3)
        self._abs_residuals: deque[float] = deque(maxlen=self.config.noise_window)
        self._noise_std_deg = self.config.measurement_std_deg
        self._consecutive_rejections = 0
        self._rejected_total = 0
        self._reinitialisations = 0

    def reset(self) -> None:
        """Forget the track; the next measurement starts a new one (counters are kept)."""
        self._tracking = False
        self._t_s = None
        self._last_measurement_t_s = None
        self._consecutive_rejections = 0

    def measurement_std_deg(self) -> float:
        """The measurement noise assumed now: measured once enough residuals exist."""
        return self._noise_std_deg

    @property
    def state(self) -> SmootherState:
        estimate = self._estimate() if self._tracking else None
        return SmootherState(
            tracking=self._tracking,
            t_s=self._t_s,
            last_measurement_t_s=self._last_measurement_t_s,
            angle_deg=None if estimate is None else estimate.angle_deg,
            rate_dps=None if estimate is None else estimate.rate_dps,
            std_deg=None if estimate is None else estimate.std_deg,
            measurement_std_deg=self.measurement_std_deg(),
            consecutive_rejections=self._consecutive_rejections,
            rejected_total=self._rejected_total,
            reinitialisations=self._reinitialisations,
        )

    def update(self, t_s: float, value_deg: float | None) -> SmoothedAngle | None:
        """Advance to `t_s` and fold in `value_deg` (None, NaN or infinite: no measurement).

        Returns the estimate at `t_s`, or None without a track (before the first measurement, or
        once `reinit_gap_s` has passed without one). Raises ValueError when `t_s` does not
        increase while a track runs.
        """
        if value_deg is not None and not math.isfinite(value_deg):
            value_deg = None
        if not self._tracking:
            self._t_s = t_s
            if value_deg is None:
                return None
            if self._started:
                self._reinitialisations += 1
            self._start(t_s, value_deg)
            return self._estimate()
        assert self._t_s is not None and self._last_measurement_t_s is not None
        dt_s = t_s - self._t_s
        if not dt_s > 0:
            raise ValueError(
                f"smoother timestamps must increase: got t_s={t_s} after t_s={self._t_s}"
            )
        if t_s - self._last_measurement_t_s > self.config.reinit_gap_s:
            self._t_s = t_s
            if value_deg is None:
                self._tracking = False
                return None
            self._reinitialisations += 1
            self._start(t_s, value_deg)
            return self._estimate()
        self._t_s = t_s
        if value_deg is None:
            self._hold(dt_s)
            return self._estimate()
        if self._holding:  # re-acquired after a gap: the rate is unknown, restart it from 0
            self._filter.restart_rate(self.config.initial_rate_std_dps**2)
            self._history.clear()
            self._holding = False
        self._predict(dt_s)
        if self._is_outlier(value_deg):
            self._rejected_total += 1
            self._consecutive_rejections += 1
            if self._consecutive_rejections >= self.config.max_rejections:
                self._reinitialisations += 1
                self._start(t_s, value_deg)
            else:  # the prediction stands in for the rejected measurement, within the raw range
                self._clamp(t_s, None)
            return self._estimate()
        self._consecutive_rejections = 0
        self._learn_noise(t_s, value_deg)
        noise_std = self.measurement_std_deg()
        self._filter.update(value_deg, noise_std**2)
        self._last_measurement_t_s = t_s
        self._clamp(t_s, value_deg)
        return self._estimate()

    def _is_outlier(self, value_deg: float) -> bool:
        """Whether the innovation exceeds the gate (after `_predict`)."""
        gate_noise_std = max(self.measurement_std_deg(), self.config.measurement_std_deg)
        innovation_var = self._filter.p00 + gate_noise_std**2
        innovation_deg = value_deg - self._filter.angle
        return innovation_deg**2 > self.config.gate_sigma**2 * innovation_var

    def _start(self, t_s: float, value_deg: float) -> None:
        config = self.config
        self._filter.start(value_deg, config.initial_std_deg**2, config.initial_rate_std_dps**2)
        self._tracking = self._started = True
        self._holding = False
        self._t_s = self._last_measurement_t_s = t_s
        self._consecutive_rejections = 0
        self._recent.clear()
        self._recent.append((t_s, value_deg))
        self._history.clear()
        self._learn_noise(t_s, value_deg)

    def _predict(self, dt_s: float) -> None:
        self._filter.predict(dt_s, self._acceleration_var)

    def _hold(self, dt_s: float) -> None:
        """No usable measurement: keep the angle, drop the rate, let the variance grow."""
        self._filter.hold()
        if dt_s > 0:
            self._predict(dt_s)
        self._holding = True

    def _learn_noise(self, t_s: float, value_deg: float) -> None:
        self._history.append((t_s, value_deg))
        if len(self._history) < 3:
            return
        (t0, z0), (t1, z1), (t2, z2) = self._history
        ratio = (t2 - t1) / (t1 - t0)
        residual = z2 - z1 - (z1 - z0) * ratio  # as `extrapolation_residuals`, one at a time
        self._abs_residuals.append(abs(residual) / math.sqrt(1.0 + (1.0 + ratio) ** 2 + ratio**2))
        config = self.config
        if len(self._abs_residuals) >= config.min_noise_samples:
            spread = statistics.median(self._abs_residuals)
            self._noise_std_deg = max(MAD_TO_STD * spread, config.min_measurement_std_deg)

    def _clamp(self, t_s: float, value_deg: float | None) -> None:
        """Add an accepted value (None: none) and clamp the estimate to the recent raw range."""
        recent = self._recent
        if value_deg is not None:
            recent.append((t_s, value_deg))
        while len(recent) > 1 and recent[0][0] <= t_s - self.config.clamp_window_s:
            recent.popleft()
        low = min(recent, key=_value)[1]
        high = max(recent, key=_value)[1]
        self._filter.angle = min(max(self._filter.angle, low), high)

    def _estimate(self) -> SmoothedAngle:
        kalman = self._filter
        return SmoothedAngle(
            angle_deg=kalman.angle,
            rate_dps=kalman.rate,
            std_deg=math.sqrt(max(kalman.p00, 0.0)),
        )
