"""Speed track files: CSV and Parquet read by one reader into bounded memory, values and types
checked, every refusal one line naming the file and line; the track beside a video; the choice
of a drive's speed."""

from __future__ import annotations

import datetime
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from roadgaze.cli import main
from roadgaze.errors import ConfigError, SpeedError
from roadgaze.speed import (
    MAX_LINE_CHARS,
    ConstantSpeed,
    SpeedTrack,
    read_speed_track,
    recorded_speed,
    track_beside,
)

pytestmark = pytest.mark.usefixtures("restore_logging")


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def test_a_csv_track_with_unknown_samples(tmp_path: Path) -> None:
    track = read_speed_track(write(tmp_path / "d.speed.csv", "t_s,kmh\n1,10\n2,70\n6,\n7,30\n"))
    assert track.t_s.tolist() == [1.0, 2.0, 6.0, 7.0]
    assert track.kmh[[0, 1, 3]].tolist() == [10.0, 70.0, 30.0] and math.isnan(track.kmh[2])
    assert track.name == str(tmp_path / "d.speed.csv")


def test_extra_columns_blank_lines_and_a_bom_are_fine_and_nan_is_unknown(tmp_path: Path) -> None:
    path = tmp_path / "t.csv"
    path.write_bytes("\ufeffcan_id, t_s ,kmh\n7,0,nan\n\n7,0.5,55.5\n".encode())
    track = read_speed_track(path, hold_s=0.25)
    assert track.kmh_at(0.1) is None and track.kmh_at(0.6) == 55.5 and track.kmh_at(0.8) is None


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "header with the columns t_s,kmh"),
        ("t_s,speed\n0,1\n", "header with the columns t_s,kmh"),
        ("t_s,kmh,kmh\n0,1,2\n", "header with the columns t_s,kmh, once each"),
        ("t_s,kmh\n", "has no sample"),
        ("t_s,kmh\n0,10\n0,20\n", "line 3: t_s 0 is not after the previous 0"),
        ("t_s,kmh\n0,fast\n", "line 2: kmh 'fast' is not a number"),
        ("t_s,kmh\n0,True\n", "line 2: kmh 'True' is not a number"),
        ("t_s,kmh\n0,-1\n", "line 2: kmh -1 is not a speed within 0-400 km/h"),
        ("t_s,kmh\n0,inf\n", "within 0-400"),
        ("t_s,kmh\nnan,1\n", "line 2: t_s 'nan' is not a finite number"),
        ("t_s,kmh\n,1\n", "line 2: t_s '' is not a number"),
        ("t_s,kmh\n0,1\n" + "9" * (MAX_LINE_CHARS + 5) + "\n", "line 3 is longer than"),
    ],
)
def test_a_bad_csv_is_one_line_naming_the_line(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(SpeedError, match=message) as caught:
        read_speed_track(write(tmp_path / "bad.csv", text))
    assert "\n" not in str(caught.value)


def test_missing_and_wrong_kind_of_file(tmp_path: Path) -> None:
    with pytest.raises(SpeedError, match="not found"):
        read_speed_track(tmp_path / "none.csv")
    with pytest.raises(SpeedError, match=r"expected a \.csv or \.parquet"):
        read_speed_track(write(tmp_path / "s.txt", "t_s,kmh\n0,1\n"))
    (tmp_path / "latin.csv").write_bytes(b"t_s,kmh\n0,\xe9\n")
    with pytest.raises(SpeedError, match="cannot read speed track"):
        read_speed_track(tmp_path / "latin.csv")
    (tmp_path / "broken.parquet").write_bytes(b"PAR1 not really")
    pytest.importorskip("pyarrow")
    with pytest.raises(SpeedError, match="cannot read speed track"):
        read_speed_track(tmp_path / "broken.parquet")


def parquet(path: Path, columns: dict[str, Any]) -> Path:
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    pq.write_table(pa.table(columns), path)
    return path


def test_a_parquet_track_of_floats_integers_or_decimals(tmp_path: Path) -> None:
    from decimal import Decimal

    path = parquet(tmp_path / "d.speed.parquet", {"t_s": [0.0, 1.0], "kmh": [None, 42.0]})
    track = read_speed_track(path)
    assert track.kmh_at(0.5) is None and track.kmh_at(2.0) == 42.0
    path = parquet(tmp_path / "i.parquet", {"t_s": [0, 1, 2], "kmh": [10, None, 30]})
    assert [read_speed_track(path).kmh_at(t) for t in (0, 1, 2)] == [10.0, None, 30.0]
    path = parquet(tmp_path / "m.parquet", {"t_s": [0, 1], "kmh": [Decimal("12.5"), None]})
    assert read_speed_track(path).kmh_at(0.5) == 12.5
    path = parquet(tmp_path / "bad.parquet", {"t_s": [0.0, 1.0], "kmh": [10.0, 500.0]})
    with pytest.raises(
        SpeedError, match=r"bad\.parquet row 2: kmh 500 is not a speed within 0-400"
    ):
        read_speed_track(path)
    path = parquet(tmp_path / "order.parquet", {"t_s": [1.0, 0.5], "kmh": [1.0, 2.0]})
    with pytest.raises(SpeedError, match=r"row 2: t_s 0\.5 is not after the previous 1"):
        read_speed_track(path)
    path = parquet(tmp_path / "none.parquet", {"time": [0.0]})
    with pytest.raises(SpeedError, match="no column t_s, kmh"):
        read_speed_track(path)


@pytest.mark.parametrize(
    ("column", "values", "kind"),
    [
        ("kmh", [False, False], "bool"),
        ("kmh", [datetime.datetime(2024, 1, 1), datetime.datetime(2024, 1, 2)], "timestamp"),
        ("kmh", [datetime.date(2024, 1, 1), datetime.date(2024, 1, 2)], "date32"),
        ("kmh", [[1.0], [2.0]], "list"),
        ("kmh", [{"v": 1.0}, {"v": 2.0}], "struct"),
        ("kmh", ["12", "13"], "string"),
        ("t_s", [True, False], "bool"),
        ("t_s", [datetime.datetime(2024, 1, 1), datetime.datetime(2024, 1, 2)], "timestamp"),
    ],
)
def test_a_parquet_column_that_is_not_numbers_is_refused(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    column: str,
    values: list[Any],
    kind: str,
) -> None:
    """A column of False read as 0 km/h would silence every alert; a timestamp column was a
    TypeError traceback."""
    columns: dict[str, Any] = {"t_s": [0.0, 1.0], "kmh": [50.0, 50.0], column: values}
    path = parquet(tmp_path / "drive.speed.parquet", columns)
    with pytest.raises(SpeedError, match=f"column {column} holds {kind}"):
        read_speed_track(path)
    # the same through the commands: one line, exit 2, before any video or bus
    for argv in (
        ["replay", str(tmp_path / "missing.mp4"), "--speed-track", str(path)],
        ["speed", "--track", str(path)],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and f"column {column} holds {kind}" in err, err


def test_memory_is_bounded_by_a_setting_not_by_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Every row costs 16 bytes in two arrays; past `capture.speed_track_max_rows` the track is
    refused (one line, exit 2)."""
    rows = "".join(f"{i / 10:g},50\n" for i in range(101))
    csv_path = write(tmp_path / "long.csv", "t_s,kmh\n" + rows)
    track = read_speed_track(csv_path, max_rows=101)
    assert track.t_s.dtype == np.float64 and track.t_s.nbytes == 101 * 8
    with pytest.raises(SpeedError, match=r"more than 100 rows \(capture.speed_track_max_rows\)"):
        read_speed_track(csv_path, max_rows=100)
    long_parquet = parquet(
        tmp_path / "long.parquet", {"t_s": [i / 10 for i in range(101)]} | {"kmh": [50.0] * 101}
    )
    with pytest.raises(SpeedError, match="more than 100 rows"):
        read_speed_track(long_parquet, max_rows=100)
    limit = ["--set", "capture.speed_track_max_rows=100"]
    for argv in (
        ["replay", str(tmp_path / "missing.mp4"), "--speed-track", str(csv_path), *limit],
        ["speed", "--track", str(csv_path), *limit],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "has more than 100 rows" in err, err


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
    with pytest.raises(SpeedError, match="--speed-kmh nan is not a speed within 0-400"):
        recorded_speed(video, constant_kmh=float("nan"))
    write(tmp_path / "drive.speed.parquet", "")
    with pytest.raises(SpeedError, match="two speed tracks"):
        recorded_speed(video)
