"""Forward and lane support the way a user meets it: `roadgaze schema support` and the records
of `roadgaze replay --out` (JSON lines and CSV) from a fresh process, on a rendered drive with a
4 s mirror look at 70 km/h."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from repo_paths import child_env

MIRROR_LOOK = "0:3,35:4,0:3"
"""Ahead 3 s, 4 s at the driver-side mirror of a left-hand-drive car (yaw +35), ahead 3 s."""


def roadgaze(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "roadgaze", *args],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=300,
        check=False,
    )


def test_roadgaze_schema_lists_the_support_message() -> None:
    done = roadgaze("schema", "support")
    assert done.returncode == 0, done.stderr
    schema = json.loads(done.stdout)
    assert schema["properties"]["schema"]["const"] == "roadgaze.support/1"
    assert {"forward", "lane", "t_s", "seq", "vehicle_id"} <= set(schema["required"])
    every = json.loads(roadgaze("schema").stdout)
    assert set(every) == {"yaw", "alert", "state", "support"}
    state = every["state"]
    assert state["properties"]["schema"]["const"] == "roadgaze.state/6"


@pytest.mark.slow
def test_replay_records_carry_support_raised_by_a_mirror_look(
    synthetic_clip: Callable[..., Any], tmp_path: Path
) -> None:
    clip, _ = synthetic_clip(MIRROR_LOOK)
    jsonl, table = tmp_path / "drive.jsonl", tmp_path / "drive.csv"
    args = ("--out", str(jsonl), "--csv", str(table), "--speed-kmh", "70", "--no-progress")
    done = roadgaze("replay", str(clip), *args)
    assert done.returncode == 0, done.stderr
    records = [json.loads(line) for line in jsonl.read_text(encoding="utf-8").splitlines()]
    with table.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert [r["support_forward"] for r in rows] == [r["support_forward"] for r in records]
    assert [r["support_lane"] for r in rows] == [r["support_lane"] for r in records]
    forward = [(r["t_s"], r["support_forward"], r["zone"]) for r in records]
    before = [level for t_s, level, _ in forward if 2.5 <= t_s < 3.0]
    assert before and set(before) == {"normal"}  # watched the road 2 s: normal before the look
    raised = next(t_s for t_s, level, _ in forward if t_s >= 3.0 and level == "heightened")
    assert raised - 3.0 <= 0.5  # within 0.5 s of the look's start (the head's turn included)
    left = next(t_s for t_s, _, zone in forward if t_s >= 3.0 and zone != "road")
    assert raised <= left + 1e-6  # at the first frame off the road
    held = [level for t_s, level, _ in forward if raised <= t_s < 7.0]
    assert set(held) == {"heightened"}
    assert forward[-1][1] == "normal"  # 2 s back on the road (ends at 10 s)
