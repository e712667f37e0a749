"""The log says when a known speed holds alerts back and when that stops: a start at most once
per 10 s of the drive (a flapping speed is summed up), every logged start's stop, the total."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from fakes import ListSource, ScriptedDetector
from roadgaze.config import Config
from roadgaze.pipeline import RunOptions, build_run


def test_the_speed_gate_is_logged_when_it_starts_and_stops(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    speeds = [(0.0, 10), (2.0, 60), (3.0, 10), (4.0, 60), (14.0, 10)]
    rows = [
        f"{t / 2:g},{next(kmh for start, kmh in reversed(speeds) if t / 2 >= start)}\n"
        for t in range(32)
    ]
    track = tmp_path / "track.csv"
    track.write_text("t_s,kmh\n" + "".join(rows), encoding="utf-8")
    options = RunOptions("drive.mp4", command="replay", speed_track=track)
    with (
        caplog.at_level(logging.INFO, logger="roadgaze.replay"),
        build_run(
            Config(), options, source=ListSource(160, 10.0), detector=ScriptedDetector([0.0] * 160)
        ) as run,
    ):
        run.run()
    lines = [r.getMessage().removeprefix("replay drive.mp4: ") for r in caplog.records]
    gate = [line for line in lines if "held back" in line or "allowed again" in line]
    assert gate == [
        "vehicle speed 10 km/h at t=0.00 s, at or below the active speed of the configured "
        "protocols: alerts held back",
        "vehicle speed 60 km/h at t=2.00 s, alerts allowed again",
        "vehicle speed 10 km/h at t=14.00 s, at or below the active speed of the configured "
        "protocols: alerts held back; 2 more changes since the last line",
        "alerts were held back by the vehicle speed for 4.9 s in all (3 times)",
    ]
