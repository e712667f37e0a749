"""The hand stage: the driver's hands on a frame, at the configured pace, as `Hand` records.

`HandStage.from_config` loads the verified models named by `[hands] models` from the model cache;
when they are missing or damaged it logs one line naming the file and the fix and returns None:
the service then runs without hands, and phone detection is off (the record's hand fields are
null). `run(image, t_s)` gives the hands of a BGR frame (a flat one lifted first by the stage's
front end, `[hands] enhance`: roadgaze.landmarks.hands.front_end); in a stream it runs the
models at most every `interval_s` and returns the last hands in between (`fresh` says which).
With `[hands] body` (the default) the driver's upper body is found at the same pace
(MediaPipe's pose models, provisioned with the hand models).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.config import Config, HandsConfig
from roadgaze.errors import ModelError
from roadgaze.landmarks.hands.engine import HandArrays, HandLandmarker, HandSettings
from roadgaze.landmarks.hands.front_end import for_hands
from roadgaze.landmarks.hands.models import model_names, resolve_hand_models
from roadgaze.landmarks.pose.engine import PoseArrays, PoseLandmarker, PoseSettings
from roadgaze.landmarks.pose.models import DETECTOR_NAME, LANDMARKS_NAME
from roadgaze.types import Hand, HandSide

log = logging.getLogger(__name__)


def to_hand(found: HandArrays, size: tuple[int, int]) -> Hand:
    """A hand in pixels with the person's own side. The handedness score is the model's score
    of `Left` (MediaPipe's binary classifier: its first label, `handedness.txt` being
    `Left`, `Right`), and MediaPipe labels hands as if the image were mirrored (a selfie
    camera): on a cabin camera, which is not mirrored, its `Left` (score > 0.5) is the person's
    own right hand, its `Right` (score < 0.5) their own left."""
    scale = np.array([size[0], size[1], size[0]], np.float32)
    points = (found.points * scale).astype(np.float32)
    own_left = found.handedness < 0.5
    box = (
        float(points[:, 0].min()),
        float(points[:, 1].min()),
        float(points[:, 0].max()),
        float(points[:, 1].max()),
    )
    return Hand(
        side=HandSide.LEFT if own_left else HandSide.RIGHT,
        side_score=float(max(found.handedness, 1.0 - found.handedness)),
        score=float(found.presence),
        landmarks_px=points,
        box_px=box,
    )


@dataclass(frozen=True, slots=True)
class HandsOfFrame:
    """What the stage gives for one frame."""

    hands: tuple[Hand, ...]
    fresh: bool
    """Measured on this frame (False: the last measurement, carried over)."""
    size: tuple[int, int]
    """The frame's width and height in pixels."""
    body: PoseArrays | None = None
    """The driver's upper body (None: not found, or `[hands] body` off)."""

    @property
    def body_arrays(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]] | None:
        """The body as the phone features take it: (landmarks, visibilities), or None."""
        return None if self.body is None else (self.body.points, self.body.visibility)


class HandStage:
    """The hand landmarker with its pace (see the module docstring)."""

    def __init__(
        self, landmarker: HandLandmarker, config: HandsConfig, body: PoseLandmarker | None = None
    ) -> None:
        self._landmarker = landmarker
        self._body = body
        self._body_interval_s = config.body_interval_s
        self._last_body: PoseArrays | None = None
        self._last_body_t_s: float | None = None
        self.body_runs = 0
        self._interval_s = config.interval_s
        self._enhance = config.enhance
        self._last_t_s: float | None = None
        self._last: tuple[Hand, ...] = ()
        self.runs = 0

    @classmethod
    def from_config(cls, config: Config) -> HandStage | None:
        """The configured stage; None (phone detection off, one warning naming the file and
        the fix) when `[hands] enabled` is false or its models are missing or unusable."""
        hands = config.hands
        if not hands.enabled:
            return None
        try:
            palm, landmarks = resolve_hand_models(
                config.model, model_names(hands.models, hands.models)
            )
            body = None
            if hands.body:
                detector, marks = resolve_hand_models(config.model, (DETECTOR_NAME, LANDMARKS_NAME))
                body = PoseLandmarker(
                    detector,
                    marks,
                    PoseSettings(
                        detect_interval_ms=round(hands.detect_interval_s * 1000),
                        threads=config.landmarks.threads,
                        delegate=config.landmarks.delegate,
                    ),
                )
            landmarker = HandLandmarker(
                palm,
                landmarks,
                HandSettings(
                    num_hands=hands.num_hands,
                    min_detection_confidence=hands.min_detection_confidence,
                    min_presence_confidence=hands.min_presence_confidence,
                    min_tracking_confidence=hands.min_tracking_confidence,
                    detect_interval_ms=round(hands.detect_interval_s * 1000),
                    threads=config.landmarks.threads,
                    delegate=config.landmarks.delegate,
                ),
            )
        except ImportError as exc:
            log.warning("phone detection is off: the hand models need ai-edge-litert (%s)", exc)
            return None
        except ModelError as exc:
            log.warning("phone detection is off: %s", exc)
            return None
        return cls(landmarker, hands, body)

    def run(self, image: npt.NDArray[np.uint8], t_s: float | None) -> HandsOfFrame:
        """The hands of a BGR (or grey, BGRA) frame at `t_s` (None: a still, always
        measured)."""
        from roadgaze.landmarks.landmarker import to_rgb

        size = (image.shape[1], image.shape[0])
        last = self._last_t_s
        if t_s is not None and last is not None and last <= t_s < last + self._interval_s:
            return HandsOfFrame(self._last, False, size, self._last_body)
        rgb = to_rgb(for_hands(image, self._enhance))
        timestamp_ms = None if t_s is None else round(t_s * 1000)
        found = self._landmarker.run(rgb, timestamp_ms)
        self._last = tuple(to_hand(hand, size) for hand in found)
        if self._body is not None and self._body_due(t_s):
            self._last_body = self._body.run(rgb, timestamp_ms)
            self._last_body_t_s = t_s
            self.body_runs += 1
        self._last_t_s = t_s
        self.runs += 1
        return HandsOfFrame(self._last, True, size, self._last_body)

    def _body_due(self, t_s: float | None) -> bool:
        """Whether the body is measured at this run: always on stills and at a stream's
        start, then at most every `body_interval_s`."""
        last = self._last_body_t_s
        return t_s is None or last is None or not last <= t_s < last + self._body_interval_s

    def close(self) -> None:
        self._landmarker.close()
        if self._body is not None:
            self._body.close()
