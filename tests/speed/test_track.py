"""The one rule of a speed track: a sample holds up to `hold_s` (never interpolated), unknown
before the first, after an unknown sample and in a gap; the loop asks it at each frame's time."""

from __future__ import annotations

import math

import pytest

from fakes import ListSource, ScriptedDetector
from roadgaze.errors import SpeedError
from roadgaze.pipeline import BusSpeed, ConstantSpeed, Pipeline, vehicle_speed
from roadgaze.speed import SpeedTrack, checked_kmh


def test_hold_up_to_hold_s_then_unknown_and_unknown_before_the_first() -> None:
    track = SpeedTrack((1.0, 2.0, 6.0, 7.0), (10.0, 70.0, None, 30.0))
    times = (0.0, 0.99, 1.0, 1.5, 2.0, 3.99, 4.0, 6.5, 7.0, 8.99, 9.0)
    got = [track.kmh_at(t) for t in times]
    assert got == [None, None, 10.0, 10.0, 70.0, 70.0, None, None, 30.0, 30.0, None]


def test_never_interpolated_between_samples() -> None:
    track = SpeedTrack((0.0, 1.0), (10.0, 30.0))
    assert [track.kmh_at(t) for t in (0.0, 0.5, 0.999, 1.0)] == [10.0, 10.0, 10.0, 30.0]


def test_the_next_change_is_the_next_sample_or_the_end_of_the_hold() -> None:
    track = SpeedTrack((1.0, 2.0, 6.0), (10.0, 70.0, 30.0), hold_s=2.0)
    assert track.next_change_s(0.0) == 1.0
    assert track.next_change_s(1.0) == 2.0
    assert track.next_change_s(2.5) == 4.0  # the hold of 2.0 ends before 6.0
    assert track.next_change_s(4.0) == 6.0
    assert track.next_change_s(6.0) == 8.0 == track.end_s
    assert track.next_change_s(8.0) == math.inf
    constant = SpeedTrack.constant(57.0)
    assert constant.kmh_at(1e9) == 57.0 and constant.next_change_s(0.0) == math.inf


@pytest.mark.parametrize(
    ("times", "speeds", "message"),
    [
        ((), (), "at least one"),
        ((0.0, 1.0), (1.0,), "as many speeds as times"),
        ((1.0, 1.0), (1.0, 2.0), "strictly increasing"),
        ((math.nan,), (1.0,), "strictly increasing"),
        ((0.0,), (401.0,), "within 0-400"),
        ((0.0,), (-0.5,), "within 0-400"),
        ((0.0,), (math.inf,), "within 0-400"),
    ],
)
def test_a_track_that_is_not_one_is_refused(
    times: tuple[float, ...], speeds: tuple[float, ...], message: str
) -> None:
    with pytest.raises(SpeedError, match=message):
        SpeedTrack(times, speeds)


def test_one_range_check_for_every_speed() -> None:
    assert checked_kmh(0.0, "x") == 0.0 and checked_kmh(400.0, "x") == 400.0
    for bad in (-1.0, 400.5, math.inf, math.nan):
        with pytest.raises(SpeedError, match=r"--speed-kmh .* is not a speed within 0-400 km/h"):
            checked_kmh(bad, "--speed-kmh")
    with pytest.raises(SpeedError, match="within 0-400"):
        ConstantSpeed(500.0)
    with pytest.raises(SpeedError, match="within 0-400"):
        SpeedTrack.constant(-3.0)


def test_the_loop_asks_the_speed_at_each_frame_time() -> None:
    """10 km/h held 0.5 s (not moving), a gap (unknown: moving), 70 km/h held 0.5 s, a gap."""
    track = SpeedTrack((0.0, 1.0), (10.0, 70.0), hold_s=0.5)
    pipeline = Pipeline(ScriptedDetector([0.0] * 20), speed=track)
    verdicts = [p.record.verdict for p in pipeline.frames(ListSource(20, fps=10.0))]
    assert [v.speed_kmh for v in verdicts] == [10.0] * 5 + [None] * 5 + [70.0] * 5 + [None] * 5
    assert [v.moving for v in verdicts] == [False] * 5 + [True] * 15


def test_a_plain_speed_function_is_the_bus() -> None:
    speed = vehicle_speed(lambda: 33.0)
    assert isinstance(speed, BusSpeed) and speed.kmh_at(123.0) == 33.0
    track = SpeedTrack((0.0,), (1.0,))
    assert vehicle_speed(track) is track


def test_the_old_import_paths_give_the_one_implementation() -> None:
    import roadgaze.capture.speed_track as capture_track
    import roadgaze.pipeline.speed as pipeline_speed
    import roadgaze.speed as speed
    import roadgaze.transport.speed_track as transport_track

    assert capture_track.SpeedTrack is transport_track.SpeedTrack is speed.SpeedTrack
    assert capture_track.read_speed_track is transport_track.read_speed_track
    assert capture_track.recorded_speed is speed.recorded_speed
    assert pipeline_speed.ConstantSpeed is speed.ConstantSpeed
    assert pipeline_speed.VehicleSpeed is speed.VehicleSpeed
