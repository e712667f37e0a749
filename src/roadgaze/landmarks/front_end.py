"""The front end for cabin images: contrast normalisation where a frame needs it, before the
landmark detector (any engine).

Per frame a cheap look decides (`assess`, about 0.1 ms at 640x480): a sparse grid of pixels
(every `GRID_STEP`-th row and column; a colour frame's green channel) gives the mean level and
the spread (95th minus 5th percentile), and the differences of neighbouring pixels along a few
rows give the sensor noise. A frame that is dark (mean below `DARK_MEAN`) or flat (spread below
`FLAT_SPREAD`), as a near-infrared camera's or a night cabin's, is enhanced (`enhance`): its
luminance, smoothed by a 5x5 Gaussian when it is noisy (MediaPipe's face detector loses
faces in sensor noise long before it loses them in low contrast), through a tone curve that
stretches its 1st-99th percentile range to 0-255 with the gamma that puts its mean at mid grey
(one lookup table, `cv2.LUT`). The enhanced frame is grey (one channel). A good frame goes to the
detector untouched: the decision is all it costs.

`landmarks.enhance`:
- `auto` (default): the rule above; and when the detector finds no face, the frame is looked at
  again in its other versions (`FrontEndDetector.looks`: a noisy hard frame ever more smoothly);
- `off`: frames go to the detector as they come;
- `always`: every frame is enhanced.

The rule and its constants were chosen on Pointing'04 subjects 1-10 with the condition suite,
the further looks leaving one subject out at a time (docs/conditions.md).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from roadgaze.types import ClosesOnExit, Detection, LandmarkDetector

EnhanceMode = Literal["auto", "off", "always"]
GRID_STEP = 8
"""The decision looks at every this many rows and columns (4,800 pixels of a 640x480 frame)."""
NOISE_ROW_STEP = 16
"""The noise is measured along every this many rows (30 rows of a 640x480 frame)."""
DARK_MEAN = 70.0
"""A frame whose mean luminance (0-255) is below this is dark."""
FLAT_SPREAD = 120.0
"""A frame whose luminance spread (95th - 5th percentile) is below this is flat."""
NOISY_LEVELS = 2.0
"""A frame whose measured noise is this many grey levels or more is smoothed before its curve
(clean camera frames and compressed video measure about 1)."""
SMOOTHING_KERNEL_PX = 5
"""A noisy frame is smoothed by a Gaussian this many pixels wide (OpenCV's sigma for the size,
1.1 px: white noise falls about fourfold). On the dev data it kept more faces, a better yaw and
fewer false closures than a 5x5 or 7x7 box (docs/conditions.md)."""
GAMMA_RANGE = (0.35, 2.5)
"""The gamma of the curve is kept within this range."""
STRONG_DIAMETER_PX = 9
"""The `strong` smoothing: a bilateral filter over this many pixels across, ..."""
STRONG_SPACE_SIGMA_PX = 3.0
"""... weighting pixels by distance with this standard deviation ..."""
STRONG_COLOUR_SIGMA = 2.0
"""... and by the difference of their levels with this many times the measured noise: the
noise is flattened, a face's edges (several noise levels high) are kept."""
WIDE_DIAMETER_PX = 13
"""The `wide` look, the last: a bilateral filter this many pixels across, ..."""
WIDE_SPACE_SIGMA_PX = 5.0
"""... with this spatial standard deviation ..."""
WIDE_COLOUR_SIGMA = 3.0
"""... and this many times the measured noise, then at the coarse scale (`COARSE_FACTOR`): for
noise too strong for `strong` (on the dev subjects under harder IR-like and dark transforms than
the suite's, docs/conditions.md)."""
COARSE_FACTOR = 2
"""The `coarse` look, after `strong`: the `strong` version averaged over blocks of this many
pixels square and scaled back (the frame at a coarser scale: noise falls by this factor again)."""
RETRY_STEP_S = 1e-4
"""In a stream, each further look at a frame is passed as taken this much later than the one
before (the detector needs strictly increasing times)."""
HOLD_S = 2.0
"""In a stream, after a second look found the face, frames take its version for this long."""
RETRY_WAIT_S = 1.0
"""In a stream, after a second look found no face, the next one waits this long."""


def _has_faces(inference: Any) -> bool:
    """Whether a detector's inference (or `Detection`) holds a face."""
    return len(getattr(inference, "faces", ())) > 0


@dataclass(frozen=True, slots=True)
class FrameLevels:
    """The luminance figures of a frame's sparse grid (0-255)."""

    mean: float
    spread: float
    """95th minus 5th percentile."""
    low: float
    high: float
    """The 1st and 99th percentiles (the stretched range)."""
    noise: float = 0.0
    """The sensor noise's standard deviation (grey levels), from the differences of
    neighbouring pixels along every `NOISE_ROW_STEP`-th row (their median absolute value, which
    edges hardly move, times 1.4826 / sqrt(2))."""

    @property
    def relative_noise(self) -> float:
        """`noise` over `spread`: how much of the frame's contrast is noise."""
        return self.noise / max(self.spread, 1.0)

    @property
    def needs_curve(self) -> bool:
        """Dark or flat: the frame gets a tone curve in `auto` mode."""
        return self.mean < DARK_MEAN or self.spread < FLAT_SPREAD


def _luminance(image: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
    """A frame's luminance (OpenCV's weights); a grey frame itself."""
    import cv2

    if image.ndim == 2:
        return image
    if image.shape[2] == 1:
        return image[:, :, 0]
    code = cv2.COLOR_BGRA2GRAY if image.shape[2] == 4 else cv2.COLOR_BGR2GRAY
    return np.asarray(cv2.cvtColor(np.ascontiguousarray(image), code), np.uint8)


def _median_of_counts(counts: npt.NDArray[np.int64]) -> float:
    return float(np.searchsorted(np.cumsum(counts), (counts.sum() + 1) // 2))


def _decision_channel(image: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
    """The channel the decision reads: the grey frame, or a colour frame's green (the largest
    share of luminance; no conversion)."""
    return (
        image[:, :, 1]
        if image.ndim == 3 and image.shape[2] >= 3
        else image.reshape(image.shape[:2])
    )


def assess(image: npt.NDArray[np.uint8], noise: bool = False) -> FrameLevels:
    """The level figures of a grey, BGR or BGRA uint8 frame, from its sparse grid (the green
    channel of a colour frame); with `noise`, also the noise (the decision does not need it)."""
    channel = _decision_channel(image)
    grid = channel[::GRID_STEP, ::GRID_STEP]
    counts = np.bincount(grid.ravel(), minlength=256).astype(np.float64)
    cumulative = np.cumsum(counts) / max(float(counts.sum()), 1.0)
    p1, p5, p95, p99 = np.searchsorted(cumulative, (0.01, 0.05, 0.95, 0.99))
    mean = float(np.dot(counts, np.arange(256)) / max(float(counts.sum()), 1.0))
    noise_std = 0.0
    rows = np.ascontiguousarray(channel[NOISE_ROW_STEP // 2 :: NOISE_ROW_STEP])
    if noise and rows.shape[0] > 0 and rows.shape[1] > 1:  # a frame too small has no noise row
        import cv2

        steps = cv2.absdiff(rows[:, 1:], rows[:, :-1]).ravel()
        noise_std = 1.4826 * _median_of_counts(np.bincount(steps, minlength=256)) / np.sqrt(2.0)
    return FrameLevels(
        mean=mean, spread=float(p95 - p5), low=float(p1), high=float(p99), noise=noise_std
    )


def tone_curve(levels: FrameLevels) -> npt.NDArray[np.uint8]:
    """The (256,) lookup table: the 1st-99th percentile range stretched to 0-255, then the gamma
    (within `GAMMA_RANGE`) that maps the stretched mean to mid grey."""
    low, high = levels.low, max(levels.high, levels.low + 1.0)
    stretched_mean = min(max((levels.mean - low) / (high - low), 0.02), 0.98)
    gamma = float(np.clip(np.log(0.5) / np.log(stretched_mean), *GAMMA_RANGE))
    ramp = np.clip((np.arange(256, dtype=np.float64) - low) / (high - low), 0.0, 1.0)
    return np.asarray(np.rint(255.0 * ramp**gamma), np.uint8)


Version = Literal["plain", "curve", "strong", "coarse", "wide"]
"""A frame's version for the detector: as it came, `enhance`d, or `enhance`d with a stronger
smoothing (`strong`, `coarse`, `wide`: further looks at a noisy hard frame)."""
BILATERAL: dict[Version, tuple[int, float, float]] = {
    "strong": (STRONG_DIAMETER_PX, STRONG_SPACE_SIGMA_PX, STRONG_COLOUR_SIGMA),
    "coarse": (STRONG_DIAMETER_PX, STRONG_SPACE_SIGMA_PX, STRONG_COLOUR_SIGMA),
    "wide": (WIDE_DIAMETER_PX, WIDE_SPACE_SIGMA_PX, WIDE_COLOUR_SIGMA),
}
"""The versions smoothed by a bilateral filter: (diameter px, space sigma px, colour sigma in
noise levels)."""
COARSE: frozenset[Version] = frozenset(("coarse", "wide"))
"""The versions then averaged over `COARSE_FACTOR` pixels square and scaled back."""


def _enhanced(
    image: npt.NDArray[np.uint8], version: Version = "curve"
) -> tuple[npt.NDArray[np.uint8], FrameLevels]:
    """`enhance`, and the levels and noise of the frame's luminance."""
    import cv2

    grey = _luminance(image)
    levels = assess(grey, noise=True)  # on the luminance (the decision read a colour's green)
    if levels.noise >= NOISY_LEVELS and version in BILATERAL:
        diameter, space_sigma, colour_sigma = BILATERAL[version]
        sigma_colour = colour_sigma * levels.noise
        grey = np.asarray(cv2.bilateralFilter(grey, diameter, sigma_colour, space_sigma), np.uint8)
    elif levels.noise >= NOISY_LEVELS:
        size = (SMOOTHING_KERNEL_PX, SMOOTHING_KERNEL_PX)
        grey = np.asarray(cv2.GaussianBlur(grey, size, 0), np.uint8)
    curved = np.asarray(cv2.LUT(grey, tone_curve(levels)), np.uint8)
    if version in COARSE and levels.noise >= NOISY_LEVELS:
        height, width = curved.shape
        small = (max(width // COARSE_FACTOR, 1), max(height // COARSE_FACTOR, 1))
        shrunk = cv2.resize(curved, small, interpolation=cv2.INTER_AREA)
        curved = np.asarray(cv2.resize(shrunk, (width, height), interpolation=cv2.INTER_LINEAR))
    return curved, levels


def enhance(
    image: npt.NDArray[np.uint8], strong: bool = False, version: Version | None = None
) -> npt.NDArray[np.uint8]:
    """`image` as the detector should see it, in one grey channel (a dark frame's colour carries
    little, and one channel costs a third): its luminance, smoothed when its noise is
    `NOISY_LEVELS` or more, through its tone curve (the levels and the noise measured on the
    luminance). The smoothing is a `SMOOTHING_KERNEL_PX` Gaussian, or with `strong` (`version`
    "strong") an edge-preserving bilateral filter (`STRONG_DIAMETER_PX`; about 30 times the
    Gaussian's CPU, so only for a further look); `version` "coarse" the strong one at half the
    scale (`COARSE_FACTOR`), "wide" a wider one (`WIDE_DIAMETER_PX`) at half the scale. A frame
    without noise gets the curve alone in every version."""
    return _enhanced(image, version or ("strong" if strong else "curve"))[0]


@dataclass(frozen=True, slots=True)
class FrontEndPrepared:
    """A frame after the front end, prepared for the wrapped detector."""

    image: npt.NDArray[np.uint8]
    """The frame as it came (a further look makes another version of it)."""
    inner: Any
    """What the wrapped detector's `prepare` made of the frame in `version`."""
    version: Version
    enhance_ms: float
    hard: bool = False
    """Dark or flat (`FrameLevels.needs_curve`), in `auto` mode: the frame gets the further
    looks of a hard frame."""
    noisy: bool = False
    """A hard frame's noise is `NOISY_LEVELS` or more (a `strong` look differs from `curve`)."""

    @property
    def enhanced(self) -> bool:
        return self.version != "plain"


@dataclass(frozen=True, slots=True)
class FrontEndInference:
    """The wrapped detector's inference of a frame and what the front end did to it."""

    inner: Any
    enhanced: bool
    """The faces were found in an enhanced version of the frame."""
    prepare_ms: float
    """The front end's time in `prepare` (the decision and the curve)."""
    retry_ms: float = 0.0
    """The enhancement of a held or further look in `infer` (not the further inferences)."""
    version: Version = "plain"
    """The version the faces were found in (the first look's without a face)."""

    @property
    def faces(self) -> Any:
        return getattr(self.inner, "faces", ())


class FrontEndDetector(ClosesOnExit):
    """A `LandmarkDetector` that puts the front end before another detector (any engine).

    It has the `prepare`/`infer`/`measure` steps the loop runs on its threads
    (`roadgaze.pipeline.steps`): the decision and the curve run in `prepare` (the decode thread
    for a file), further looks in `infer`. A wrapped detector with only `detect` gets the front
    end too. Closing it closes the wrapped detector.
    """

    def __init__(self, detector: LandmarkDetector, mode: EnhanceMode = "auto") -> None:
        self.detector = detector
        self.mode = mode
        self._prepare = getattr(detector, "prepare", None)
        self._infer = getattr(detector, "infer", None)
        self._measure = getattr(detector, "measure", None)
        self._steps = None not in (self._prepare, self._infer, self._measure)
        self._retries = self._steps and "retry_rejected" in _parameters(self._infer)
        self._hold: Version = "plain"
        self._hold_until_s = -math.inf
        self._retry_after_s = -math.inf

    def __getattr__(self, name: str) -> Any:
        """The wrapped detector's other attributes (`video`, `face_mode`, ...)."""
        detector = self.__dict__.get("detector")
        if detector is None:
            raise AttributeError(name)
        return getattr(detector, name)

    def _inner_prepare(self, image: npt.NDArray[np.uint8]) -> Any:
        return self._prepare(image) if self._steps and self._prepare is not None else image

    def prepare(self, image: npt.NDArray[np.uint8]) -> FrontEndPrepared:
        """The frame, enhanced when the mode and the rule say so, prepared for the detector."""
        start = time.perf_counter()
        hard = self.mode == "auto" and assess(image).needs_curve
        if hard or self.mode == "always":
            image_in, levels = _enhanced(image)
            version: Version = "curve"
        else:
            image_in, levels, version = image, None, "plain"
        noisy = hard and levels is not None and levels.noise >= NOISY_LEVELS
        spent_ms = (time.perf_counter() - start) * 1e3
        inner = self._inner_prepare(image_in)
        return FrontEndPrepared(image, inner, version, spent_ms, hard, noisy)

    def _run(self, inner: Any, t_s: float | None, retry_rejected: bool = False) -> Any:
        if self._retries and self._infer is not None:
            return self._infer(inner, t_s, retry_rejected=retry_rejected)
        if self._steps and self._infer is not None:
            return self._infer(inner, t_s)
        return self.detector.detect(inner, t_s)

    @staticmethod
    def looks(prepared: FrontEndPrepared) -> tuple[Version, ...]:
        """The versions `auto` tries in turn until one has a face: a good frame as it came, then
        enhanced; a hard one enhanced, then (when noisy) enhanced ever more smoothly, `strong`,
        `coarse`, `wide` (the dearest last), else as it came."""
        if not prepared.hard:
            return ("plain", "curve")
        return ("curve", "strong", "coarse", "wide") if prepared.noisy else ("curve", "plain")

    def infer(self, prepared: FrontEndPrepared, t_s: float | None = None) -> FrontEndInference:
        """The detector on the prepared frame. In `auto` mode, when it finds no face, on the
        frame's further versions in turn (`looks`; the n-th at `t_s + n * RETRY_STEP_S` in a
        stream); on a hard frame the detector is also asked to look again at a face its landmark
        model rejected (`retry_rejected`).

        In a stream a further look that found the face makes the next `HOLD_S` seconds of frames
        take its version first (no further inference each); when none found one, the next
        further looks (and retries) wait `RETRY_WAIT_S`, so a stream without a face costs one
        round of them a second.
        """
        if self.mode != "auto":
            return FrontEndInference(
                self._run(prepared.inner, t_s), prepared.enhanced, prepared.enhance_ms
            )
        looks = self.looks(prepared)
        if t_s is not None and t_s < self._hold_until_s and self._hold in looks:
            looks = (self._hold, *(look for look in looks if look != self._hold))
        waiting = t_s is not None and t_s < self._retry_after_s
        first: Any = None
        retry_ms = 0.0
        for index, version in enumerate(looks[:1] if waiting else looks):
            inner = prepared.inner
            if version != prepared.version:
                inner, spent_ms = self._version_of(prepared, version)
                retry_ms += spent_ms
            retry = prepared.hard and version != "plain" and not waiting
            inference = self._run(inner, None if t_s is None else t_s + index * RETRY_STEP_S, retry)
            if _has_faces(inference):
                if index > 0 and t_s is not None:
                    self._hold, self._hold_until_s = version, t_s + HOLD_S
                return FrontEndInference(
                    inference, version != "plain", prepared.enhance_ms, retry_ms, version
                )
            first = inference if first is None else first
        if t_s is not None and not waiting:
            self._retry_after_s = t_s + RETRY_WAIT_S
        return FrontEndInference(
            first, looks[0] != "plain", prepared.enhance_ms, retry_ms, looks[0]
        )

    def _version_of(self, prepared: FrontEndPrepared, version: Version) -> tuple[Any, float]:
        """The frame prepared in `version`, and the enhancement's time (ms)."""
        if version == "plain":
            return self._inner_prepare(prepared.image), 0.0
        start = time.perf_counter()
        image = enhance(prepared.image, version=version)
        return self._inner_prepare(image), (time.perf_counter() - start) * 1e3

    def measure(self, inference: FrontEndInference) -> Detection:
        """The wrapped detector's measurement of the inference."""
        if self._steps and self._measure is not None:
            return self._measure(inference.inner)  # type: ignore[no-any-return]
        return inference.inner  # type: ignore[no-any-return]

    def detect(self, image: npt.NDArray[np.uint8], t_s: float | None = None) -> Detection:
        """`prepare`, `infer` and `measure` in a row; the wrapped detector's errors."""
        return self.measure(self.infer(self.prepare(image), t_s))

    def close(self) -> None:
        self.detector.close()


def _parameters(function: Any) -> frozenset[str]:
    """The names of a callable's parameters (none when it has no signature)."""
    import inspect

    try:
        return frozenset(inspect.signature(function).parameters)
    except (TypeError, ValueError):
        return frozenset()


def with_front_end(detector: LandmarkDetector, mode: EnhanceMode) -> LandmarkDetector:
    """`detector` behind the front end, or as it is with `mode` "off"."""
    return detector if mode == "off" else FrontEndDetector(detector, mode)
