"""The command line: errors end in one line and an exit code, never a traceback."""

from __future__ import annotations

import subprocess
import sys

import pytest

import roadgaze.evaluation.paper
from roadgaze.cli import main
from roadgaze.errors import ConfigError


def test_user_errors_print_one_line_and_exit_2(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def broken() -> None:
        raise ConfigError("geometry.beta: must be > 1 (found 0.5)")

    monkeypatch.setattr(roadgaze.evaluation.paper, "experiment_1", broken)
    assert main(["paper-tables"]) == 2
    err = capsys.readouterr().err
    assert err == "roadgaze paper-tables: error: geometry.beta: must be > 1 (found 0.5)\n"


@pytest.mark.parametrize(
    ("typed", "line"),
    [
        ("replya", "unknown command 'replya'; did you mean replay? roadgaze --help lists them"),
        ("evaluate", "unknown command 'evaluate'; did you mean eval? roadgaze --help lists them"),
        ("paper", "unknown command 'paper'; did you mean paper-tables?"),
        ("no-such-command", "unknown command 'no-such-command'; roadgaze --help lists them"),
    ],
)
def test_an_unknown_command_is_one_line_with_the_nearest_names_and_exit_2(
    typed: str, line: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([typed, "--help"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("roadgaze: error: ") and line in err and err.count("\n") == 1


def test_the_help_says_what_the_tool_is(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "driver monitoring for forward-collision warning" in text
    assert "head-yaw" not in text


def test_module_entry_point_prints_help_quickly(subprocess_env: dict[str, str]) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "roadgaze", "--help"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
        env=subprocess_env,
    )
    assert result.returncode == 0
    assert "paper-tables" in result.stdout
    # --help must not import the heavy stages.
    probe = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys, roadgaze.cli as c; c.build_parser(); "
            "print(sorted(m for m in ('mediapipe', 'zenoh', 'matplotlib') if m in sys.modules))",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
        env=subprocess_env,
    )
    assert probe.stdout.strip() == "[]"
