"""The online angle smoother on synthetic tracks with known truth (noise, steps, gaps, outliers,
the raw-range bound)."""

from __future__ import annotations

import numpy as np
import pytest

from roadgaze.config import SmoothingConfig
from roadgaze.pose.offline import excursion_deg
from roadgaze.pose.smoothing import (
    AngleSmoother,
    ConstantVelocityFilter,
    extrapolation_residuals,
    robust_noise_std_deg,
)

FPS = 30.0


def smooth(
    truth_deg: np.ndarray,
    noise_std_deg: float = 0.0,
    seed: int = 0,
    config: SmoothingConfig | None = None,
    missing: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, AngleSmoother]:
    """Smoothed yaw and std per frame (NaN where there is no track)."""
    rng = np.random.default_rng(seed)
    smoother = AngleSmoother(config or SmoothingConfig())
    yaw, std = np.full(len(truth_deg), np.nan), np.full(len(truth_deg), np.nan)
    for i, value in enumerate(truth_deg):
        measured = None if missing is not None and missing[i] else value
        if measured is not None:
            measured += noise_std_deg * rng.standard_normal()
        result = smoother.update(i / FPS, measured)
        if result is not None:
            yaw[i], std[i] = result.angle_deg, result.std_deg
    return yaw, std, smoother


@pytest.mark.parametrize("seed", range(5))
def test_constant_yaw_noise_is_reduced_by_at_least_40_percent(seed: int) -> None:
    truth = np.full(300, 12.0)
    yaw, _, _ = smooth(truth, noise_std_deg=3.0, seed=seed)
    residual_std = float(np.std(yaw[30:] - truth[30:]))
    assert residual_std <= 0.6 * 3.0
    assert abs(float(np.mean(yaw[30:])) - 12.0) < 0.5


@pytest.mark.parametrize("direction", [+1.0, -1.0])
def test_30_degree_step_settles_within_0_3_s(direction: float) -> None:
    step_frame = 30
    truth = np.r_[np.zeros(step_frame), np.full(60, 30.0 * direction)]
    yaw, _, _ = smooth(truth)
    error = np.abs(yaw - truth)[step_frame:]
    outside = np.nonzero(error > 3.0)[0]  # 10 % of the step
    settle_s = 0.0 if len(outside) == 0 else (outside[-1] + 1) / FPS
    assert settle_s <= 0.3
    assert float(np.max(error[int(0.3 * FPS) :])) < 0.5


def test_noisy_30_degree_step_is_followed_within_0_3_s() -> None:
    truth = np.r_[np.zeros(30), np.full(90, 30.0)]
    for seed in range(5):
        yaw, _, _ = smooth(truth, noise_std_deg=3.0, seed=seed)
        late = yaw[30 + int(0.3 * FPS) :] - truth[30 + int(0.3 * FPS) :]
        assert abs(float(np.mean(late))) < 1.5
        assert float(np.max(np.abs(late))) < 8.0


def test_small_step_inside_the_gate_is_tracked_without_rejection() -> None:
    truth = np.r_[np.zeros(30), np.full(60, 8.0)]
    yaw, _, smoother = smooth(truth)
    assert smoother.state.rejected_total == 0
    assert abs(yaw[-1] - 8.0) < 0.2


def test_one_second_gap_is_bridged_and_reacquired() -> None:
    truth = np.r_[np.full(60, 10.0), np.full(30, 10.0), np.full(60, 20.0)]
    missing = np.zeros(len(truth), bool)
    missing[60:90] = True  # 1 s without a face at 30 fps
    yaw, std, smoother = smooth(truth, missing=missing)
    gap_std = std[60:90]
    assert not np.any(np.isnan(yaw[60:90])), "the gap must be bridged by prediction"
    assert np.all(np.diff(gap_std) > 0), "variance must grow while predicting"
    assert gap_std[-1] > 3 * std[59]
    np.testing.assert_allclose(yaw[60:90], 10.0, atol=0.1)
    assert smoother.state.reinitialisations == 0
    assert abs(yaw[-1] - 20.0) < 0.2, "re-acquired after the gap"
    assert np.all(np.abs(yaw[90 + int(0.3 * FPS) :] - 20.0) < 2.0)


def test_long_gap_drops_the_track_and_restarts_on_the_next_face() -> None:
    config = SmoothingConfig(reinit_gap_s=1.5)
    truth = np.r_[np.full(30, -20.0), np.full(60, 0.0), np.full(10, 35.0)]
    missing = np.zeros(len(truth), bool)
    missing[30:90] = True  # 2 s without a face
    yaw, _, smoother = smooth(truth, missing=missing, config=config)
    last_face_t = 29 / FPS
    dropped = [i for i in range(30, 90) if np.isnan(yaw[i])]
    assert dropped and dropped[0] / FPS - last_face_t > 1.5
    assert all(np.isnan(yaw[i]) for i in range(dropped[0], 90))
    assert yaw[90] == pytest.approx(35.0)
    assert smoother.state.reinitialisations == 1


def test_single_outlier_is_gated_out() -> None:
    truth = np.full(60, 5.0)
    smoother = AngleSmoother()
    results = []
    for i, value in enumerate(truth):
        measured = 60.0 if i == 40 else float(value)
        result = smoother.update(i / FPS, measured)
        assert result is not None
        results.append(result.angle_deg)
    assert abs(results[40] - 5.0) < 0.5
    assert smoother.state.rejected_total == 1
    assert smoother.state.reinitialisations == 0


def test_no_face_before_first_face_gives_none_and_nan_counts_as_no_face() -> None:
    smoother = AngleSmoother()
    assert smoother.update(0.0, None) is None
    assert smoother.update(0.1, float("nan")) is None
    first = smoother.update(0.2, 7.0)
    assert first is not None
    assert first.angle_deg == 7.0
    assert first.rate_dps == 0.0
    assert first.std_deg == pytest.approx(SmoothingConfig().initial_std_deg)


def test_rate_follows_a_ramp() -> None:
    truth = np.linspace(0.0, 60.0, 61)  # 60 deg over 2 s = 30 deg/s... at 30 fps: 1 deg/frame
    smoother = AngleSmoother()
    result = None
    for i, value in enumerate(truth):
        result = smoother.update(i / FPS, float(value))
    assert result is not None
    assert result.rate_dps == pytest.approx(30.0, abs=1.0)
    assert result.angle_deg == pytest.approx(60.0, abs=0.5)


def test_dt_comes_from_timestamps() -> None:
    """The same track sampled at 10 fps and 30 fps ends at the same rate estimate."""
    rates = []
    for fps in (10.0, 30.0):
        smoother = AngleSmoother()
        result = None
        for i in range(int(3 * fps)):
            result = smoother.update(i / fps, 20.0 * i / fps)
        assert result is not None
        rates.append(result.rate_dps)
    np.testing.assert_allclose(rates, 20.0, atol=0.5)


def test_non_increasing_time_raises() -> None:
    smoother = AngleSmoother()
    smoother.update(1.0, 0.0)
    with pytest.raises(ValueError, match="increase"):
        smoother.update(1.0, 0.0)


def eased_turns(fps: float = 15.0) -> tuple[np.ndarray, np.ndarray]:
    """Times and yaws of a drive-like track: holds and 0.5 s cosine-eased turns of 35-40 deg."""
    t = np.arange(int(12 * fps)) / fps
    keys = [(0.0, 0.0), (2.0, 40.0), (5.0, 0.0), (7.0, -35.0), (9.0, 0.0)]
    yaw = np.zeros_like(t)
    previous = 0.0
    for start, target in keys:
        progress = np.clip((t - start) / 0.5, 0.0, 1.0)
        yaw = np.where(
            t >= start, previous + (target - previous) * (0.5 - 0.5 * np.cos(np.pi * progress)), yaw
        )
        previous = target
    return t, yaw


def run_smoother(t: np.ndarray, values: np.ndarray) -> np.ndarray:
    smoother = AngleSmoother()
    out = np.full(len(t), np.nan)
    for i, (t_s, value) in enumerate(zip(t, values, strict=True)):
        result = smoother.update(float(t_s), None if np.isnan(value) else float(value))
        if result is not None:
            out[i] = result.angle_deg
    return out


def test_a_clean_drive_passes_through_without_overshoot() -> None:
    t, truth = eased_turns()
    estimate = run_smoother(t, truth)
    assert float(np.max(np.abs(estimate - truth))) < 0.5  # no lag worth a glance
    assert excursion_deg(estimate, truth, t) == 0.0  # no overshoot, no ringing


@pytest.mark.parametrize("seed", range(3))
def test_a_noisy_drive_is_improved_and_never_leaves_the_raw_range(seed: int) -> None:
    t, truth = eased_turns()
    raw = truth + np.random.default_rng(seed).normal(0.0, 3.0, truth.shape)
    estimate = run_smoother(t, raw)
    assert np.mean(np.abs(estimate - truth)) < 0.9 * np.mean(np.abs(raw - truth))
    for i in range(len(t)):  # causal bound: the accepted raw values of the last 0.5 s
        recent = raw[(t > t[i] - 0.5) & (t <= t[i])]
        assert recent.min() - 1e-9 <= estimate[i] <= recent.max() + 1e-9


def test_jumps_of_an_image_folder_do_not_run_away() -> None:
    """Abrupt poses one after another (an image folder): today's filter extrapolated to -92 deg
    where the raw yaw never went below -57; the estimate must stay within the raw range."""
    values = np.array([0, 15, 30, 45, 60, 0, -15, -30, -45, -57, 0, 30, 60, 67, 0] * 3, float)
    t = np.arange(len(values)) / 30.0
    estimate = run_smoother(t, values)
    assert np.nanmin(estimate) >= values.min() and np.nanmax(estimate) <= values.max()
    assert excursion_deg(estimate, values, t) == 0.0


def test_a_gap_holds_the_last_estimate_instead_of_extrapolating() -> None:
    t = np.arange(60) / 30.0
    values = np.where(t < 1.0, 60.0 * t, np.nan)  # turning at 60 deg/s when the face is lost
    estimate = run_smoother(t, values)
    held = estimate[t >= 1.0]
    np.testing.assert_allclose(held, estimate[np.flatnonzero(t < 1.0)[-1]], atol=1e-9)


def test_noise_is_measured_from_the_series() -> None:
    t = np.arange(600) / 15.0
    rng = np.random.default_rng(0)
    turning = 20.0 * np.sin(t)
    assert robust_noise_std_deg(t, turning + rng.normal(0.0, 3.0, t.size)) == pytest.approx(
        3.0, abs=0.3
    )
    assert robust_noise_std_deg(t, turning) < 0.05  # a smooth turn is not noise
    assert np.isnan(robust_noise_std_deg(t[:2], turning[:2]))
    irregular = np.cumsum(np.random.default_rng(1).uniform(0.03, 0.1, 400))
    residual = extrapolation_residuals(irregular, rng.normal(0.0, 2.0, 400))
    assert float(np.std(residual)) == pytest.approx(2.0, rel=0.15)  # scaled for any dt
    smoother = AngleSmoother()
    for i, value in enumerate(turning + rng.normal(0.0, 3.0, t.size)):
        smoother.update(float(t[i]), float(value))
    assert smoother.state.measurement_std_deg == pytest.approx(3.0, abs=0.8)


@pytest.mark.parametrize("dt_s", [1 / 30, 1 / 15, 0.4])
def test_the_process_noise_is_filterpys_piecewise_white_acceleration(dt_s: float) -> None:
    from filterpy.common import Q_discrete_white_noise

    from roadgaze.pose.smoothing import constant_velocity_model

    transition, noise = constant_velocity_model(dt_s, 300.0)
    np.testing.assert_allclose(noise, Q_discrete_white_noise(dim=2, dt=dt_s, var=300.0**2))
    np.testing.assert_array_equal(transition, [[1.0, dt_s], [0.0, 1.0]])


class FilterpyFilter:
    """filterpy's `KalmanFilter` behind `ConstantVelocityFilter`'s interface: the reference."""

    def __init__(self) -> None:
        from filterpy.kalman import KalmanFilter

        self.kalman = KalmanFilter(dim_x=2, dim_z=1)
        self.kalman.H = np.array([[1.0, 0.0]])

    angle = property(
        lambda self: float(self.kalman.x[0, 0]),
        lambda self, value: self.kalman.x.__setitem__((0, 0), value),
    )
    rate = property(lambda self: float(self.kalman.x[1, 0]))
    p00 = property(lambda self: float(self.kalman.P[0, 0]))

    def start(self, angle: float, angle_var: float, rate_var: float) -> None:
        self.kalman.x = np.array([[angle], [0.0]])
        self.kalman.P = np.diag([angle_var, rate_var])

    def predict(self, dt_s: float, acceleration_var: float) -> None:
        from filterpy.common import Q_discrete_white_noise

        noise = Q_discrete_white_noise(dim=2, dt=dt_s, var=acceleration_var)
        self.kalman.predict(F=np.array([[1.0, dt_s], [0.0, 1.0]]), Q=noise)

    def update(self, measured: float, measurement_var: float) -> None:
        self.kalman.update(np.array([[measured]]), R=np.array([[measurement_var]]))

    def hold(self) -> None:
        self.kalman.x[1, 0] = 0.0

    def restart_rate(self, rate_var: float) -> None:
        self.kalman.x[1, 0] = 0.0
        self.kalman.P[0, 1] = self.kalman.P[1, 0] = 0.0
        self.kalman.P[1, 1] = rate_var


def drive_with_faults(seed: int, count: int = 3000) -> list[tuple[float, float | None]]:
    """Head turns with noise, irregular frame times, short and long gaps, single outliers and
    runs of them (which restart the track)."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.02, 0.12, count))
    yaw = 30.0 * np.sin(t / 1.7) * np.sin(t / 5.3) + rng.normal(0.0, rng.uniform(0.2, 3.0), count)
    values: list[float | None] = [float(v) for v in yaw]
    for start in rng.integers(0, count - 40, 25):
        length = int(rng.integers(1, 30))  # up to 3.5 s: some past `reinit_gap_s`
        values[start : start + length] = [None] * length
    for index in rng.integers(0, count, 40):
        values[index] = float(yaw[index] + rng.choice([-1, 1]) * rng.uniform(20, 80))
    for start in rng.integers(0, count - 10, 6):
        values[start : start + 6] = [float(yaw[start] + 60.0)] * 6
    return list(zip(t.tolist(), values, strict=True))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_float_filter_agrees_with_filterpys_kalman_filter(seed: int) -> None:
    """The smoother with `ConstantVelocityFilter` and with filterpy's `KalmanFilter` in its
    place give the same estimates, frame by frame, through gaps, outliers and restarts."""
    ours, reference = AngleSmoother(), AngleSmoother()
    reference._filter = FilterpyFilter()  # type: ignore[assignment]
    events = 0
    for t_s, value in drive_with_faults(seed):
        mine, theirs = ours.update(t_s, value), reference.update(t_s, value)
        assert (mine is None) == (theirs is None)
        if mine is not None and theirs is not None:
            assert mine.angle_deg == pytest.approx(theirs.angle_deg, rel=1e-9, abs=1e-9)
            assert mine.rate_dps == pytest.approx(theirs.rate_dps, rel=1e-9, abs=1e-7)
            assert mine.std_deg == pytest.approx(theirs.std_deg, rel=1e-9)
        assert ours.state.rejected_total == reference.state.rejected_total
        assert ours.state.reinitialisations == reference.state.reinitialisations
    events = ours.state.rejected_total + ours.state.reinitialisations
    assert ours.state.rejected_total > 20 and ours.state.reinitialisations > 5 and events > 30


def test_the_float_filters_matrices_are_filterpys() -> None:
    """One predict and one update from a random state, against filterpy's matrix products."""
    rng = np.random.default_rng(4)
    for _ in range(200):
        ours, reference = ConstantVelocityFilter(), FilterpyFilter()
        angle, angle_var, rate_var = rng.uniform(-50, 50), rng.uniform(0.1, 50), rng.uniform(1, 900)
        ours.start(angle, angle_var, rate_var)
        reference.start(angle, angle_var, rate_var)
        dt_s, var = rng.uniform(0.01, 0.5), rng.uniform(1.0, 1e6)
        ours.predict(dt_s, var)
        reference.predict(dt_s, var)
        measured, measurement_var = rng.uniform(-60, 60), rng.uniform(0.01, 25)
        ours.update(measured, measurement_var)
        reference.update(measured, measurement_var)
        covariance = [[ours.p00, ours.p01], [ours.p01, ours.p11]]
        np.testing.assert_allclose([ours.angle, ours.rate], reference.kalman.x[:, 0], rtol=1e-12)
        np.testing.assert_allclose(covariance, reference.kalman.P, rtol=1e-9, atol=1e-12)
