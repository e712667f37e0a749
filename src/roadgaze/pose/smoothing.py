"""Kalman smoother of head yaw: constant-velocity model over filterpy's `KalmanFilter`.

State `[yaw_deg, yaw_rate_dps]`; `dt` comes from the samples' timestamps, so dropped frames and
irregular rates are handled. Without a face the filter only predicts (its variance grows); after
`reinit_gap_s` without an accepted measurement the track is dropped and restarts on the next
face. A measurement whose innovation exceeds `gate_sigma` standard deviations is rejected as an
outlier; `max_rejections` consecutive rejections mean the head really moved, and the track is
re-initialised on the new measurement. Noise levels come from `SmoothingConfig`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from filterpy.common import Q_discrete_white_noise
from filterpy.kalman import KalmanFilter

from roadgaze.config import SmoothingConfig
from roadgaze.types import SmoothedYaw


@dataclass(frozen=True, slots=True)
class SmootherState:
    """A snapshot of the smoother's explicit state (for inspection, logging and tests)."""

    tracking: bool
    """False before the first face and after the track was dropped."""
    t_s: float | None
    """Time of the last update or prediction."""
    last_measurement_t_s: float | None
    """Time of the last accepted (or re-initialising) measurement."""
    yaw_deg: float | None
    yaw_rate_dps: float | None
    yaw_std_deg: float | None
    consecutive_rejections: int
    """Measurements rejected by the gate since the last accepted one."""
    rejected_total: int
    reinitialisations: int
    """Re-starts after a gap or after a run of rejections (the first start is not counted)."""


class YawSmoother:
    """Smooths one stream of raw yaw measurements; call `update` once per frame, in time order."""

    def __init__(self, config: SmoothingConfig | None = None) -> None:
        self.config = config if config is not None else SmoothingConfig()
        self._filter = KalmanFilter(dim_x=2, dim_z=1)
        self._filter.H = np.array([[1.0, 0.0]])
        self._filter.R = np.array([[self.config.measurement_std_deg**2]])
        self._tracking = False
        self._t_s: float | None = None
        self._last_measurement_t_s: float | None = None
        self._consecutive_rejections = 0
        self._rejected_total = 0
        self._reinitialisations = 0
        self._started = False
        self._model_dt_s = math.nan

    def reset(self) -> None:
        """Forget the track; the next measurement starts a new one."""
        self._tracking = False
        self._t_s = None
        self._last_measurement_t_s = None
        self._consecutive_rejections = 0

    @property
    def state(self) -> SmootherState:
        estimate = self._estimate() if self._tracking else None
        return SmootherState(
            tracking=self._tracking,
            t_s=self._t_s,
            last_measurement_t_s=self._last_measurement_t_s,
            yaw_deg=None if estimate is None else estimate.yaw_deg,
            yaw_rate_dps=None if estimate is None else estimate.yaw_rate_dps,
            yaw_std_deg=None if estimate is None else estimate.yaw_std_deg,
            consecutive_rejections=self._consecutive_rejections,
            rejected_total=self._rejected_total,
            reinitialisations=self._reinitialisations,
        )

    def update(self, t_s: float, yaw_deg: float | None) -> SmoothedYaw | None:
        """Advance to `t_s` and fold in `yaw_deg` (None: no face, predict only).

        Returns the estimate at `t_s`, or None when there is no track (before the first face, or
        once `reinit_gap_s` has passed without a measurement). `t_s` must increase strictly while
        a track is running; a NaN or infinite `yaw_deg` counts as no measurement.
        """
        if yaw_deg is not None and not math.isfinite(yaw_deg):
            yaw_deg = None
        if not self._tracking:
            if yaw_deg is None:
                self._t_s = t_s
                return None
            if self._started:
                self._reinitialisations += 1
            self._start(t_s, yaw_deg)
            return self._estimate()
        assert self._t_s is not None and self._last_measurement_t_s is not None
        dt_s = t_s - self._t_s
        if not dt_s > 0:
            raise ValueError(
                f"smoother timestamps must increase: got t_s={t_s} after t_s={self._t_s}"
            )
        if t_s - self._last_measurement_t_s > self.config.reinit_gap_s:
            if yaw_deg is None:
                self._tracking = False
                self._t_s = t_s
                return None
            self._reinitialisations += 1
            self._start(t_s, yaw_deg)
            return self._estimate()
        self._predict(dt_s)
        self._t_s = t_s
        if yaw_deg is None:
            return self._estimate()
        innovation_deg = yaw_deg - float(self._filter.x[0, 0])
        innovation_var = float(self._filter.P[0, 0]) + self.config.measurement_std_deg**2
        if innovation_deg**2 > self.config.gate_sigma**2 * innovation_var:
            self._rejected_total += 1
            self._consecutive_rejections += 1
            if self._consecutive_rejections >= self.config.max_rejections:
                self._reinitialisations += 1
                self._start(t_s, yaw_deg)
            return self._estimate()
        self._filter.update(np.array([[yaw_deg]]))
        self._consecutive_rejections = 0
        self._last_measurement_t_s = t_s
        return self._estimate()

    def _start(self, t_s: float, yaw_deg: float) -> None:
        self._filter.x = np.array([[yaw_deg], [0.0]])
        self._filter.P = np.diag(
            [self.config.initial_std_deg**2, self.config.initial_rate_std_dps**2]
        )
        self._tracking = True
        self._started = True
        self._t_s = t_s
        self._last_measurement_t_s = t_s
        self._consecutive_rejections = 0

    def _predict(self, dt_s: float) -> None:
        if dt_s != self._model_dt_s:  # most streams repeat one dt: build F and Q once
            self._model_dt_s = dt_s
            self._filter.F = np.array([[1.0, dt_s], [0.0, 1.0]])
            self._filter.Q = Q_discrete_white_noise(
                dim=2, dt=dt_s, var=self.config.acceleration_std_dps2**2
            )
        self._filter.predict()

    def _estimate(self) -> SmoothedYaw:
        x = self._filter.x
        return SmoothedYaw(
            yaw_deg=float(x[0, 0]),
            yaw_rate_dps=float(x[1, 0]),
            yaw_std_deg=math.sqrt(max(float(self._filter.P[0, 0]), 0.0)),
        )
