"""The front end for cabin images: the per-frame decision, the tone curve, and the detector
wrapper's second look, hold and wait in a stream (fake detectors: no MediaPipe)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from fakes import ListSource, face_at
from roadgaze.landmarks.front_end import (
    DARK_MEAN,
    FLAT_SPREAD,
    HOLD_S,
    RETRY_STEP_S,
    RETRY_WAIT_S,
    FrontEndDetector,
    assess,
    enhance,
    tone_curve,
    with_front_end,
)
from roadgaze.pipeline import Pipeline
from roadgaze.types import Detection


def scene(low: float, high: float, channels: int = 3) -> np.ndarray:
    """A 480x640 frame whose levels spread evenly from `low` to `high`."""
    ramp = np.linspace(low, high, 640)[None, :] * np.ones((480, 1))
    image = np.rint(ramp).astype(np.uint8)
    return np.repeat(image[:, :, None], channels, axis=2) if channels > 1 else image


GOOD, DARK, FLAT = scene(10, 245), scene(5, 60), scene(90, 170)


def test_the_decision_picks_dark_and_flat_frames_only() -> None:
    good, dark, flat = assess(GOOD), assess(DARK), assess(FLAT)
    assert good.mean == pytest.approx(127.5, abs=2) and good.spread == pytest.approx(212, abs=3)
    assert not good.needs_curve
    assert dark.mean < DARK_MEAN and dark.needs_curve
    assert flat.spread < FLAT_SPREAD and flat.mean > DARK_MEAN and flat.needs_curve
    assert assess(scene(90, 170, channels=1)) == flat  # grey frames read the same
    assert assess(np.dstack([FLAT, FLAT[:, :, :1]])) == flat  # BGRA


def test_the_curve_stretches_the_range_and_centres_the_mean() -> None:
    levels = assess(DARK)
    curve = tone_curve(levels)
    assert curve.shape == (256,) and curve.dtype == np.uint8
    assert np.all(np.diff(curve.astype(int)) >= 0)
    assert curve[int(levels.low)] == 0 and curve[int(levels.high)] == 255
    assert curve[round(levels.mean)] == pytest.approx(128, abs=8)
    out = enhance(DARK)
    assert out.shape == DARK.shape[:2] and out.mean() == pytest.approx(128, abs=10)
    np.testing.assert_array_equal(enhance(DARK[:, :, 0]), out)  # grey in, the same out


class FussyDetector:
    """Fake detector with only `detect`: a face when the frame's spread is wide enough (or
    always/never), recording what it was given."""

    def __init__(self, min_spread: float = 150.0) -> None:
        self.min_spread = min_spread
        self.seen: list[tuple[float | None, np.ndarray]] = []
        self.closed = False

    def detect(self, image: np.ndarray, t_s: float | None = None) -> Detection:
        if t_s is not None and self.seen:
            assert t_s > (self.seen[-1][0] or -1.0)
        self.seen.append((t_s, image))
        if float(image.max()) - float(image.min()) < self.min_spread:
            return Detection(faces=(), driver_index=None)
        return Detection(faces=(face_at(5.0),), driver_index=0)

    def close(self) -> None:
        self.closed = True


def test_off_is_the_detector_itself_and_closing_closes_it() -> None:
    inner = FussyDetector()
    assert with_front_end(inner, "off") is inner
    wrapped = with_front_end(inner, "auto")
    assert isinstance(wrapped, FrontEndDetector) and wrapped.min_spread == 150.0  # delegated
    wrapped.close()
    assert inner.closed


@pytest.mark.parametrize(
    ("mode", "frame", "curved"),
    [("auto", GOOD, False), ("auto", DARK, True), ("auto", FLAT, True), ("always", GOOD, True)],
    ids=["good-untouched", "dark-curved", "flat-curved", "always"],
)
def test_stills_get_the_curve_the_mode_asks_for(mode: str, frame: np.ndarray, curved: bool) -> None:
    inner = FussyDetector()
    detection = FrontEndDetector(inner, mode).detect(frame)  # type: ignore[arg-type]
    assert len(inner.seen) == 1 and detection.driver is not None
    assert np.array_equal(inner.seen[0][1], frame) is not curved


def test_grey_frames_flow_through_as_grey() -> None:
    inner = FussyDetector()
    detection = FrontEndDetector(inner).detect(FLAT[:, :, 0], 0.0)
    assert detection.driver is not None and inner.seen[0][1].ndim == 2


def test_a_still_without_a_face_gets_a_second_look() -> None:
    inner = FussyDetector(min_spread=240.0)  # only the stretched frame has such a spread
    detection = FrontEndDetector(inner).detect(scene(10, 200))
    assert detection.driver is not None and len(inner.seen) == 2
    never = FussyDetector(min_spread=300.0)
    assert FrontEndDetector(never).detect(GOOD).driver is None and len(never.seen) == 2


def test_a_stream_holds_the_curve_after_a_second_look_found_the_face() -> None:
    inner = FussyDetector(min_spread=240.0)
    front_end = FrontEndDetector(inner)
    frame, dt = scene(10, 200), 0.1
    times = [i * dt for i in range(int(HOLD_S / dt) + 3)]
    found = [front_end.detect(frame, t).driver is not None for t in times]
    assert all(found)
    calls = [t for t, _ in inner.seen]
    # Frame 0: a miss and a second look just after it; then one curved call a frame until the
    # hold ends, where the untouched frame misses again and is looked at twice.
    assert calls[:3] == [0.0, pytest.approx(RETRY_STEP_S), dt]
    held = round(HOLD_S / dt)
    assert len(calls) == len(times) + 2 and calls.count(times[held]) == 1
    assert calls[held + 2] == pytest.approx(times[held] + RETRY_STEP_S)


def test_a_stream_without_a_face_looks_again_once_a_wait() -> None:
    inner = FussyDetector(min_spread=300.0)
    front_end = FrontEndDetector(inner)
    times = [i * 0.1 for i in range(25)]  # 2.5 s
    for t in times:
        assert front_end.detect(GOOD, t).driver is None
    extra = len(inner.seen) - len(times)
    assert extra == int(times[-1] // RETRY_WAIT_S) + 1  # at 0, 1.0 and 2.0 s


def test_the_pipeline_times_the_front_end_as_its_own_stage() -> None:
    inner = FussyDetector(min_spread=0.0)
    pipeline = Pipeline(FrontEndDetector(inner, "always"))
    summary = pipeline.run(ListSource(12))
    assert summary.frames == 12 and summary.frames_with_face == 12
    assert summary.stages["enhance"].median_ms > 0.0
    off = Pipeline(FussyDetector(min_spread=0.0)).run(ListSource(12))
    assert off.stages["enhance"].median_ms == 0.0


def test_an_enhanced_still_without_a_face_is_looked_at_untouched() -> None:
    inner = FussyDetector(min_spread=300.0)
    detector = FrontEndDetector(inner)
    assert detector.detect(DARK).driver is None
    assert [image.ndim for _, image in inner.seen] == [2, 3]  # enhanced (grey), then as it came
    np.testing.assert_array_equal(inner.seen[1][1], DARK)


def noisy(frame: np.ndarray, std: float = 6.0, seed: int = 0) -> np.ndarray:
    """`frame` with Gaussian sensor noise of `std` levels."""
    values = frame + np.random.default_rng(seed).normal(0.0, std, frame.shape)
    return np.clip(np.rint(values), 0, 255).astype(np.uint8)


def grain(image: np.ndarray) -> float:
    """The noise left in a frame whose rows are all alike (ramps, steps): the standard deviation
    of its levels about their column's mean."""
    values = image.astype(float)
    return float((values - values.mean(axis=0)).std())


class SteppedDetector:
    """Fake detector with the loop's steps and the landmarker's `retry_rejected`: a face when
    `accepts(image)`, recording (t_s, image, retry_rejected) per inference."""

    def __init__(self, accepts: Callable[[np.ndarray], bool]) -> None:
        self.accepts = accepts
        self.seen: list[tuple[float | None, np.ndarray, bool]] = []

    def prepare(self, image: np.ndarray) -> np.ndarray:
        return image

    def infer(
        self, image: np.ndarray, t_s: float | None = None, *, retry_rejected: bool = False
    ) -> Detection:
        self.seen.append((t_s, image, retry_rejected))
        if not self.accepts(image):
            return Detection(faces=(), driver_index=None)
        return Detection(faces=(face_at(5.0),), driver_index=0)

    def measure(self, inference: Detection) -> Detection:
        return inference

    def detect(self, image: np.ndarray, t_s: float | None = None) -> Detection:
        return self.measure(self.infer(self.prepare(image), t_s))

    def close(self) -> None:
        pass


NOISY_FLAT = noisy(FLAT[:, :, 0])


def test_strong_smoothing_flattens_the_noise_and_keeps_an_edge() -> None:
    """On a flat noisy frame with a step, the strong (bilateral) version keeps the step sharp
    where the Gaussian spreads it, and leaves less grain; both stretch the levels alike."""
    step = np.where(np.arange(640) < 320, 110, 150)[None, :] * np.ones((480, 1))
    frame = noisy(step)
    gaussian, strong = enhance(frame), enhance(frame, strong=True)
    assert grain(strong) < 0.95 * grain(gaussian)
    rows = slice(100, 380)  # the step between columns 319 and 320: kept in one pixel
    rise = lambda image: float(image[rows, 320].mean() - image[rows, 319].mean())  # noqa: E731
    assert rise(strong) > 120 > 2.0 * rise(gaussian)
    assert abs(float(strong.mean()) - float(gaussian.mean())) < 3.0
    clean = enhance(FLAT)  # no noise: no smoothing, the strong version is the same
    np.testing.assert_array_equal(enhance(FLAT, strong=True), clean)


def test_a_noisy_hard_still_is_looked_at_curved_then_strong_with_retries() -> None:
    inner = SteppedDetector(lambda image: False)
    assert FrontEndDetector(inner).detect(NOISY_FLAT).driver is None  # type: ignore[arg-type]
    images = [image for _, image, _ in inner.seen]
    assert len(images) == 2 and [retry for _, _, retry in inner.seen] == [True, True]
    np.testing.assert_array_equal(images[0], enhance(NOISY_FLAT))
    np.testing.assert_array_equal(images[1], enhance(NOISY_FLAT, strong=True))
    clean = SteppedDetector(lambda image: False)  # no noise: as it came instead of strong
    FrontEndDetector(clean).detect(FLAT)  # type: ignore[arg-type]
    assert [(image.ndim, retry) for _, image, retry in clean.seen] == [(2, True), (3, False)]
    good = SteppedDetector(lambda image: False)  # a good frame: as before, no retries
    FrontEndDetector(good).detect(GOOD)  # type: ignore[arg-type]
    assert [(image.ndim, retry) for _, image, retry in good.seen] == [(3, False), (2, False)]


def test_a_stream_holds_the_strong_version_and_waits_without_a_face() -> None:
    strong = enhance(NOISY_FLAT, strong=True)
    smooth = lambda image: np.array_equal(image, strong)  # noqa: E731
    inner = SteppedDetector(smooth)
    front_end = FrontEndDetector(inner)  # type: ignore[arg-type]
    assert front_end.detect(NOISY_FLAT, 0.0).driver is not None
    assert [t for t, _, _ in inner.seen] == [0.0, pytest.approx(RETRY_STEP_S)]
    for t_s in (0.1, 0.2):  # held: the strong version at once
        assert front_end.detect(NOISY_FLAT, t_s).driver is not None
    assert len(inner.seen) == 4 and smooth(inner.seen[-1][1])
    never = SteppedDetector(lambda image: False)
    front_end = FrontEndDetector(never)  # type: ignore[arg-type]
    for index in range(12):
        front_end.detect(NOISY_FLAT, index * 0.1)
    # Two looks with retries at 0 s and at 1 s, one look without them in between.
    retried = [round(t or 0.0, 1) for t, _, retry in never.seen if retry]
    assert retried == [0.0, 0.0, 1.0, 1.0] and len(never.seen) == 12 + 2


@pytest.fixture(scope="module")
def ir_astronaut() -> np.ndarray:
    """skimage's astronaut as a flat, noisy near-infrared frame (one grey channel)."""
    import cv2
    from skimage import data as skimage_data

    from roadgaze.evaluation.conditions import ir_grey

    bgr = cv2.cvtColor(skimage_data.astronaut(), cv2.COLOR_RGB2BGR)
    return ir_grey(bgr, np.random.default_rng(0), contrast=0.3, noise_std=8.0)


def test_real_mediapipe_finds_an_ir_face_only_through_the_front_end(
    ir_astronaut: np.ndarray,
) -> None:
    from roadgaze.config import Config, ModelConfig
    from roadgaze.landmarks.landmarker import MediaPipeLandmarker
    from roadgaze.landmarks.model_store import resolve_model

    model = resolve_model(ModelConfig(), environ={})
    assert ir_astronaut.ndim == 2
    with MediaPipeLandmarker(Config().landmarks, model) as landmarker:
        assert landmarker.detect(ir_astronaut).driver is None
        still = FrontEndDetector(landmarker).detect(ir_astronaut).driver
    assert still is not None and 80 < still.x_right_px - still.x_left_px < 110
    with FrontEndDetector(MediaPipeLandmarker(Config().landmarks, model, video=True)) as stream:
        found = [stream.detect(ir_astronaut, i / 15).driver is not None for i in range(5)]
    assert all(found)


@pytest.mark.parametrize("shape", [(4, 4), (1, 1), (4, 4, 3), (7, 1, 3), (1, 300)])
def test_a_frame_too_small_for_a_noise_row_is_assessed_and_enhanced(
    shape: tuple[int, ...],
) -> None:
    """A damaged image decoded to a few pixels (a truncated JPEG) still gets its figures and its
    curve: no noise row to measure, so no noise (an exception here stopped `eval` on one file)."""
    frame = np.zeros(shape, np.uint8)
    levels = assess(frame, noise=True)
    assert levels.noise == 0.0 and levels.mean == 0.0
    assert enhance(frame).shape[:2] == shape[:2]
