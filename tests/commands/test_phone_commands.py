"""Phone detection through the real command line: `estimate` with and without the hand models,
`model verify hands`, `eval --task phone` on bad input."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from repo_paths import STATEFARM, child_env
from roadgaze.config import ModelConfig
from roadgaze.landmarks.model_store import resolve_model

IMAGE = STATEFARM / "images" / "c2" / "img_90391.jpg"


def _roadgaze(*arguments: str, **env: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "roadgaze", *arguments],
        capture_output=True,
        text=True,
        timeout=300,
        env=child_env(**env),
        check=False,
    )


@pytest.fixture(scope="module")
def face_model() -> Path:
    return resolve_model(ModelConfig(), environ={})


def test_estimate_without_hand_models_still_works_and_says_how_to_fetch_them(
    tmp_path: Path, face_model: Path
) -> None:
    if not IMAGE.is_file():
        pytest.skip(f"no State Farm development images at {STATEFARM}")
    done = _roadgaze(
        "estimate",
        str(IMAGE),
        ROADGAZE_CACHE_DIR=str(tmp_path),
        ROADGAZE_MODEL_PATH=str(face_model),
    )
    assert done.returncode == 0, done.stderr
    fields = json.loads(done.stdout)
    assert fields["phone_use"] is None and fields["n_hands"] is None
    warnings = [line for line in done.stderr.splitlines() if "phone detection is off" in line]
    assert len(warnings) == 1 and "roadgaze model fetch hands" in warnings[0]
    assert "palm_detection_lite.tflite" in warnings[0]
    assert "Traceback" not in done.stderr


def test_estimate_judges_a_phone_at_the_ear(face_model: Path) -> None:
    if not IMAGE.is_file():
        pytest.skip(f"no State Farm development images at {STATEFARM}")
    from roadgaze.landmarks.hands.models import fetch_hand_models

    fetch_hand_models(ModelConfig())
    done = _roadgaze("estimate", str(IMAGE))
    assert done.returncode == 0, done.stderr
    fields = json.loads(done.stdout)
    assert fields["n_hands"] >= 1
    assert isinstance(fields["phone_use"], bool) and 0.0 <= fields["phone_score"] <= 1.0


def test_model_verify_hands_names_each_file(tmp_path: Path) -> None:
    done = _roadgaze("model", "verify", "hands", ROADGAZE_CACHE_DIR=str(tmp_path))
    assert done.returncode == 1
    lines = done.stdout.splitlines()
    assert len(lines) == 6 and all("not found" in line for line in lines)
    assert "hand_landmark_full.tflite" in done.stdout
    assert "pose_landmark_full.tflite" in done.stdout


def test_eval_task_phone_bad_dataset_is_one_line(tmp_path: Path) -> None:
    (tmp_path / "ground_truth.csv").write_text("file,yaw_deg\na.jpg,1\n", encoding="utf-8")
    done = _roadgaze("eval", str(tmp_path), "--task", "phone")
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and "file,phone_use" in done.stderr


@pytest.mark.parametrize(
    ("conditions", "message"),
    [
        (["ir_grey", "dark"], "--task phone takes one --condition, found ir_grey, dark"),
        (["all"], "--task phone takes one --condition, found all"),
        (["infrared"], "unknown condition 'infrared'"),
    ],
)
def test_eval_task_phone_takes_one_known_condition(
    tmp_path: Path, conditions: list[str], message: str
) -> None:
    (tmp_path / "ground_truth.csv").write_text("file,phone_use\na.jpg,1\n", encoding="utf-8")
    flags = [part for name in conditions for part in ("--condition", name)]
    done = _roadgaze("eval", str(tmp_path), "--task", "phone", *flags)
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and message in done.stderr
