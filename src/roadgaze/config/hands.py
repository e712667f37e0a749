"""The hand stage and the phone judgement: `[hands]` (pure: pydantic only).

Kept apart from `roadgaze.config.settings`, which only adds the section to `Config`; the
defaults and the measurements behind them are in docs/phone.md.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from roadgaze.config.section import Section


class HandsConfig(Section):
    """Hands beside the face (MediaPipe's palm detector and hand landmark model on LiteRT) and
    the per-frame phone judgement built on them. Without the hand models (`roadgaze model fetch
    hands`) the service runs without them and says that phone detection is off."""

    enabled: bool = True
    """Run the hand stage and judge phone use on each frame it runs on."""
    models: Literal["lite", "full"] = "lite"
    """MediaPipe's lite or full palm detector and hand landmark model."""
    num_hands: int = Field(default=2, ge=1, le=4)
    min_detection_confidence: float = Field(default=0.5, ge=0, le=1)
    """Palm detections kept (MediaPipe's default)."""
    min_presence_confidence: float = Field(default=0.5, ge=0, le=1)
    """Hands kept by the landmark model's presence score (MediaPipe's default)."""
    min_tracking_confidence: float = Field(default=0.5, ge=0, le=1)
    """A new palm overlapping a tracked hand by more than this IoU is the same hand."""
    interval_s: float = Field(default=0.3, ge=0)
    """The hand stage runs at most this often (0: every frame); frames in between carry the
    last hands and judgement. A phone is a matter of seconds (docs/phone.md)."""
    detect_interval_s: float = Field(default=0.6, ge=0)
    """The palm detector runs at most this often while fewer hands are tracked than
    `num_hands` (0: whenever MediaPipe's graph would, i.e. on every such frame)."""
    body: bool = True
    """Also find the driver's upper body (MediaPipe's pose detector and landmark model) at the
    hand stage's pace: the arms judge the frames whose hands are not found (docs/phone.md).
    False: the classifier sees no body, and finds less phone use."""
    body_interval_s: float = Field(default=0.9, ge=0)
    """The body at most this often (0: with every run of the hands); runs of the hands in
    between carry the last body. An arm holding a phone moves slowly; the body costs about three
    times the hands (docs/phone.md, Cost)."""
    enhance: Literal["auto", "off", "always"] = "auto"
    """The hand stage's front end (roadgaze.landmarks.hands.front_end): `auto` lifts a flat
    frame (as the face's front end judges it) for the hand and body models, smoothing its noise
    first; `off` passes frames as they come; `always` lifts every frame (docs/phone.md, "At
    night")."""
    phone_threshold: float | None = Field(default=None, ge=0, le=1)
    """The phone score from which a frame is judged phone use; None: the shipped classifier's
    own operating point (chosen leaving drivers out, docs/phone.md)."""
