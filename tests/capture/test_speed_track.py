"""Speed tracks of recorded drives: reading, hold-last with a timeout, unknown = moving, bad files
in one line, and the loop asking the speed at each frame's own time."""

from __future__ import annotations

from pathlib import Path

import pytest

from fakes import ListSource, ScriptedDetector
from roadgaze.capture.speed_track import (
    SpeedTrack,
    read_speed_track,
    recorded_speed,
    track_beside,
)
from roadgaze.errors import ConfigError, SourceError
from roadgaze.pipeline import BusSpeed, ConstantSpeed, Pipeline, vehicle_speed


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def test_hold_last_for_hold_s_then_unknown_and_unknown_before_the_first(tmp_path: Path) -> None:
    track = read_speed_track(write(tmp_path / "d.speed.csv", "t_s,kmh\n1,10\n2,70\n6,\n7,30\n"))
    assert track.t_s == (1.0, 2.0, 6.0, 7.0) and track.kmh == (10.0, 70.0, None, 30.0)
    times = (0.0, 0.99, 1.0, 1.5, 2.0, 3.99, 4.0, 4.01, 6.5, 7.0, 9.0, 9.01)
    got = [track.kmh_at(t) for t in times]
    assert got == [None, None, 10.0, 10.0, 70.0, 70.0, 70.0, None, None, 30.0, 30.0, None]


def test_extra_columns_are_ignored_and_nan_is_unknown(tmp_path: Path) -> None:
    csv = write(tmp_path / "t.csv", "can_id,t_s,kmh\n7,0,nan\n7,0.5,55.5\n")
    track = read_speed_track(csv, hold_s=0.25)
    assert track.kmh == (None, 55.5)
    assert track.kmh_at(0.6) == 55.5 and track.kmh_at(0.8) is None


def test_parquet_track(tmp_path: Path) -> None:
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    path = tmp_path / "drive.speed.parquet"
    pq.write_table(pa.table({"t_s": [0.0, 1.0], "kmh": [None, 42.0]}), path)
    track = read_speed_track(path)
    assert track.kmh == (None, 42.0) and track.kmh_at(0.5) is None and track.kmh_at(2.0) == 42.0
    pq.write_table(pa.table({"time": [0.0]}), path)
    with pytest.raises(SourceError, match="no column t_s, kmh"):
        read_speed_track(path)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "header with the columns t_s,kmh"),
        ("t_s,speed\n0,1\n", "header with the columns t_s,kmh"),
        ("t_s,kmh\n", "has no sample"),
        ("t_s,kmh\n0,10\n0,20\n", "line 3: t_s 0 is not after the previous 0"),
        ("t_s,kmh\n0,fast\n", "line 2: kmh 'fast' is not a number"),
        ("t_s,kmh\n0,-1\n", "line 2: kmh '-1' is outside 0-400 km/h"),
        ("t_s,kmh\n0,inf\n", "outside 0-400"),
        ("t_s,kmh\nnan,1\n", "line 2: t_s 'nan' is not a finite number"),
        ("t_s,kmh\n,1\n", "line 2: t_s '' is not a number"),
    ],
)
def test_bad_csv_is_one_line_naming_the_line(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(SourceError, match=message) as caught:
        read_speed_track(write(tmp_path / "bad.csv", text))
    assert "\n" not in str(caught.value)


def test_missing_and_wrong_kind_of_file(tmp_path: Path) -> None:
    with pytest.raises(SourceError, match="not found"):
        read_speed_track(tmp_path / "none.csv")
    with pytest.raises(SourceError, match=r"expected a \.csv or \.parquet"):
        read_speed_track(write(tmp_path / "s.txt", "t_s,kmh\n0,1\n"))
    (tmp_path / "broken.parquet").write_bytes(b"PAR1 not really")
    pytest.importorskip("pyarrow")
    with pytest.raises(SourceError, match="cannot read speed track"):
        read_speed_track(tmp_path / "broken.parquet")


def test_the_track_beside_the_video_and_the_choice(tmp_path: Path) -> None:
    video = write(tmp_path / "drive.mp4", "x")
    assert track_beside(video) is None
    assert recorded_speed(video).speed is None
    track = write(tmp_path / "drive.speed.csv", "t_s,kmh\n0,12\n")
    assert track_beside(video) == track
    choice = recorded_speed(video)
    assert isinstance(choice.speed, SpeedTrack) and choice.track_path == track
    assert "1 samples" in choice.origin and "12-12 km/h" in choice.origin
    constant = recorded_speed(video, constant_kmh=70.0)
    assert isinstance(constant.speed, ConstantSpeed) and constant.speed.kmh_at(1e6) == 70.0
    other = write(tmp_path / "other.csv", "t_s,kmh\n0,99\n")
    named = recorded_speed(video, track=other).speed
    assert named is not None and named.kmh_at(0.0) == 99.0
    with pytest.raises(ConfigError, match="not both"):
        recorded_speed(video, track=other, constant_kmh=5.0)
    with pytest.raises(ConfigError, match="within 0-400"):
        recorded_speed(video, constant_kmh=float("nan"))
    write(tmp_path / "drive.speed.parquet", "")
    with pytest.raises(SourceError, match="two speed tracks"):
        recorded_speed(video)


def test_the_loop_asks_the_speed_at_each_frame_time() -> None:
    """10 km/h held 0.5 s (not moving), a gap (unknown: moving), 70 km/h held 0.5 s, a gap."""
    track = SpeedTrack((0.0, 1.0), (10.0, 70.0), hold_s=0.5)
    pipeline = Pipeline(ScriptedDetector([0.0] * 20), speed=track)
    verdicts = [p.record.verdict for p in pipeline.frames(ListSource(20, fps=10.0))]
    assert [v.speed_kmh for v in verdicts] == [10.0] * 6 + [None] * 4 + [70.0] * 6 + [None] * 4
    assert [v.moving for v in verdicts] == [False] * 6 + [True] * 14


def test_a_plain_speed_function_is_the_bus() -> None:
    speed = vehicle_speed(lambda: 33.0)
    assert isinstance(speed, BusSpeed) and speed.kmh_at(123.0) == 33.0
    track = SpeedTrack((0.0,), (1.0,))
    assert vehicle_speed(track) is track
