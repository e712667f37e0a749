"""An interpreter with MediaPipe 0.10.14, the reference the LiteRT hand and pose engines are held
to (tests/landmarks/test_hands.py, test_pose.py)."""

from __future__ import annotations

import csv
import json
import subprocess
import venv
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest

REFERENCE_PACKAGES = (
    "numpy<2",
    "protobuf<5",
    "absl-py",
    "attrs",
    "flatbuffers",
)


def reference_python(cache: Path) -> Path:
    """An interpreter with mediapipe 0.10.14 (made once, kept in the cache); skips when pip
    cannot install it here."""
    folder = cache / "mediapipe-0.10.14-reference"
    python = folder / "bin" / "python"
    if (folder / "ready").is_file():
        return python
    venv.create(folder, with_pip=True, clear=True)
    for arguments in (["--no-deps", "mediapipe==0.10.14"], list(REFERENCE_PACKAGES)):
        done = subprocess.run(
            [str(python), "-m", "pip", "install", "-q", "--disable-pip-version-check", *arguments],
            capture_output=True,
            text=True,
            timeout=900,
            check=False,
        )
        if done.returncode != 0:
            pytest.skip(f"cannot install the reference mediapipe 0.10.14: {done.stderr[-300:]}")
    (folder / "ready").write_text("ok\n")
    return python


def reference_on_drivers(
    cache: Path, script: str, every: int, folder: Path
) -> tuple[dict[str, npt.NDArray[np.uint8]], Any]:
    """Every `every`-th State Farm development image (RGB, by its file with `/` as `_`) and what
    `scripts/<script>` prints for them under MediaPipe 0.10.14 (its JSON, read back)."""
    import cv2

    from repo_paths import REPO, STATEFARM

    with (STATEFARM / "ground_truth.csv").open(encoding="utf-8") as stream:
        rows = list(csv.DictReader(stream))[::every]
    images = {
        row["file"].replace("/", "_"): np.ascontiguousarray(
            cv2.imread(str(STATEFARM / row["file"]))[:, :, ::-1]
        )
        for row in rows
    }
    np.savez(folder / "images.npz", **images)
    subprocess.run(
        [
            str(reference_python(cache)),
            str(REPO / "scripts" / script),
            str(folder / "images.npz"),
            str(folder / "reference.json"),
        ],
        check=True,
        capture_output=True,
        timeout=600,
    )
    return images, json.loads((folder / "reference.json").read_text())
