"""An interpreter with MediaPipe 0.10.14, the reference the LiteRT hand and pose engines are held
to (tests/landmarks/test_hands.py, test_pose.py)."""

from __future__ import annotations

import subprocess
import venv
from pathlib import Path

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
