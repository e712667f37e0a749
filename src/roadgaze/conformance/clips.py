"""A scenario as a recorded drive: its frames, `NAME.speed.csv`, `NAME.truth.csv` (`NAME.mkv`).

The head pose and eyes of the scenario (driver's frame) go through the camera mounting
(`roadgaze.mounting.head_to_camera`) and are rendered as that camera sees the face (a head
pose of 0, 0 in the camera's frame faces the lens: the photo's own downward look,
`HeadFrame.facing_pitch_deg`, is nodded away), dressed in what the scenario's `conditions` name
(`roadgaze.synth.outfit`: glasses, a mask, a beard, a cap, ...), the jaw moving with speech when
it is `talking` and opening as its segments yawn (`mouth_track`), a hand on the wheel where the
camera sees it (`hand_at_12`), a phone held up in the outer hand (`phone_wheel`,
`phone_windscreen`); sensor noise goes on every frame (a held pose is not a frozen
camera), or at `night` the infrared picture with its own noise (`roadgaze.synth.effects.night`).
A covered lens is a dark flat frame, no face the cabin without the driver, frozen frames the
last frame again, byte for byte. `RenderedSource` hands the frames to the loop
as a video file would, rendered in the loop's decode thread (so rendering overlaps MediaPipe);
with a clip path it also writes them losslessly (FFV1), so `roadgaze replay NAME.mkv` shows the
same drive. The speed track (`roadgaze.capture.speed_track`) holds the scenario's speed every
`SPEED_PERIOD_S`; without a speed there is no track (unknown speed).
"""

from __future__ import annotations

import zlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from roadgaze.capture.base import SourceBase, SourceInfo, SourceStatus
from roadgaze.conformance.model import CameraState, Scenario, segments_timeline
from roadgaze.mounting import Cabin, head_to_camera, mounting_for
from roadgaze.synth.clip import write_truth_csv
from roadgaze.synth.effects import NoiseBank, covered_frame, night
from roadgaze.synth.eyes import EyeRenderer, EyeState
from roadgaze.synth.head import HeadFrame
from roadgaze.synth.layers import Layer
from roadgaze.synth.lean import leaned
from roadgaze.synth.mouth import speech_track
from roadgaze.synth.occluders import hand_layer
from roadgaze.synth.outfit import WORN, Outfit, check_conditions
from roadgaze.synth.phone_hand import PLACES, phone_hand_layer
from roadgaze.synth.renderer import ImageBGR
from roadgaze.synth.timeline import DEFAULT_TRANSITION_S, eased
from roadgaze.types import FloatArray, Frame

MOUTH_STEP = 0.02
"""The jaw's opening is rendered in steps of this fraction of a yawn (0.8 mm on a 14 cm face), so
a held pose with a talking mouth reuses its frames."""
SPEED_PERIOD_S = 0.5
"""A speed sample every half second (a CAN speed signal comes at 10-50 Hz; the track holds)."""
CLIP_SUFFIX = ".mkv"


def leans_m(scenario: Scenario, t_s: FloatArray) -> FloatArray:
    """(N, 3) the head's displacement from its driving place at each time (driver's frame,
    metres), eased as the turn is."""
    durations = [segment.duration_s for segment in scenario.segments]
    return np.column_stack(
        [
            eased([s.lean_m[axis] for s in scenario.segments], durations, DEFAULT_TRANSITION_S, t_s)
            for axis in range(3)
        ]
    )


def camera_states(scenario: Scenario, t_s: FloatArray) -> list[CameraState]:
    """What the camera delivers at each time (the segment the time falls in)."""
    ends = np.cumsum([segment.duration_s for segment in scenario.segments])
    index = np.minimum(np.searchsorted(ends, t_s, side="right"), len(ends) - 1)
    return [scenario.segments[int(i)].camera for i in index]


MOUTH_RAMP_S = 0.8
"""A segment's mouth opens and closes over this (a yawn gapes slowly and closes fast; eased)."""


def mouth_track(scenario: Scenario, t_s: FloatArray) -> FloatArray:
    """The jaw's opening the segments hold at each time (0 where none opens), eased over
    `MOUTH_RAMP_S` at each segment's ends."""
    opening = np.zeros(len(t_s))
    start = 0.0
    for segment in scenario.segments:
        end = start + segment.duration_s
        if segment.mouth_open > 0.0:
            inside = (t_s >= start) & (t_s < end)
            ramp = min(MOUTH_RAMP_S, segment.duration_s / 2.0)
            edge = np.minimum(t_s[inside] - start, end - t_s[inside]) / ramp
            ease = 0.5 - 0.5 * np.cos(np.pi * np.clip(edge, 0.0, 1.0))
            opening[inside] = segment.mouth_open * ease
        start = end
    return opening


def write_speed_track(path: Path, speed_kmh: float, duration_s: float) -> None:
    """`t_s,kmh` every `SPEED_PERIOD_S` from 0 to past `duration_s`, at one speed."""
    count = int(duration_s / SPEED_PERIOD_S) + 2
    rows = "".join(f"{i * SPEED_PERIOD_S:.2f},{speed_kmh:g}\n" for i in range(count))
    path.write_text("t_s,kmh\n" + rows, encoding="utf-8")


class ScenarioRenderer:
    """Renders scenarios with one `EyeRenderer` (built once: it runs MediaPipe on the photo; give
    it `eyeball_at_rest=True`, so eyes at rest turn with the head as an eyeball does); identical
    poses are rendered once per scenario."""

    def __init__(self, renderer: EyeRenderer, fps: float, cabin: Cabin = "lhd") -> None:
        self.renderer = renderer
        self.fps = fps
        self.cabin = cabin
        self.facing_pitch_deg = HeadFrame.of(renderer).facing_pitch_deg
        """Added to every rendered pitch: the photo's face looks this far below its camera."""
        self._outfits: dict[tuple[str, ...], Outfit] = {}
        self._hands: dict[str, Layer | None] = {}
        self._phones: dict[str, Layer] = {}

    def outfit(self, conditions: tuple[str, ...]) -> Outfit:
        """The face dressed in the worn ones of `conditions` (built once per combination)."""
        worn = tuple(name for name in WORN if name in conditions)
        if worn not in self._outfits:
            self._outfits[worn] = Outfit(self.renderer, worn)
        return self._outfits[worn]

    def _hand(self, preset: str) -> Layer | None:
        """The hand on the wheel as the camera at `preset` sees it (built once per camera)."""
        if preset not in self._hands:
            road_yaw, road_pitch, _ = head_to_camera(mounting_for(preset, self.cabin), 0.0, 0.0)
            rest = (road_yaw, road_pitch + self.facing_pitch_deg)
            self._hands[preset] = hand_layer(self.renderer, preset, self.cabin, rest)
        return self._hands[preset]

    def _phone(self, scenario: Scenario, place: str) -> Layer:
        """A phone held up at `place` (`roadgaze.synth.phone_hand`) as the scenario's camera
        sees it through its lens (built once per camera, place and zoom)."""
        key = f"{scenario.mounting}/{place}/{scenario.zoom:g}"
        if key not in self._phones:
            mounting = mounting_for(scenario.mounting, self.cabin)
            road_yaw, road_pitch, _ = head_to_camera(mounting, 0.0, 0.0)
            rest = (road_yaw, road_pitch + self.facing_pitch_deg)
            self._phones[key] = phone_hand_layer(
                self.renderer, place, self.cabin, rest, scenario.zoom
            )
        return self._phones[key]

    def _face(
        self,
        scenario: Scenario,
        row: FloatArray,
        mouth_open: float,
        cache: dict[tuple[float, ...], ImageBGR],
        lean_m: FloatArray,
    ) -> ImageBGR:
        mounting = mounting_for(scenario.mounting, self.cabin)
        yaw, camera_pitch, _ = head_to_camera(mounting, float(row[1]), float(row[2]))
        pitch = camera_pitch + self.facing_pitch_deg
        worn = scenario.conditions
        t_s = float(row[0])
        if scenario.worn_from and t_s < scenario.start_of(scenario.worn_from) - 1e-9:
            worn = ()
        if scenario.worn_until and t_s >= scenario.start_of(scenario.worn_until) - 1e-9:
            worn = ()
        lean = (float(lean_m[0]), float(lean_m[1]), float(lean_m[2]))
        values = (yaw, pitch, *row[3:6], mouth_open, *lean, len(worn))
        key = tuple(round(float(v), 4) for v in values)
        if key not in cache:
            outfit = self.outfit(worn)
            state = EyeState.both(float(row[3]), float(row[4]), float(row[5]))
            frame = outfit.render(yaw, pitch, state, mouth_open)
            hand = self._hand(scenario.mounting) if "hand_at_12" in worn else None
            width_px = self.renderer.mesh.face_width_px
            frame = leaned(frame, width_px, mounting, lean, scenario.zoom)
            frame = frame if hand is None else hand.over(frame)
            for place in PLACES:
                if f"phone_{place}" in worn:
                    frame = self._phone(scenario, place).over(frame)
            cache[key] = frame
        return cache[key]

    def frames(self, scenario: Scenario) -> Iterator[ImageBGR]:
        """Every frame of the scenario, in order (rendered as they are asked for). Raises
        ConfigError for a condition that does not exist."""
        check_conditions(scenario.conditions)
        truth = segments_timeline(scenario.segments).eye_truth(self.fps)
        states = camera_states(scenario, truth[:, 0])
        leans = leans_m(scenario, truth[:, 0])
        seed = zlib.crc32(scenario.name.encode())
        rng = np.random.default_rng(seed)
        noise = NoiseBank(self.renderer.size, rng)
        at_night = "night" in scenario.conditions
        mouth = mouth_track(scenario, truth[:, 0])
        if "talking" in scenario.conditions:
            mouth = np.maximum(mouth, speech_track(truth[:, 0], seed))
        mouth = np.round(mouth / MOUTH_STEP) * MOUTH_STEP
        cache: dict[tuple[float, ...], ImageBGR] = {}
        last: ImageBGR | None = None
        for row, state, opening, lean in zip(truth, states, mouth, leans, strict=True):
            if state == "frozen" and last is not None:
                frame = last
            elif state == "covered":
                frame = covered_frame(self.renderer.size, rng)
            else:
                seen = (
                    self.renderer.background
                    if state == "no_face"
                    else self._face(scenario, row, float(opening), cache, lean)
                )
                frame = night(seen, rng) if at_night else noise(seen)
            last = frame
            yield frame

    def write_side_files(self, scenario: Scenario, folder: Path) -> Path | None:
        """`NAME.truth.csv` and, with a speed, `NAME.speed.csv` in `folder`; returns the track."""
        folder.mkdir(parents=True, exist_ok=True)
        truth = segments_timeline(scenario.segments).eye_truth(self.fps)
        write_truth_csv(folder / f"{scenario.name}.truth.csv", truth)
        track = folder / f"{scenario.name}.speed.csv"
        track.unlink(missing_ok=True)
        if scenario.speed_kmh is None:
            return None
        write_speed_track(track, scenario.speed_kmh, scenario.duration_s)
        return track


class RenderedSource(SourceBase):
    """A scenario's frames as a file-like `FrameSource` (not live, at the renderer's rate);
    with `clip` set, each frame is also written to that lossless video."""

    def __init__(self, renderer: ScenarioRenderer, scenario: Scenario, clip: Path | None) -> None:
        self._renderer = renderer
        self._scenario = scenario
        self._clip = clip
        self._status = SourceStatus()
        width, height = renderer.renderer.size
        count = max(1, round(scenario.duration_s * renderer.fps))
        self._info = SourceInfo(scenario.name, False, renderer.fps, count, width, height)

    @property
    def info(self) -> SourceInfo:
        return self._info

    def __iter__(self) -> Iterator[Frame]:
        from roadgaze.outputs.video import open_video_writer

        writer: Any = None
        if self._clip is not None:
            size = (self._info.width, self._info.height)
            writer = open_video_writer(self._clip, self._renderer.fps, size, "FFV1")
        try:
            for index, image in enumerate(self._renderer.frames(self._scenario)):
                if writer is not None:
                    writer.write(image)
                self._status = SourceStatus(frames_delivered=index + 1)
                yield Frame(index=index, t_s=index / self._renderer.fps, image=image)
        finally:
            if writer is not None:
                writer.release()

    def close(self) -> None:
        return None
