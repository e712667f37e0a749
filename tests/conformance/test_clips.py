"""The scenarios' frames: noise on every frame, a covered lens, frozen frames byte for byte, no
face, what the driver wears, a talking mouth, the night, a hand on the wheel, the face as a
camera at a mounting preset sees it, the speed track."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from roadgaze.capture.speed_track import read_speed_track
from roadgaze.conformance.clips import RenderedSource, ScenarioRenderer
from roadgaze.conformance.model import Scenario, Segment
from roadgaze.errors import ConfigError
from roadgaze.pose.mounting import FRONT, head_to_camera, mounting_for
from roadgaze.synth.eyes import EyeState
from roadgaze.synth.lean import leaned

FPS = 5.0


@pytest.fixture(scope="module")
def renderer() -> ScenarioRenderer:
    from roadgaze.synth import EyeRenderer, load_photo

    return ScenarioRenderer(EyeRenderer(load_photo(), (160, 160), eyeball_at_rest=True), FPS)


def grey(frame: Any) -> Any:
    return frame.astype(np.float64).mean(axis=2)


def test_camera_states_and_noise(renderer: ScenarioRenderer) -> None:
    segments = (
        Segment(1.0),
        Segment(1.0, camera="frozen"),
        Segment(0.6, camera="covered"),
        Segment(0.6, camera="no_face"),
    )
    frames = list(renderer.frames(Scenario("states", "", segments, 70.0, ())))
    assert len(frames) == 16
    ahead = [grey(f) for f in frames[:5]]
    for first, second in itertools.pairwise(ahead):
        assert np.abs(first - second).mean() > 1.0  # a held pose is not a frozen camera
    assert all(np.array_equal(frame, frames[4]) for frame in frames[5:10])  # frozen: repeats
    for frame in frames[10:13]:
        assert grey(frame).mean() < 12.0 and grey(frame).std() < 4.0  # covered: dark and flat
    background = renderer.renderer.background.astype(np.float64)
    for frame in frames[13:]:
        assert np.abs(frame.astype(np.float64) - background).mean() < 3.0  # the cabin, no face


def test_a_preset_renders_the_face_as_its_camera_sees_it(renderer: ScenarioRenderer) -> None:
    scenario = Scenario("pillar", "", (Segment(0.2, 0.0, -35.0),), 70.0, (), mounting="a_pillar")
    frame = next(renderer.frames(scenario)).astype(np.float64)
    yaw, pitch, _ = head_to_camera(mounting_for("a_pillar"), 0.0, -35.0)
    assert yaw < -20.0  # the camera on the left pillar sees the face turned to its right
    facing = renderer.facing_pitch_deg
    seen = renderer.renderer.render_eyes(yaw, pitch + facing, EyeState()).astype(np.float64)
    front = renderer.renderer.render_eyes(0.0, -35.0 + facing, EyeState()).astype(np.float64)
    assert np.abs(frame - seen).mean() < 3.0 < np.abs(frame - front).mean()


def test_a_lean_moves_the_face_as_the_camera_sees_the_head_moved(
    renderer: ScenarioRenderer,
) -> None:
    lean = (0.1, -0.2, -0.15)
    segments = (Segment(1.0), Segment(1.0, lean_m=lean))
    frames = list(renderer.frames(Scenario("lean", "", segments, 70.0, (), zoom=0.7)))
    facing = renderer.facing_pitch_deg
    still = renderer.renderer.render_eyes(0.0, facing, EyeState())
    width_px = renderer.renderer.mesh.face_width_px
    at_rest = leaned(still, width_px, FRONT, (0.0, 0.0, 0.0), 0.7).astype(np.float64)
    moved = leaned(still, width_px, FRONT, lean, 0.7).astype(np.float64)
    assert np.abs(frames[0] - at_rest).mean() < 3.0 < np.abs(frames[0] - moved).mean()
    assert np.abs(frames[-1] - moved).mean() < 3.0 < np.abs(frames[-1] - at_rest).mean()


def test_the_road_pose_faces_the_camera(renderer: ScenarioRenderer) -> None:
    """The photo's face looks 11.5 deg below its camera; a scenario looking at the road with the
    camera in front is rendered facing the lens."""
    assert renderer.facing_pitch_deg == pytest.approx(11.5, abs=0.5)
    frame = next(renderer.frames(Scenario("road", "", (Segment(0.2),), 70.0, ())))
    faced = renderer.renderer.render_eyes(0.0, renderer.facing_pitch_deg, EyeState())
    assert np.abs(frame.astype(np.float64) - faced.astype(np.float64)).mean() < 3.0


def test_sunglasses_cover_the_eyes(renderer: ScenarioRenderer) -> None:
    plain, dark = (
        next(renderer.frames(Scenario("g", "", (Segment(0.2),), 70.0, (), conditions=worn)))
        for worn in ((), ("dark_sunglasses",))
    )
    changed = np.abs(grey(plain) - grey(dark)) > 40
    assert 0.005 < changed.mean() < 0.08  # two lenses: a small part of the frame
    assert grey(dark)[changed].mean() < 30.0


def test_worn_from_puts_the_condition_on_at_its_segment(renderer: ScenarioRenderer) -> None:
    """A scenario with `worn_from` shows the bare face before that segment, dressed from it."""
    segments = (Segment(0.4, label="ahead"), Segment(0.4, label="worn"))
    bare = Scenario("w", "", segments, 70.0, ())
    late = Scenario("w", "", segments, 70.0, (), conditions=("dark_sunglasses",), worn_from="worn")
    pairs = list(zip(renderer.frames(bare), renderer.frames(late), strict=True))
    assert len(pairs) == 4  # 5 fps: 0.0 and 0.2 s bare, from 0.4 s on
    before = [np.abs(grey(a) - grey(b)).mean() for a, b in pairs[:2]]
    after = [np.abs(grey(a) - grey(b)).mean() for a, b in pairs[2:]]
    assert max(before) < 0.5 < 2.0 < min(after)


def test_side_files_and_the_source(renderer: ScenarioRenderer, tmp_path: Path) -> None:
    scenario = Scenario("drive", "", (Segment(1.2),), 35.0, ())
    track = renderer.write_side_files(scenario, tmp_path)
    assert track == tmp_path / "drive.speed.csv" and (tmp_path / "drive.truth.csv").is_file()
    speed = read_speed_track(track)
    assert speed.kmh_at(0.0) == 35.0 and speed.kmh_at(1.2) == 35.0
    clip = tmp_path / "drive.mkv"
    frames = list(RenderedSource(renderer, scenario, clip))
    assert [f.t_s for f in frames] == pytest.approx([0.0, 0.2, 0.4, 0.6, 0.8, 1.0])
    assert clip.stat().st_size > 0
    assert (
        renderer.write_side_files(Scenario("drive", "", (Segment(1.0),), None, ()), tmp_path)
        is None
    )
    assert not track.exists()  # no speed: no track (unknown)


def test_eyes_at_rest_turn_with_the_head_as_an_eyeball(renderer: ScenarioRenderer) -> None:
    """Ahead, the frame is the plain render; pitched up, only the irises move (the flat iris of
    the photo would read as eyes looking down)."""
    eyes = renderer.renderer
    assert np.array_equal(eyes.render_eyes(0.0, 0.0, EyeState()), eyes.render(0.0, 0.0))
    moved = np.abs(grey(eyes.render_eyes(0.0, 20.0, EyeState())) - grey(eyes.render(0.0, 20.0)))
    assert 0.0 < (moved > 20).mean() < 0.01
    eyes.eyeball_at_rest = False
    try:
        assert np.array_equal(eyes.render_eyes(0.0, 20.0, EyeState()), eyes.render(0.0, 20.0))
    finally:
        eyes.eyeball_at_rest = True


def test_conditions_render_from_the_first_frame(renderer: ScenarioRenderer) -> None:
    def first(*conditions: str, mounting: str = "front") -> Any:
        scenario = Scenario("c", "", (Segment(0.2),), 70.0, (), mounting, conditions)
        return grey(next(renderer.frames(scenario)))

    plain = first()
    assert Scenario("s", "", (), None, (), conditions=("dark_sunglasses",)).sunglasses
    for name in ("clear_sunglasses", "stubble", "beard", "mask", "cap", "hat", "fringe"):
        assert np.abs(first(name) - plain).mean() > 0.5, name
    night = next(
        renderer.frames(Scenario("c", "", (Segment(0.2),), 70.0, (), conditions=("night",)))
    )
    assert np.array_equal(night[..., 0], night[..., 2]) and night.std() < 0.7 * plain.std()
    column, front = first("hand_at_12", mounting="steering_column"), first("hand_at_12")
    (x0, y0), (x1, y1) = renderer.renderer.mesh.points_px[[33, 263], :2].round().astype(int)
    eyes = (slice(min(y0, y1) - 3, max(y0, y1) + 4), slice(x0, x1))  # where the eyes rest
    assert np.abs(column - first(mounting="steering_column"))[eyes].mean() > 10.0
    assert np.abs(front - plain)[eyes].mean() < 2.0
    with pytest.raises(ConfigError, match="unknown condition sunhat"):
        first("sunhat")


def test_a_talking_driver_moves_the_mouth_and_nothing_else(renderer: ScenarioRenderer) -> None:
    scenario = Scenario("talk", "", (Segment(4.0),), 70.0, (), conditions=("talking",))
    frames = [grey(f) for f in renderer.frames(scenario)]
    still = [grey(f) for f in renderer.frames(replace_conditions(scenario, ()))]
    mouth = (slice(92, 112), slice(65, 95))  # the lips and chin in a 160 px frame
    moved = [np.abs(a - b)[mouth].mean() for a, b in zip(frames, still, strict=True)]
    assert max(moved) > 5.0 and min(moved) < 2.0  # it opens and closes
    eyes = (slice(45, 65), slice(50, 110))
    assert max(np.abs(a - b)[eyes].mean() for a, b in zip(frames, still, strict=True)) < 2.0


def replace_conditions(scenario: Scenario, conditions: tuple[str, ...]) -> Scenario:
    from dataclasses import replace

    return replace(scenario, conditions=conditions)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("scenario_name", "condition"),
    [
        ("microsleep_70", "night"),
        ("microsleep_70", "clear_sunglasses"),
        ("side_left_70", "stubble"),
        ("microsleep_70", "talking"),
    ],
)
def test_a_green_scenario_still_passes_under_a_noise_variable(
    tmp_path: Path, scenario_name: str, condition: str
) -> None:
    """The real service (MediaPipe, the pipeline, the monitor) on the drive rendered under the
    condition, as the dossier runs it: every requirement still PASS."""
    from roadgaze.config import Config
    from roadgaze.conformance.dossier_rows import under
    from roadgaze.conformance.matrix import scenario_matrix
    from roadgaze.conformance.run import run_suite
    from roadgaze.synth import EyeRenderer, load_photo

    config = Config()
    monitor = config.monitor.model_dump() | {"protocol": "euroncap"}
    config = config.model_copy(update={"monitor": type(config.monitor).model_validate(monitor)})
    scenario = next(s for s in scenario_matrix(config.monitor) if s.name == scenario_name)
    eyes = EyeRenderer(load_photo(), (320, 320), config=config, eyeball_at_rest=True)
    suite = run_suite([under(condition)(scenario)], config, tmp_path, ScenarioRenderer(eyes, 15.0))
    assert suite.outcomes and all(o.result == "PASS" for o in suite.outcomes), [
        (o.requirement.key, o.measured_s, o.alerts) for o in suite.outcomes
    ]
