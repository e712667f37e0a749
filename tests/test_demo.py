"""roadgaze.demo: the whole service on a synthetic drive, alerts received over Zenoh."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from roadgaze.config import Config
from roadgaze.demo import format_alert, run_demo
from roadgaze.synth import parse_timeline, read_truth_csv

SHORT_DRIVE = "0:1,0/-35:3.8,0:1"
"""A 3.8 s look into the lap: one long-distraction alert, then cleared. (Before zones the glance
went 40 deg to the left, now the left mirror, which raises no long distraction.)"""


@pytest.mark.slow
def test_run_demo_delivers_every_alert_to_the_subscriber(tmp_path: Path) -> None:
    printed: list[dict[str, Any]] = []
    result = run_demo(
        tmp_path / "demo",
        Config(),
        timeline=parse_timeline(SHORT_DRIVE),
        size=(320, 240),
        on_alert=printed.append,
    )
    assert result.frames == round(5.8 * 15) == result.frames_with_face
    assert result.alerts_raised == 2
    assert [m["kind"] for m in result.alerts_received] == ["long_distraction", "cleared"]
    assert printed == list(result.alerts_received)
    assert result.yaw_mae_deg < 6.0
    for path in result.files:
        assert path.is_file() and path.stat().st_size > 0, path
    folder = tmp_path / "demo"
    assert sorted(p.name for p in folder.iterdir()) == sorted(
        ["drive.mp4", "truth.csv", "frames.jsonl", "alerts.jsonl", "yaw.png", "annotated.mp4"]
    )
    frames = [json.loads(line) for line in (folder / "frames.jsonl").read_text().splitlines()]
    truth = read_truth_csv(folder / "truth.csv")
    assert len(frames) == len(truth) == result.frames
    np.testing.assert_allclose([f["t_s"] for f in frames], truth[:, 0], atol=1e-3)
    alerts = [json.loads(line) for line in (folder / "alerts.jsonl").read_text().splitlines()]
    assert alerts == list(result.alerts_received)
    assert alerts[0]["schema"] == "roadgaze.alert/4" and abs(alerts[0]["yaw_deg"]) < 10.0
    assert frames[-1]["gaze"] == "on_road" and frames[-1]["zone"] == "road"
    looking_down = [f for f in frames if 2.0 <= f["t_s"] <= 4.5]
    assert {f["zone"] for f in looking_down} == {"lap"}
    assert all(f["pitch_deg"] - f["neutral_pitch_deg"] < -25.0 for f in looking_down)
    assert all(f["yaw_offline_deg"] is not None for f in frames)  # filled at the end


def test_format_alert_is_one_readable_line() -> None:
    line = format_alert(
        {
            "seq": 0,
            "kind": "long_distraction",
            "level": "warning",
            "t_s": 6.4,
            "off_road_s": 3.0,
            "window_off_road_s": 3.0,
            "yaw_deg": 32.14,
        }
    )
    assert line == (
        "subscriber received alert #0: long_distraction warning at t=6.40 s "
        "(off road 3.00 s, 3.00 s in the window; yaw +32.1 deg)"
    )
    assert "undecodable" in format_alert({"undecodable": "x"})


@pytest.mark.slow
def test_cli_demo_prints_alerts_as_received(tmp_path: Path, subprocess_env: dict[str, str]) -> None:
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "roadgaze",
            "demo",
            "--out",
            str(tmp_path / "d"),
            "--timeline",
            SHORT_DRIVE,
        ],
        capture_output=True,
        text=True,
        env=subprocess_env,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    received = [line for line in result.stdout.splitlines() if "subscriber received alert" in line]
    assert len(received) == 2 and "long_distraction warning" in received[0]
    assert "2 alerts raised, 2 received by the subscriber" in result.stdout
    # Results on stdout, the rest on stderr; each alert told once (by the subscriber).
    assert all(line.startswith("demo: ") for line in result.stdout.splitlines())
    assert "long_distraction" not in result.stderr and "cleared" not in result.stderr
    written = [
        line.split(": wrote ")[1] for line in result.stderr.splitlines() if ": wrote " in line
    ]
    assert sorted(Path(path).name for path in written) == sorted(
        ["drive.mp4", "truth.csv", "frames.jsonl", "alerts.jsonl", "yaw.png", "annotated.mp4"]
    )
    assert "demo: rendering" in result.stderr
    # A normal finish: no warning (the subscriber leaving first used to read as a link down).
    assert " WARNING " not in result.stderr and "link down" not in result.stderr


def test_cli_demo_rejects_a_bad_timeline(tmp_path: Path, subprocess_env: dict[str, str]) -> None:
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "roadgaze",
            "demo",
            "--out",
            str(tmp_path / "d"),
            "--timeline",
            "0:1,far:2",
        ],
        capture_output=True,
        text=True,
        env=subprocess_env,
        timeout=60,
        check=False,
    )
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        "roadgaze demo: error: timeline keyframe 'far:2': yaw 'far' is not a number "
        "(expected YAW[/PITCH]:SECONDS, e.g. 40:3.5 or 30/-10:2)"
    ]


def test_the_demo_fetches_missing_hand_models_unless_downloads_are_off(tmp_path: Path) -> None:
    """A first run on a fresh machine shows the whole service: the demo fetches the hand models
    (the daemon never does); with downloads off it leaves the cache alone."""
    from roadgaze.config.settings import ModelConfig
    from roadgaze.demo import fetch_hand_models_for_demo
    from roadgaze.landmarks.hands.models import MODEL_FILES, find_hand_models

    said: list[str] = []
    off = Config(model=ModelConfig(cache_dir=tmp_path / "off", allow_download=False))
    fetch_hand_models_for_demo(off, said.append)
    assert said == [] and not (tmp_path / "off").exists()
    on = Config(model=ModelConfig(cache_dir=tmp_path / "on"))
    fetch_hand_models_for_demo(on, said.append)
    found, missing = find_hand_models(on.model, tuple(MODEL_FILES))
    if missing:
        pytest.skip(f"hand models could not be fetched here: {missing}")
    assert said == ["fetching the hand models (roadgaze model fetch hands)"]
    assert sorted(found) == sorted(MODEL_FILES)
    fetch_hand_models_for_demo(on, said.append)  # all there: nothing more to fetch
    assert len(said) == 1
