"""What runs the face landmarker's models: LiteRT or MediaPipe's FaceLandmarker
(`landmarks.engine`).

An engine gives `roadgaze.landmarks.landmarker.Landmarker` three things: the image it takes
(`image`), landmarkers of a number of faces (`landmarker`, each `run(image, timestamp_ms)` ->
faces as `roadgaze.landmarks.results.FaceArrays`, IMAGE mode for `timestamp_ms` None) and a face
counter for the multi-face switch (`counter`). The rest of roadgaze never knows which one ran;
`tests/landmarks/test_engines.py` holds them equal.

`open_engine` builds the configured one. A LiteRT engine that cannot start (ai-edge-litert not
installed, a model LiteRT does not load) falls back to MediaPipe with one warning naming the fix.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from roadgaze.config import LandmarksConfig
from roadgaze.errors import ModelError
from roadgaze.landmarks.multi_face import FaceCounting
from roadgaze.landmarks.results import Blendshapes, FaceArrays

log = logging.getLogger(__name__)

__all__ = ["ENGINES", "Engine", "FaceCounting", "FaceRunner", "Tracking", "open_engine"]

ENGINES = ("litert", "mediapipe")
LITERT_FIX = "pip install 'ai-edge-litert==2.3.0'"


class FaceRunner(Protocol):
    """One landmarker: the faces of one image (VIDEO mode: in time order)."""

    def run(self, image: Any, timestamp_ms: int | None) -> list[FaceArrays]: ...

    def close(self) -> None: ...


@runtime_checkable
class Tracking(Protocol):
    """A `FaceRunner` whose run splits in two: `track` (the landmarks, which the next frame's
    regions depend on) and `complete` (the matrix and the blendshapes of one face, which nothing
    later needs). The loop measures faces on another thread than it infers them, so `complete`
    runs there, in parallel with `track` on the next frame (the LiteRT engine)."""

    def track(
        self, image: Any, timestamp_ms: int | None, retry_rejected: bool = False
    ) -> list[npt.NDArray[np.float32]]:
        """`retry_rejected`: look again at a face the landmark model rejected (the LiteRT
        engine's second looks)."""
        ...

    def complete(
        self, points: npt.NDArray[np.float32], size: tuple[int, int]
    ) -> tuple[npt.NDArray[np.float64] | None, Blendshapes | None]: ...


class Engine(Protocol):
    """The models behind a `Landmarker` (see the module docstring)."""

    name: str

    def image(self, rgb: Any) -> Any: ...

    def landmarker(self, num_faces: int) -> FaceRunner: ...

    def counter(self) -> FaceCounting | None: ...


def open_engine(
    config: LandmarksConfig, model_path: Path, video: bool, name: str | None = None
) -> Engine:
    """The engine `name` (default `config.engine`) for `model_path`; ModelError (one line) when
    neither it nor the MediaPipe fallback can load the model."""
    chosen = name or config.engine
    if chosen == "litert":
        try:
            from roadgaze.landmarks.engines.litert import LiteRtEngine

            return LiteRtEngine(config, model_path, video)
        except ImportError as exc:
            log.warning(
                "the LiteRT engine needs ai-edge-litert (%s): running MediaPipe instead; %s",
                exc,
                LITERT_FIX,
            )
        except ModelError as exc:
            log.warning("the LiteRT engine cannot start (%s): running MediaPipe instead", exc)
    elif chosen != "mediapipe":
        raise ModelError(f"unknown landmark engine '{chosen}'; choose one of {', '.join(ENGINES)}")
    from roadgaze.landmarks.engines.mediapipe import MediaPipeEngine

    return MediaPipeEngine(config, model_path, video)
