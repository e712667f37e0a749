"""The camera's side: sensor noise, a covered lens, and the night picture (the condition suite's
one definition of an infrared camera, `ir_grey`)."""

from __future__ import annotations

import numpy as np

from roadgaze.evaluation.conditions import ir_grey
from roadgaze.synth.effects import NoiseBank, covered_frame, night


def test_night_is_the_condition_suites_infrared_picture_in_three_equal_channels() -> None:
    rng = np.random.default_rng(0)
    day = rng.integers(0, 256, (48, 64, 3), dtype=np.uint8)
    dark = night(day, np.random.default_rng(5))
    assert dark.shape == day.shape and dark.dtype == np.uint8
    assert np.array_equal(dark[..., 0], dark[..., 1]) and np.array_equal(dark[..., 1], dark[..., 2])
    assert np.array_equal(dark[..., 0], ir_grey(day, np.random.default_rng(5)))
    assert abs(float(dark.mean()) - 120.0) < 3.0 and dark.std() < 0.6 * day.std()
    assert not np.array_equal(dark, night(day, np.random.default_rng(6)))  # fresh noise each frame


def test_noise_differs_frame_to_frame_and_a_covered_lens_is_dark() -> None:
    flat = np.full((32, 32, 3), 128, dtype=np.uint8)
    bank = NoiseBank((32, 32), np.random.default_rng(1))
    first, second = bank(flat), bank(flat)
    assert not np.array_equal(first, second) and abs(float(first.mean()) - 128.0) < 1.0
    lens = covered_frame((32, 24), np.random.default_rng(1))
    assert lens.shape == (24, 32, 3) and lens.mean() < 10.0
