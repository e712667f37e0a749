"""The offline (RTS) pass: better than raw on noisy tracks, bounded, robust to outliers and gaps."""

from __future__ import annotations

import numpy as np
import pytest

from roadgaze.pose.offline import offline_pose, rts_smooth

FPS = 15.0


def drive(seconds: float = 20.0) -> tuple[np.ndarray, np.ndarray]:
    """A head turning between the road and glances: eased 0.5 s turns, holds of 1.5-3 s."""
    t = np.arange(int(seconds * FPS)) / FPS
    targets = [0.0, 40.0, 0.0, -35.0, 0.0, 30.0, 0.0, -40.0, 0.0]
    starts = np.linspace(0.0, seconds - 2.0, len(targets))
    yaw = np.zeros_like(t)
    previous = 0.0
    for start, target in zip(starts, targets, strict=True):
        progress = np.clip((t - start) / 0.5, 0.0, 1.0)
        ease = 0.5 - 0.5 * np.cos(np.pi * progress)
        yaw = np.where(t >= start, previous + (target - previous) * ease, yaw)
        previous = target
    return t, yaw


@pytest.mark.parametrize("noise_deg", [2.0, 4.0])
def test_error_at_most_0_8_of_raw_on_noisy_tracks(noise_deg: float) -> None:
    t, truth = drive()
    ratios = []
    for seed in range(5):
        raw = truth + np.random.default_rng(seed).normal(0.0, noise_deg, truth.shape)
        smoothed = rts_smooth(t, raw)
        ratios.append(np.mean(np.abs(smoothed - truth)) / np.mean(np.abs(raw - truth)))
    assert max(ratios) <= 0.8, ratios


def test_a_clean_track_is_left_as_it_is_and_never_leaves_the_raw_range() -> None:
    t, truth = drive()
    smoothed = rts_smooth(t, truth)
    assert float(np.max(np.abs(smoothed - truth))) < 0.5
    for i in range(len(t)):
        window = truth[np.abs(t - t[i]) <= 0.25]
        assert window.min() - 1e-9 <= smoothed[i] <= window.max() + 1e-9


def test_single_outliers_are_dropped() -> None:
    t, truth = drive()
    raw = truth.copy()
    raw[[40, 41, 120]] += [55.0, 50.0, -60.0]  # spikes of one and two frames
    smoothed = rts_smooth(t, raw)
    assert float(np.max(np.abs(smoothed - truth))) < 1.0


def test_gaps_split_tracks_and_stay_nan() -> None:
    t, truth = drive()
    raw = truth.copy()
    raw[:10] = np.nan  # no face at the start
    raw[100:130] = np.nan  # 2 s without a face: two tracks
    raw[200:205] = np.nan  # a short gap is bridged
    smoothed = rts_smooth(t, raw)
    assert np.all(np.isnan(smoothed[:10])) and np.all(np.isnan(smoothed[100:130]))
    assert np.all(np.isfinite(smoothed[200:205]))
    np.testing.assert_allclose(smoothed[10:100], truth[10:100], atol=0.5)


def test_offline_pose_smooths_both_angles_and_rejects_bad_input() -> None:
    t, truth = drive()
    result = offline_pose(t, truth, -0.5 * truth)
    np.testing.assert_allclose(result.yaw_deg, truth, atol=0.5)
    np.testing.assert_allclose(result.pitch_deg, -0.5 * truth, atol=0.5)
    assert np.all(np.isnan(rts_smooth(t, np.full(t.shape, np.nan))))
    with pytest.raises(ValueError, match="increase"):
        rts_smooth([0.0, 0.0, 1.0], [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="one length"):
        rts_smooth([0.0, 1.0], [1.0])


def test_excursion_is_the_largest_distance_outside_the_nearby_raw_range() -> None:
    from roadgaze.pose import excursion_deg

    t = np.arange(10) / 10.0
    raw = np.array([0.0, 0, 0, 0, 10, 10, 10, 10, 10, 10])
    assert excursion_deg(raw, raw, t) == 0.0
    overshoot = raw.copy()
    overshoot[6] = 13.0  # 3 deg above every raw value within +-0.5 s
    assert excursion_deg(overshoot, raw, t) == pytest.approx(3.0)
    lagging = raw.copy()
    lagging[9] = 4.0  # 6 deg below every raw value within +-0.4 s (all 10)
    assert excursion_deg(lagging, raw, t, half_window_s=0.4) == pytest.approx(6.0)
    assert excursion_deg([np.nan], [1.0], [0.0]) == 0.0
