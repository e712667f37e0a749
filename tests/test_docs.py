"""The documentation stands alone: nothing points outside the repository, and the closed-form
table of docs/paper.md is what the code computes."""

from __future__ import annotations

import re
import sys

import numpy as np
import pytest

from repo_paths import REPO
from roadgaze.pose.geometry import YAW_MODELS, expected_error_deg

MODEL_LABELS = {
    "cylindrical": "cylindrical",
    "ellipsoidal": "ellipsoidal",
    "ce": "CE",
    "center_ce": "Center-CE",
    "boundary_ce": "Boundary-CE",
}


def user_files() -> list:
    files = [REPO / "README.md", REPO / "CHANGELOG.md"]
    for folder, pattern in (
        ("config", "*"),
        ("docs", "*"),
        ("src", "*.py"),
        ("scripts", "*"),
        ("deploy", "*"),
        ("docker", "*"),
    ):
        files += [path for path in (REPO / folder).rglob(pattern) if path.is_file()]
    return [path for path in files if path.suffix not in {".png", ".pyc"}]


def test_no_file_a_user_has_points_outside_the_repository() -> None:
    outside = re.compile(r"PAPER\.md|\.\./" + "shared")
    found = [
        f"{path.relative_to(REPO)}:{number}"
        for path in user_files()
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1)
        if outside.search(line)
    ]
    assert found == []


def test_ci_runs_the_readmes_test_command_exactly() -> None:
    """The README's second command (install and run the tests, in parallel) is the line
    `.ci/run` runs, so what a user types is what CI checks."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    commands = re.findall(r"^python3 -m venv .*$", readme, flags=re.MULTILINE)
    assert len(commands) >= 2 and "pytest -n auto" in commands[1], commands
    ci_lines = (REPO / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    assert commands[1] in ci_lines


def test_tests_find_the_evaluation_data_in_one_place() -> None:
    """Only tests/repo_paths.py knows where the data is ($ROADGAZE_DATA, else beside the
    development checkout)."""
    beside = "../" + "shared"
    found = [
        str(path.relative_to(REPO))
        for path in (REPO / "tests").rglob("*.py")
        if path.name != "repo_paths.py" and beside in path.read_text()
    ]
    assert found == []


def test_the_closed_form_table_of_paper_md_is_what_the_code_computes() -> None:
    text = (REPO / "docs" / "paper.md").read_text()
    header = re.search(r"^\| true yaw \(deg\) \|(.+)\|$", text, re.MULTILINE)
    assert header is not None
    yaws = [float(cell) for cell in header.group(1).split("|")]
    text = text[header.end() :]
    for model in YAW_MODELS:
        row = re.search(rf"^\| {re.escape(MODEL_LABELS[model])} \|(.+)\|$", text, re.MULTILINE)
        assert row is not None, model
        documented = [float(cell) for cell in row.group(1).split("|")]
        np.testing.assert_allclose(documented, expected_error_deg(model, yaws), atol=0.005)


@pytest.mark.parametrize("name", ["paper.md", "landmarks.md", "pose.md"])
def test_docs_link_to_files_that_exist(name: str) -> None:
    text = (REPO / "docs" / name).read_text()
    for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", text):
        assert (REPO / "docs" / target).exists(), f"docs/{name} links to missing {target}"


INSTALLED_IMPORTS = {
    "roadgaze", "numpy", "cv2", "mediapipe", "zenoh", "pydantic", "matplotlib", "tqdm", "skimage",
    "filterpy", "cryptography", "pyarrow", "ray", "foxglove", "mcap",
}  # fmt: skip
"""What `pip install roadgaze` and its extras (fleet, ray, foxglove) bring, by import name."""


def test_python_examples_in_the_docs_import_only_what_the_install_has_or_say_how() -> None:
    """A snippet importing anything else (pandas, once) must say `pip install NAME` just before."""
    missing = []
    for path in [*(REPO / "docs").glob("*.md"), REPO / "README.md"]:
        text = path.read_text(encoding="utf-8")
        for block in re.finditer(r"```python\n(.*?)```", text, re.DOTALL):
            before = text[max(0, block.start() - 400) : block.start()]
            for name in re.findall(r"^\s*(?:import|from)\s+(\w+)", block.group(1), re.MULTILINE):
                known = name in INSTALLED_IMPORTS or name in sys.stdlib_module_names
                if not known and f"pip install {name}" not in before:
                    missing.append(f"{path.name}: {name}")
    assert missing == []
