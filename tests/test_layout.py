"""The source tree reads as the pipeline: pure stages stay pure, files stay small, folders say
what they do and export their public names."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys

import pytest

from repo_paths import SRC, child_env

PACKAGE = SRC / "roadgaze"
PURE_MODULES = (
    "roadgaze.types",
    "roadgaze.pose.geometry",
    "roadgaze.pose.smoothing",
    "roadgaze.pose.mounting",
    "roadgaze.pose",
    "roadgaze.monitor",
    "roadgaze.monitor.eyes",
    "roadgaze.monitor.eye_rules",
    "roadgaze.monitor.escalation",
    "roadgaze.monitor.neutral",
    "roadgaze.transport.messages",
    "roadgaze.transport.keys",
    "roadgaze.transport.speed",
    "roadgaze.speed",
    "roadgaze.transport.vss",
    "roadgaze.landmarks.features",
    "roadgaze.landmarks.driver",
    "roadgaze.landmarks.eyes",
    "roadgaze.config",
    "roadgaze.eye_records",
    "roadgaze.evaluation.stats",
    "roadgaze.synth.timeline",
)
"""Pose maths, the monitor, the message schemas and the feature maths: numpy and pydantic only."""
HEAVY = ("cv2", "mediapipe", "zenoh")
MAX_LINES = 400
FOLDERS = sorted(p for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").is_file())


def test_pure_modules_import_no_opencv_mediapipe_or_zenoh() -> None:
    """One interpreter imports them in turn: the first that pulls in a heavy module is named."""
    code = (
        "import importlib, sys\n"
        f"for module in {PURE_MODULES!r}:\n"
        "    importlib.import_module(module)\n"
        f"    bad = sorted({set(HEAVY)!r} & set(sys.modules))\n"
        "    if bad:\n"
        "        print(module, 'imports', ' '.join(bad)); sys.exit(1)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=120,
        env=child_env(),
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr


def test_no_source_file_is_over_400_lines() -> None:
    long_files = {
        str(path.relative_to(SRC)): count
        for path in PACKAGE.rglob("*.py")
        if (count := len(path.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert long_files == {}


@pytest.mark.parametrize("folder", FOLDERS, ids=lambda path: path.name)
def test_each_folder_states_its_job_in_one_line_and_exports_its_names(folder: object) -> None:
    init = folder / "__init__.py"  # type: ignore[operator]
    tree = ast.parse(init.read_text(encoding="utf-8"))
    docstring = ast.get_docstring(tree)
    assert docstring is not None and "\n" not in docstring.strip(), f"{init}: one-line docstring"
    module = importlib.import_module(f"roadgaze.{folder.name}")  # type: ignore[attr-defined]
    exported = getattr(module, "__all__", None)
    assert exported, f"{init} has no __all__"
    for name in exported:
        assert hasattr(module, name), f"roadgaze.{folder.name}.{name} is exported but missing"


def test_the_yaw_models_stay_importable_from_their_old_path() -> None:
    from roadgaze.geometry import YAW_MODELS as OLD
    from roadgaze.pose.geometry import YAW_MODELS

    assert OLD is YAW_MODELS and list(OLD) == [
        "cylindrical",
        "ellipsoidal",
        "ce",
        "center_ce",
        "boundary_ce",
    ]
