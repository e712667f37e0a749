"""The `model`, `estimate` and `eval` sub-commands through the real command line."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from skimage import data as skimage_data

from roadgaze.cli import main
from roadgaze.config import ModelConfig
from roadgaze.landmarks.model_store import MODEL_FILENAME, check_file, resolve_model


@pytest.fixture(scope="module")
def real_model() -> Path:
    """The user's verified model (fetched on first use in a fresh clone)."""
    return resolve_model(ModelConfig(), environ={})


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("set")
    bgr = cv2.cvtColor(skimage_data.astronaut(), cv2.COLOR_RGB2BGR)
    cv2.imwrite(str(root / "astronaut.png"), bgr)
    cv2.imwrite(str(root / "mirrored.png"), np.ascontiguousarray(bgr[:, ::-1]))
    (root / "corrupt.jpg").write_bytes(b"not an image")
    (root / "ground_truth.csv").write_text(
        "file,yaw_deg,pitch_deg\nastronaut.png,0,0\nmirrored.png,0,0\ncorrupt.jpg,10,0\n"
        "missing.jpg,0,90\n",
        encoding="utf-8",
    )
    return root


def test_model_fetch_copies_explicit_file_without_network(
    tmp_path: Path,
    real_model: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setenv("ROADGAZE_MODEL_PATH", str(real_model))
    monkeypatch.setenv("ROADGAZE_CACHE_DIR", str(tmp_path / "cache"))
    assert main(["model", "fetch"]) == 0
    cached = tmp_path / "cache" / MODEL_FILENAME
    assert capsys.readouterr().out.strip() == str(cached)
    assert check_file(cached) is None
    assert main(["model", "verify"]) == 0
    out = capsys.readouterr().out
    assert f"explicit: {real_model}: ok" in out and f"cache: {cached}: ok" in out


@pytest.mark.parametrize(
    ("settings", "says", "never_says"),
    [
        ([], ["will download it from https://", "roadgaze model fetch"], "downloads are disabled"),
        (
            ["--set", "model.allow_download=false"],
            ["downloads are disabled", "place the file by hand"],
            "will download",
        ),
    ],
    ids=["downloads-allowed", "downloads-disabled"],
)
def test_model_path_without_model_says_what_will_happen(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    settings: list[str],
    says: list[str],
    never_says: str,
) -> None:
    monkeypatch.delenv("ROADGAZE_MODEL_PATH", raising=False)
    monkeypatch.setenv("ROADGAZE_CACHE_DIR", str(tmp_path / "empty"))
    assert main(["model", "path", *settings]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    error_lines = [line for line in captured.err.splitlines() if line.startswith("roadgaze")]
    assert len(error_lines) == 1
    for text in says:
        assert text in error_lines[0]
    assert never_says not in error_lines[0]
    assert str(tmp_path / "empty" / MODEL_FILENAME) in error_lines[0]
    assert not (tmp_path / "empty").exists()  # nothing was downloaded
    assert main(["model", "verify"]) == 1


@pytest.mark.parametrize("action", ["fetch", "path", "verify"])
def test_model_actions_describe_themselves(action: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["model", action, "--help"])
    _usage, _, rest = capsys.readouterr().out.partition("\n\n")
    description = rest.split("\n\n")[0]
    assert len(description.split()) >= 15, description  # a paragraph, not just the usage


def test_estimate_prints_one_json_object_per_image(
    folder: Path,
    real_model: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setenv("ROADGAZE_MODEL_PATH", str(real_model))
    images = [folder / "astronaut.png", folder / "nothing.png", folder / "mirrored.png"]
    assert main(["estimate", *map(str, images)]) == 1
    captured = capsys.readouterr()
    objects = [json.loads(line) for line in captured.out.splitlines()]
    assert [o["file"] for o in objects] == list(map(str, images))
    first, missing, mirrored = objects
    for key in (
        "face",
        "yaw_deg",
        "models",
        "x_left",
        "x_right",
        "x_center",
        "roll_deg",
        "mediapipe_yaw_deg",
    ):
        assert key in first
    assert first["face"] is True and first["yaw_deg"] == first["models"]["center_ce"]
    assert set(first["models"]) == {"cylindrical", "ellipsoidal", "ce", "center_ce", "boundary_ce"}
    assert first["x_left"] < first["x_center"] < first["x_right"]
    assert mirrored["yaw_deg"] == pytest.approx(-first["yaw_deg"], abs=1.0)
    assert missing["face"] is False and "file not found" in missing["error"]
    assert "file not found" in captured.err
    # Rounded as `replay` rounds: angles to 3 decimals, pixels to 2 (not 16 digits).
    assert first["yaw_deg"] == round(first["yaw_deg"], 3)
    assert first["mediapipe_pitch_deg"] == round(first["mediapipe_pitch_deg"], 3)
    assert first["x_left"] == round(first["x_left"], 2)
    assert all(len(repr(value)) <= 9 for value in first["models"].values())


def test_eval_writes_every_output(
    folder: Path,
    tmp_path: Path,
    real_model: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setenv("ROADGAZE_MODEL_PATH", str(real_model))
    outputs = {
        "--report": tmp_path / "report.json",
        "--predictions": tmp_path / "predictions.csv",
        "--plot": tmp_path / "eval.png",
        "--compare-landmarks": tmp_path / "landmarks.md",
    }
    arguments = ["eval", str(folder), "--workers", "1", "--no-progress", "--refit"]
    for option, path in outputs.items():
        arguments += [option, str(path)]
    assert main(arguments) == 0
    out = capsys.readouterr().out
    assert "3 images scored (1 skipped with |pitch| = 90, 1 unreadable)" in out
    assert "global re-fit" in out
    report = json.loads(outputs["--report"].read_text())
    center = report["ranges"]["all"]["center_ce"]
    assert center["n_images"] == 3 and center["n_faces"] == 2
    assert center["detection_rate"] == pytest.approx(2 / 3, abs=1e-3)
    with outputs["--predictions"].open() as stream:
        rows = list(csv.DictReader(stream))
    assert [r["file"] for r in rows] == ["astronaut.png", "mirrored.png", "corrupt.jpg"]
    assert [r["face"] for r in rows] == ["1", "1", "0"]
    assert float(rows[0]["yaw_center_ce"]) == pytest.approx(-float(rows[1]["yaw_center_ce"]), abs=1)
    assert rows[2]["yaw_mediapipe"] == ""
    assert cv2.imread(str(outputs["--plot"])) is not None
    assert "**(default)**" in outputs["--compare-landmarks"].read_text()


def test_eval_bad_dataset_is_one_line_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["eval", str(tmp_path), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "ground_truth.csv not found" in err


def test_estimate_as_a_process_has_clean_stderr(
    folder: Path, real_model: Path, subprocess_env: dict[str, str]
) -> None:
    """No traceback and no MediaPipe start-up noise; the bad file is named on one line."""
    import subprocess
    import sys

    env = {**subprocess_env, "ROADGAZE_MODEL_PATH": str(real_model)}
    completed = subprocess.run(
        [
            sys.executable,
            "-m",
            "roadgaze",
            "estimate",
            str(folder / "corrupt.jpg"),
            str(folder / "astronaut.png"),
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        check=False,
    )
    assert completed.returncode == 1
    lines = [json.loads(line) for line in completed.stdout.splitlines()]
    assert [line["face"] for line in lines] == [False, True]
    assert completed.stderr.strip().splitlines() == [
        f"roadgaze estimate: {folder / 'corrupt.jpg'}: cannot decode as an image (corrupt or "
        "unsupported format)"
    ]
