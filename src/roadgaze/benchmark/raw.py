"""MediaPipe's FaceLandmarker alone on a clip: the throughput roadgaze's loop is compared with;
and the models inside it alone on LiteRT: the floor of any engine that runs them.

The reference is what a user would measure with MediaPipe and nothing else: VIDEO mode,
`num_faces=1`, MediaPipe's default outputs (no transformation matrices, no blendshapes), the
configured confidences, frames decoded and converted to RGB beforehand (in chunks of
`CHUNK_FRAMES`, so memory stays bounded), and only `detect_for_video` timed, through MediaPipe's
public Python API (its conversion of the result to Python objects included).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from itertools import islice
from pathlib import Path
from typing import Any

import numpy as np

from roadgaze.config import Config, LandmarksConfig
from roadgaze.types import Frame

log = logging.getLogger(__name__)

CHUNK_FRAMES = 64
"""Frames decoded and converted before a run of timed calls (about 60 MB at 640x480)."""


@dataclass(frozen=True, slots=True)
class RawResult:
    """The timed calls of one or more raw passes."""

    durations_s: tuple[float, ...]
    """Each timed `detect_for_video` call, seconds."""
    cpu_s: float
    """Process CPU time over the timed calls (all of MediaPipe's threads)."""
    passes_fps: tuple[float, ...]

    @property
    def frames_timed(self) -> int:
        return len(self.durations_s)

    @property
    def fps(self) -> float:
        total = sum(self.durations_s)
        return len(self.durations_s) / total if total > 0 else 0.0

    @property
    def cpu_ms_per_frame(self) -> float:
        return 1e3 * self.cpu_s / len(self.durations_s) if self.durations_s else 0.0

    def percentile_ms(self, percent: float) -> float:
        if not self.durations_s:
            return 0.0
        return float(np.percentile(1e3 * np.asarray(self.durations_s), percent))

    def __add__(self, other: RawResult) -> RawResult:
        """Two passes together (e.g. one before and one after the loop's pass)."""
        return RawResult(
            self.durations_s + other.durations_s,
            self.cpu_s + other.cpu_s,
            self.passes_fps + other.passes_fps,
        )


def raw_mediapipe_pass(
    frames: Iterable[Frame], model_path: Path, config: LandmarksConfig, warmup: int
) -> RawResult:
    """Time MediaPipe's `detect_for_video` over `frames` with a fresh landmarker (the first
    `warmup` frames are not timed). Raises ModelError for a model MediaPipe cannot load."""
    import cv2
    import mediapipe as mp
    from mediapipe.tasks.python import vision
    from mediapipe.tasks.python.core.base_options import BaseOptions

    from roadgaze.errors import ModelError
    from roadgaze.landmarks.native_log import filtered_native_stderr

    options = vision.FaceLandmarkerOptions(
        base_options=BaseOptions(model_asset_path=str(model_path)),
        running_mode=vision.RunningMode.VIDEO,
        num_faces=1,
        min_face_detection_confidence=config.min_detection_confidence,
        min_face_presence_confidence=config.min_presence_confidence,
        min_tracking_confidence=config.min_tracking_confidence,
    )
    try:
        with filtered_native_stderr():
            landmarker: Any = vision.FaceLandmarker.create_from_options(options)
    except (RuntimeError, ValueError, OSError) as exc:
        raise ModelError(f"cannot load face landmarker model {model_path}: {exc}") from None
    durations_s: list[float] = []
    cpu_s = 0.0
    last_ms = -1
    position = 0
    try:
        for chunk in _chunks(iter(frames), CHUNK_FRAMES):
            images = [
                (frame.t_s, np.ascontiguousarray(cv2.cvtColor(frame.image, cv2.COLOR_BGR2RGB)))
                for frame in chunk
            ]
            for t_s, rgb in images:
                image = mp.Image(image_format=mp.ImageFormat.SRGB, data=rgb)
                timestamp_ms = max(round(t_s * 1000.0), last_ms + 1)
                last_ms = timestamp_ms
                cpu_before = time.process_time()
                before = time.perf_counter()
                if position < warmup:  # MediaPipe's first call logs its set-up on fd 2
                    with filtered_native_stderr():
                        landmarker.detect_for_video(image, timestamp_ms)
                else:
                    landmarker.detect_for_video(image, timestamp_ms)
                elapsed_s = time.perf_counter() - before
                if position >= warmup:
                    durations_s.append(elapsed_s)
                    cpu_s += time.process_time() - cpu_before
                position += 1
    finally:
        with filtered_native_stderr():
            landmarker.close()
    fps = len(durations_s) / sum(durations_s) if durations_s else 0.0
    return RawResult(tuple(durations_s), cpu_s, (fps,))


def litert_models_pass(spec: str, config: Config, warmup: int) -> Callable[[], RawResult] | None:
    """A pass of `models_alone` over the source `spec` (None without ai-edge-litert)."""
    import importlib.util

    if importlib.util.find_spec("ai_edge_litert") is None:
        return None

    def run() -> RawResult:
        from roadgaze.capture import open_source
        from roadgaze.landmarks.model_store import resolve_model

        log.info("models-alone pass (LiteRT)")
        with open_source(spec, config) as source:
            return models_alone(source, resolve_model(config.model), config.landmarks, warmup)

    return run


def models_alone(
    frames: Iterable[Frame], model_path: Path, config: LandmarksConfig, warmup: int
) -> RawResult:
    """Time the bundle's landmark and blendshape models alone on LiteRT, once each per frame of
    `frames` (the first `warmup` frames not timed), as a tracked frame runs them: the landmark
    model on the frame's central square (cropped untimed), the blendshape model on the subset
    of its landmarks. Nothing else a frame needs (decoding, the crop, the face's measurements) is
    timed, so no engine of these models can cost less CPU. Raises ModelError for a bundle LiteRT
    cannot load and ImportError without ai-edge-litert."""
    import cv2

    from roadgaze.landmarks.engines.litert import (
        BLENDSHAPE_INDEX,
        LANDMARKS_SIZE,
        Bundle,
        Models,
        Warper,
    )

    models = Models.load(Bundle.read(model_path), config)
    warper = Warper(LANDMARKS_SIZE, cv2.BORDER_REPLICATE)
    durations_s: list[float] = []
    cpu_s = 0.0
    for position, frame in enumerate(frames):
        height, width = frame.image.shape[:2]
        side = float(min(width, height))
        rgb = np.ascontiguousarray(cv2.cvtColor(frame.image, cv2.COLOR_BGR2RGB), np.uint8)
        crop = warper.warp(rgb, (width / 2.0, height / 2.0, side, side, 0.0))
        cpu_before, before = time.process_time(), time.perf_counter()
        points = models.landmarks.run(crop, 1.0 / 255.0)[0].reshape(-1, 3)
        models.blendshapes.run(np.ascontiguousarray(points[BLENDSHAPE_INDEX, :2]))
        elapsed_s, cpu_elapsed_s = time.perf_counter() - before, time.process_time() - cpu_before
        if position >= warmup:
            durations_s.append(elapsed_s)
            cpu_s += cpu_elapsed_s
    fps = len(durations_s) / sum(durations_s) if durations_s else 0.0
    return RawResult(tuple(durations_s), cpu_s, (fps,))


def _chunks(frames: Iterator[Frame], size: int) -> Iterator[list[Frame]]:
    while chunk := list(islice(frames, size)):
        yield chunk
